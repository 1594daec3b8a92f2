"""Seed-to-seed spread of the per-band measured error against its stated standard error (issue 29).

For each BRDF: one SHRM (``prefilter`` at ε, default rule), then for each of ``--seeds`` seeds
the per-band relative RMS against the brute-force angular reference (``analysis.reference``)
on the pairs of one estimator:

- ``old``: :func:`~shrmkit.analysis.compare.band_pairs` (caps about the 16 brightest pixels,
  i.i.d.) and :func:`~shrmkit.analysis.compare.band_relative_rms` — the report's before issue 29;
- ``new``: :func:`~shrmkit.analysis.compare.band_sample` (pixel density, stratified) and
  :func:`~shrmkit.analysis.compare.band_error` — the report's, ``shrm compare``'s and the
  benchmarks' estimator now;
- ``grid``: the first issue-29 estimator: the density's block means on their fixed grid only
  (``neighbours=False``, before a block took the largest mean of its neighbours) and the plain
  delta-method s.e. (``studentized=False``, before the t factor √(ν/(ν − 2)));
- ``iid``: the new density without stratification (i.i.d. standard error).

Several estimators in one run (``--estimator grid new``) share the SHRMs and the seeds.

Per band it prints the mean estimate over seeds, the spread (std over seeds, ddof = 1), the mean
stated standard error and their ratio (≈ 1 when the stated s.e. is honest; the ratio of 8 seeds is
itself uncertain by ≈ 25 %).

Shared data are read from ``../shared/data`` (never copied into the repository).

Run:  .venv/bin/python benchmarks/band_error_spread.py --estimator grid new --height 512 --per-band 60 [--jobs 8]
"""

from __future__ import annotations

import argparse
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

from shrmkit.analysis.compare import band_error, band_pairs, band_relative_rms, band_sample
from shrmkit.analysis.reference import reference_radiance
from shrmkit.analysis.shrm import prefilter
from shrmkit.analysis.view_bands import DEFAULT_BAND_EDGES_DEG
from shrmkit.brdf_io.envmap import load_env
from shrmkit.brdf_io.specs import load_brdf

__all__ = ["main", "measure"]

DATA = Path(__file__).resolve().parents[2] / "shared" / "data"
GRACE = DATA / "env" / "grace_latlong.exr"
EDGES = DEFAULT_BAND_EDGES_DEG
_STATE: dict = {}


def measure(estimator: str, seed: int, per_band: int) -> list[dict]:
    """One seed's per-band records (``measured_rel_rms``, ``stderr``) for the SHRM in ``_STATE``."""
    env, brdf, shrm = _STATE["env"], _STATE["brdf"], _STATE["shrm"]
    if estimator == "old":
        R, V, theta, w = band_pairs(env.radiance, per_band, EDGES, seed=seed)
        return band_relative_rms(shrm.radiance(R, V), reference_radiance(env, brdf, R, V), theta, EDGES, w)
    stratified = estimator != "iid"
    sample = band_sample(env.radiance, per_band, EDGES, seed=seed, stratified=stratified,
                         neighbours=estimator != "grid")
    ref = reference_radiance(env, brdf, sample.R, sample.V)
    return band_error(shrm.radiance(sample.R, sample.V), ref, sample, stratified=stratified,
                      studentized=estimator != "grid")


def _one(args: tuple[str, int, int]) -> list[dict]:
    return measure(*args)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--estimator", nargs="+", choices=("old", "grid", "new", "iid"), default=["new"])
    parser.add_argument("--env", default=str(GRACE), help="environment file (y-up, flipped like Grace)")
    parser.add_argument("--height", type=int, default=512, help="environment rows (512: Grace at full resolution)")
    parser.add_argument("--brdf", action="append", help="BRDF spec (repeatable)")
    parser.add_argument("--eps", type=float, default=0.03)
    parser.add_argument("--seeds", type=int, default=8)
    parser.add_argument("--per-band", type=int, default=60)
    parser.add_argument("--jobs", type=int, default=1, help="worker processes (one seed each)")
    args = parser.parse_args(argv)
    env = load_env(args.env, up="y", flip=True, height=args.height)
    for spec in args.brdf or ["microfacet:sigma=0.05", "cook-torrance:alpha=0.1,dist=ggx",
                              "cook-torrance:alpha=0.3,dist=ggx", "phong:s=512"]:
        brdf = load_brdf(spec)
        shrm = prefilter(env, brdf, eps=args.eps)
        _STATE.update(env=env, brdf=brdf, shrm=shrm)  # inherited by forked workers
        for estimator in args.estimator:
            _run(args, spec, env, shrm, estimator)


def _run(args: argparse.Namespace, spec: str, env, shrm, estimator: str) -> None:
    t0 = time.perf_counter()
    jobs = [(estimator, seed, args.per_band) for seed in range(args.seeds)]
    if args.jobs > 1:
        with ProcessPoolExecutor(args.jobs) as pool:
            runs = list(pool.map(_one, jobs))
    else:
        runs = [_one(job) for job in jobs]
    seconds = time.perf_counter() - t0
    print(f"\n{spec} on {Path(args.env).name} {env.height}x{env.width}, eps {args.eps:g}: F_B {shrm.F}, P_B "
          f"{shrm.P}; estimator {estimator}, {args.per_band} pairs per band, {args.seeds} seeds, {seconds:.0f} s")
    print(f"{'band':>8} {'mean':>8} {'min':>8} {'max':>8} {'spread':>8} {'s.e.':>8} {'ratio':>6}")
    ratios = []
    for k, (lo, hi) in enumerate(zip(EDGES[:-1], EDGES[1:], strict=True)):
        m = np.array([run[k]["measured_rel_rms"] for run in runs])
        se = np.array([run[k]["stderr"] for run in runs])
        spread = float(np.std(m, ddof=1))
        ratios.append(spread / se.mean())
        print(f"{lo:>3g}-{hi:<4g} {m.mean():8.4f} {m.min():8.4f} {m.max():8.4f} {spread:8.4f} {se.mean():8.4f} "
              f"{spread / se.mean():6.2f}")
    print(f"spread/s.e. per band: {' '.join(f'{r:.2f}' for r in ratios)}; max {max(ratios):.2f}, "
          f"root mean square {np.sqrt(np.mean(np.square(ratios))):.2f}")

if __name__ == "__main__":
    main()
