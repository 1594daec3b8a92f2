"""Speed against error per view band, and the storage each material needs (issue 10).

Two tables:

1. **Per band** — for each (environment, BRDF) of the hard set (microfacet σ 0.05/0.1/0.3,
   Phong s 32/1000, GGX α 0.1/0.3, Cook–Torrance Beckmann α = 0.092 f0 = 0.1; Grace 64 rows
   ``--env-up y --env-flip``, a one-pixel sun 1e5× the sky at 128 rows, ``venice_sunset`` 64
   rows): ``prefilter`` at ε = 0.03 with the default rule (``bands``, view limit 80°, auto
   window), its time and SHRM size, and per θ_v band the predicted and bounded relative RMS
   (``SHRM.meta["view_bands"]``) beside the relative RMS measured against brute-force angular
   integration (``analysis.reference``) on pairs drawn per band with importance sampling of
   the map's bright pixels and stratification (``analysis.compare.band_sample``), ± its standard
   error (``band_error``, which matches the spread over seeds).
2. **Storage** — orders (F, P) and the SHRM bytes of a 256 MiB-budget map under the bands
   rule and under RH02's rule (``--criterion rh02``) for Cook–Torrance/GGX materials and a
   MERL table written from a GGX model (the table that needed F = 63, P = 16, 266 MB under
   RH02's rule).

Shared data are read from ``../shared/data`` (never copied into the repository).

Run:  .venv/bin/python benchmarks/view_bands.py [--quick] [--per-band N] [--only-storage]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from rich.console import Console
from rich.table import Table

from shrmkit.analysis.compare import band_error, band_sample
from shrmkit.analysis.orders import choose_orders
from shrmkit.analysis.reference import reference_radiance
from shrmkit.analysis.shrm import default_size, prefilter
from shrmkit.analysis.view_bands import DEFAULT_BAND_EDGES_DEG
from shrmkit.brdf_io.envmap import load_env
from shrmkit.brdf_io.merl import write_merl
from shrmkit.brdf_io.specs import load_brdf

__all__ = ["main"]

DATA = Path(__file__).resolve().parents[2] / "shared" / "data"
EPS = 0.03
BRDFS = ["microfacet:sigma=0.05", "microfacet:sigma=0.1", "microfacet:sigma=0.3", "phong:s=32", "phong:s=1000",
         "cook-torrance:alpha=0.1,dist=ggx", "cook-torrance:alpha=0.3,dist=ggx", "cook-torrance:alpha=0.092,f0=0.1"]
STORAGE = ["cook-torrance:alpha=0.05,f0=0.04", "cook-torrance:alpha=0.092,f0=0.1", "cook-torrance:alpha=0.2,f0=0.9",
           "cook-torrance:alpha=0.05,f0=0.9,dist=ggx", "cook-torrance:alpha=0.1,f0=0.04,dist=ggx",
           "cook-torrance:alpha=0.3,f0=0.04,dist=ggx", "cook-torrance:alpha=0.5,f0=0.04,dist=ggx"]
MERL_SPEC = "cook-torrance:kd=0.2/0.1/0.05,ks=1,alpha=0.3,f0=0.9/0.6/0.3,dist=ggx"

console = Console(width=220, highlight=False)


def environments(quick: bool) -> dict:
    envs = {"sun": lambda: load_env("builtin:sun,height=128,elevation=35,azimuth=20")}
    if (DATA / "env" / "grace_latlong.exr").is_file():
        envs["grace"] = lambda: load_env(DATA / "env" / "grace_latlong.exr", up="y", flip=True, height=64)
    if not quick and (DATA / "env" / "polyhaven_cc0" / "venice_sunset_1k.hdr").is_file():
        envs["venice"] = lambda: load_env(DATA / "env" / "polyhaven_cc0" / "venice_sunset_1k.hdr", up="y", height=64)
    return envs


def band_table(quick: bool, per_band: int) -> None:
    table = Table(title=f"per view band at eps = {EPS:g} (rule: bands to 80°; measured ± s.e., brute force)")
    for name in ("env", "BRDF", "F_B", "P_B", "map", "MB", "prefilter s", "window"):
        table.add_column(name, justify="right")
    for lo, hi in zip(DEFAULT_BAND_EDGES_DEG[:-1], DEFAULT_BAND_EDGES_DEG[1:], strict=True):
        table.add_column(f"{lo:g}-{hi:g}°\npred/bound\nmeasured", justify="right")
    brdfs = BRDFS[::2] if quick else BRDFS
    for env_name, make in environments(quick).items():
        env = make()
        pairs = band_sample(env.radiance, per_band, DEFAULT_BAND_EDGES_DEG, seed=11)
        for spec in brdfs:
            brdf = load_brdf(spec)
            t0 = time.perf_counter()
            shrm = prefilter(env, brdf, eps=EPS)
            seconds = time.perf_counter() - t0
            ref = reference_radiance(env, brdf, pairs.R, pairs.V)
            measured = band_error(shrm.radiance(pairs.R, pairs.V), ref, pairs)
            cells = []
            for band, m in zip(shrm.meta["view_bands"], measured, strict=True):
                mark = "" if band["inside"] else "*"
                cells.append(f"{band['predicted_rel_rms']:.3f}/{band['bound_rel_rms']:.3f}{mark}\n"
                             f"{m['measured_rel_rms']:.3f}±{m['stderr']:.3f}")
            window = "none" if shrm.meta["window"] == "none" else f"L{shrm.meta['window_strength']:.2f}"
            table.add_row(env_name, spec.replace("cook-torrance:", "ct:"), str(shrm.F), str(shrm.P),
                          f"{shrm.height}x{shrm.width}", f"{shrm.coeffs.nbytes / 1e6:.0f}", f"{seconds:.1f}", window,
                          *cells)
            console.print(f"done {env_name} {spec}", style="dim")
    console.print(table)
    console.print("* beyond the view limit: stated, not promised. Relative RMS over uniform R and θ_v uniform in the"
                  " band; the measured value is a Monte Carlo estimate (± one standard error).")


def storage_bytes(F: int, P: int) -> int:
    S = default_size(F, P)
    return (P + 1) ** 2 * S * 2 * S * 3 * 4


def storage_table() -> None:
    table = Table(title=f"orders and SHRM storage at eps = {EPS:g} (default caps F <= 512, P <= 20; "
                        "256 MiB map budget)")
    for name in ("BRDF", "bands F", "P", "eps", "capped", "s", "MB", "rh02 F", "P ", "eps ", "capped ", "s ", "MB "):
        table.add_column(name, justify="right")
    with tempfile.TemporaryDirectory() as tmp:
        merl = write_merl(Path(tmp) / "ggx.binary", load_brdf(MERL_SPEC))
        for spec in STORAGE + [str(merl)]:
            brdf = load_brdf(spec)
            row = [f"MERL table of {MERL_SPEC}" if spec == str(merl) else spec]
            for criterion in ("bands", "rh02"):
                t0 = time.perf_counter()
                o = choose_orders(brdf, eps=EPS, criterion=criterion)
                row += [str(o.F), str(o.P), f"{o.eps:.4f}", str(o.capped), f"{time.perf_counter() - t0:.1f}",
                        f"{storage_bytes(o.F, o.P) / 2**20:.0f}"]
            table.add_row(*row)
            console.print(f"done {row[0]}", style="dim")
    console.print(table)
    console.print("MB: the float32 global SHRM, (P+1)² RGB maps of S × 2S with S = min(10F, the 256 MiB budget's "
                  "size) (analysis.shrm.default_size): above the budget the map shrinks and the per-band statement "
                  "counts the coarser lookup.")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="half the BRDFs, no venice_sunset")
    parser.add_argument("--per-band", type=int, default=400, help="brute-force pairs per view band (default 400)")
    parser.add_argument("--only-storage", action="store_true")
    args = parser.parse_args()
    if not args.only_storage:
        band_table(args.quick, args.per_band)
    storage_table()


if __name__ == "__main__":
    main()
