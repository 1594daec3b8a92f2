"""Fit speed and error: round trips through MERL-resolution tables and the Cornell data.

Usage::

    .venv/bin/python benchmarks/fit_speed.py [--quick] [--no-cornell]

Runs on one core (BLAS threads pinned to 1 before numpy loads). Prints three tables:
1. round trips — known models tabulated at MERL resolution (90·90·180), written and read
   back as .binary, then fitted: time, evaluations, relative RMS, worst parameter error;
2. Cornell — each of the five measured materials fitted with Lafortune 1–3 lobes and
   Cook–Torrance: time and errors;
3. Cornell per view-elevation band (Green et al. 2007, Fig. 4 style): rel_rms per band.
Target: a 2-lobe Lafortune or a Cook–Torrance fit of a MERL table in <= 10 s.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
from rich.console import Console  # noqa: E402
from rich.table import Table  # noqa: E402

from shrmkit.analysis.fit import fit_brdf  # noqa: E402
from shrmkit.brdf_io.models import CookTorrance, Lafortune, LafortuneLobe, rgb  # noqa: E402

SHARED = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "brdf"


def lafortune(kd, lobes) -> Lafortune:
    return Lafortune(
        kd=rgb(kd),
        lobes=tuple(LafortuneLobe(cxy=rgb(a), cz=rgb(b), n=rgb(n), ks=rgb(k)) for a, b, n, k in lobes),
    )


def truth_params(truth) -> dict[str, float]:
    if isinstance(truth, CookTorrance):
        out = {"alpha": truth.alpha}
        for key in ("kd", "ks", "f0"):
            out.update({f"{key}{c}": getattr(truth, key)[c] for c in range(3)})
        return out
    out = {f"kd{c}": truth.kd[c] for c in range(3)}
    for k, lobe in enumerate(truth.lobes):
        out.update({f"l{k}{key}": float(getattr(lobe, key)[0]) for key in ("cxy", "cz", "n")})
        out.update({f"l{k}ks{c}": lobe.ks[c] for c in range(3)})
    return out


def fitted_params(params: dict) -> dict[str, float]:
    if "alpha" in params:
        out = {"alpha": params["alpha"]}
        for key in ("kd", "ks", "f0"):
            out.update({f"{key}{c}": params[key][c] for c in range(3)})
        return out
    out = {f"kd{c}": params["kd"][c] for c in range(3)}
    for k, lobe in enumerate(params["lobes"]):
        out.update({f"l{k}{key}": lobe[key] for key in ("cxy", "cz", "n")})
        out.update({f"l{k}ks{c}": lobe["ks"][c] for c in range(3)})
    return out


def roundtrip_cases():
    cases = [
        ("Lafortune 1 lobe", lafortune((0.3, 0.2, 0.1), [(-1.0, 0.95, 60.0, (0.5, 0.6, 0.7))]),
         {"model": "lafortune", "lobes": 1}),
        ("Lafortune 2 lobes", lafortune((0.2, 0.25, 0.3), [(-1.0, 0.98, 120.0, (0.9, 0.8, 0.7)),
                                                           (0.8, 1.0, 4.0, (0.05, 0.1, 0.1))]),
         {"model": "lafortune", "lobes": 2}),
        ("Cook-Torrance Beckmann", CookTorrance(kd=rgb((0.3, 0.2, 0.1)), ks=rgb((0.3, 0.4, 0.5)), alpha=0.15,
                                                f0=rgb((0.05, 0.5, 0.9))), {"model": "cook-torrance"}),
        ("Cook-Torrance GGX", CookTorrance(kd=rgb((0.1, 0.2, 0.3)), ks=rgb((0.5, 0.4, 0.3)), alpha=0.08,
                                           f0=rgb((0.9, 0.6, 0.04)), distribution="ggx"),
         {"model": "cook-torrance", "distribution": "ggx"}),
        ("Ngan05 brass (n=10700)", lafortune((0.0387, 0.0273, 0.0123), [
            (-1.0, 1.0, 10700.0, tuple(np.array([0.118, 0.0479, 0.0172]) * 10702 / (2 * np.pi)))]),
         {"model": "lafortune", "lobes": 1}),
    ]
    return cases


def run_roundtrips(console: Console, quick: bool) -> None:
    from shrmkit.brdf_io.merl import read_merl, tabulate_merl, write_merl

    table = Table(title="round trips through MERL .binary (90x90x180), one core")
    for col in ("case", "noise", "fit s", "evals", "samples", "rel_rms", "max param err", "status"):
        table.add_column(col, justify="right")
    with tempfile.TemporaryDirectory() as tmp:
        for name, truth, kw in roundtrip_cases()[: 3 if quick else None]:
            values = tabulate_merl(truth)
            for noise in (False, True):
                v = values
                if noise:
                    rng = np.random.default_rng(2024)
                    v = values * (1.0 + 0.02 * rng.standard_normal(values.shape))
                    v[:, rng.random(values.shape[1:]) < 0.1] = np.nan
                    v = np.maximum(v, 0.0)
                path = Path(tmp) / "case.binary"
                write_merl(path, v)
                brdf = read_merl(path)
                r = fit_brdf(brdf, **kw)
                ref, got = truth_params(truth), fitted_params(r.params)
                err = max(abs(got[k] - ref[k]) / max(abs(ref[k]), 1e-12) for k in ref)
                table.add_row(name, "2% + 10% missing" if noise else "none", f"{r.seconds:.2f}",
                              str(r.evaluations), str(r.n_samples), f"{r.errors['rel_rms']:.2e}",
                              f"{100 * err:.3f}%", r.status)
    console.print(table)


def run_cornell(console: Console, quick: bool) -> None:
    from shrmkit.analysis.fit.sampling import collect_samples
    from shrmkit.brdf_io.cornell import read_cornell

    files = sorted((SHARED / "cornell").glob("*.brdf"))
    if not files:
        console.print(f"no Cornell data under {SHARED / 'cornell'}: skipped")
        return
    models = [("Lafortune 1", {"model": "lafortune", "lobes": 1}),
              ("Lafortune 2", {"model": "lafortune", "lobes": 2}),
              ("Lafortune 3", {"model": "lafortune", "lobes": 3}),
              ("Cook-Torrance", {"model": "cook-torrance"})]
    if quick:
        models = models[:2] + models[3:]
    summary = Table(title="Cornell measured BRDFs (1439 samples each, θ <= 80°, metric rel)")
    for col in ("material", "model", "s", "rel_rms", "log_rms", "status"):
        summary.add_column(col, justify="right")
    bands_table = Table(title="Cornell: rel_rms per view-elevation band θ_o (deg)")
    results = []
    for path in files:
        brdf = read_cornell(path)
        samples = collect_samples(brdf)
        for label, kw in models:
            t = time.perf_counter()
            r = fit_brdf(brdf, samples=samples, **kw)
            summary.add_row(brdf.name, label, f"{time.perf_counter() - t:.2f}", f"{r.errors['rel_rms']:.4f}",
                            f"{r.errors['log_rms']:.4f}", r.status)
            results.append((brdf.name, label, r))
    edges = [(b.lo_deg, b.hi_deg) for b in results[0][2].bands]
    for col in ("material", "model", *[f"{lo:g}–{hi:g}" for lo, hi in edges]):
        bands_table.add_column(col, justify="right")
    for name, label, r in results:
        by_edge = {(b.lo_deg, b.hi_deg): b for b in r.bands}
        bands_table.add_row(name, label, *[
            f"{by_edge[e].rel_rms:.3f}" if e in by_edge else "-" for e in edges])
    console.print(summary)
    console.print(bands_table)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer cases")
    parser.add_argument("--no-cornell", action="store_true", help="skip the Cornell data")
    parser.add_argument("--no-roundtrip", action="store_true", help="skip the MERL round trips")
    args = parser.parse_args(argv)
    console = Console(width=140)
    if not args.no_roundtrip:
        run_roundtrips(console, args.quick)
    if not args.no_cornell:
        run_cornell(console, args.quick)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
