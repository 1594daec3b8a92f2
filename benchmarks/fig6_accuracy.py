"""Accuracy of the reflected light field against the order F (RH02 Fig. 6 analog).

Grace Cathedral (``grace_latlong.exr``, flip=True, area-resampled to 256 rows; falls back to
``builtin:sky`` if the shared file is absent) and a Phong lobe s = 32, P = 0. For F = 0..20:

- ε_B(F): the relative energy error of truncating B to l <= F, computed against a high-order
  expansion (lighting coefficients to lmax = 100, ρ̂ coefficients to F0 = 100) with
  ``analysis.scene.reflected_error``;
- the min-of-errors estimate min(ε_L(F), ε_ρ(F)) (RH02 §5.1) and the conservative residual
  bound (``analysis.scene.residual_bound``);
- at a few F, the measured relative RMS error of ``prefilter(..., F=F, P=0)``'s radiance
  against the angular-domain reference on random (R, V) pairs. ε_B is an energy fraction, so
  the radiance RMS it predicts for uniformly distributed R is √ε_B.

Run:  .venv/bin/python benchmarks/fig6_accuracy.py [--quick]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
from rich.console import Console
from rich.table import Table

from shrmkit.analysis.brdf_coeffs import rho_lpq
from shrmkit.analysis.compare import relative_rms, sample_pairs
from shrmkit.analysis.lighting import lighting_coefficients
from shrmkit.analysis.orders import eps_table
from shrmkit.analysis.reference import reference_radiance
from shrmkit.analysis.scene import reflected_error, residual_bound
from shrmkit.analysis.shrm import prefilter
from shrmkit.brdf_io.envmap import EnvironmentMap, load_env
from shrmkit.brdf_io.reparam import ReparamGrid, reparameterize
from shrmkit.brdf_io.specs import load_brdf

__all__ = ["main"]

GRACE = Path("/work/shared/data/env/grace_latlong.exr")
MAX_THETA_V = np.radians(80.0)

console = Console(width=200, highlight=False)


def fmt(x: float) -> str:
    """4 decimals, or 3 significant digits below 1e-3."""
    return f"{x:.4f}" if x >= 1e-3 or x == 0 else f"{x:.2e}"


def environment(height: int) -> EnvironmentMap:
    if GRACE.is_file():
        # the pbrt-v2 copy is stored bottom row first: flip=True puts the windows on top (+z)
        return load_env(GRACE, flip=True, height=height)
    console.print(f"{GRACE} not found: falling back to builtin:sky")
    return load_env(f"builtin:sky,height={height}")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="fewer measured F values and pairs (< 1 min)")
    parser.add_argument("--s", type=float, default=32.0, help="Phong exponent (default 32)")
    parser.add_argument("--env-height", type=int, default=256)
    parser.add_argument("--lmax", type=int, default=100, help="order of the high-order expansion (default 100)")
    parser.add_argument("--max-F", type=int, default=20)
    parser.add_argument("--seed", type=int, default=6)
    args = parser.parse_args(argv)
    t_start = time.perf_counter()
    env = environment(args.env_height)
    brdf = load_brdf(f"phong:s={args.s:g}")
    lmax = min(args.lmax, env.height - 1)

    t0 = time.perf_counter()
    lighting = lighting_coefficients(env.radiance, lmax, name=env.name)
    # ρ̂_lpq to F0 = lmax on a grid that integrates those orders exactly; P0 = 4 so that any
    # energy at p > 0 (none for this radially symmetric lobe) would count as error at P = 0
    P0 = 4
    reparam = reparameterize(brdf, ReparamGrid.for_orders(lmax, P0))
    coefficients = rho_lpq(reparam, lmax, P0)
    t_coeffs = time.perf_counter() - t0
    eps_L = lighting.eps()
    eps_rho = eps_table(coefficients)[:, 0]

    measured_F = [1, 4, 10] if args.quick else [1, 2, 4, 6, 8, 10, 14, 20]
    n_pairs = 150 if args.quick else 300
    R, V = sample_pairs(n_pairs, seed=args.seed, max_view_deg=80.0)[:2]
    t0 = time.perf_counter()
    ref = reference_radiance(env, brdf, R, V)
    t_ref = time.perf_counter() - t0
    measured: dict[int, tuple[float, int, float]] = {}
    for F in measured_F:
        if F > args.max_F:
            continue
        shrm = prefilter(env, brdf, F=F, P=0, window="none")  # the truncation alone, as ε_B(F)
        measured[F] = (relative_rms(shrm.radiance(R, V, clamp=False), ref), shrm.height, shrm.eps["reflected"])

    table = Table(
        title=f"RH02 Fig. 6 analog: {env.name} {env.height}×{env.width}, {brdf.name}, P = 0; "
        f"high-order expansion lmax = F0 = {lmax}; measured on {n_pairs} random (R, V) pairs",
        box=None,
    )
    for col in (
        "F",
        "ε_L(F)",
        "ε_ρ(F)",
        "min(ε_L, ε_ρ)",
        "ε_B(F)",
        "1 − ε_B",
        "bound",
        "bound >= ε_B",
        "√ε_B",
        "rel RMS measured",
        "S (SHRM rows)",
        "prefilter's ε_B",
    ):
        table.add_column(col, justify="right")
    for F in range(args.max_F + 1):
        e_b = reflected_error(lighting, coefficients, F, 0)
        bound = residual_bound(lighting, coefficients, F, 0)
        m = measured.get(F)
        table.add_row(
            str(F),
            fmt(eps_L[F]),
            fmt(eps_rho[F]),
            fmt(min(eps_L[F], eps_rho[F])),
            fmt(e_b),
            f"{1 - e_b:.4f}",
            fmt(bound),
            "yes" if bound >= e_b else "NO",
            fmt(np.sqrt(e_b)),
            fmt(m[0]) if m else "",
            str(m[1]) if m else "",
            fmt(m[2]) if m else "",
        )
    console.print(table)
    console.print(
        f"coefficients (lighting SHT + ρ̂_lpq to {lmax}): {t_coeffs:.2f} s; angular reference on {n_pairs} pairs: "
        f"{t_ref:.2f} s; total {time.perf_counter() - t_start:.1f} s"
    )
    console.print(
        "prefilter's ε_B: the same quantity computed inside prefilter() from its own, lower-order expansions"
        " (l <= max(2F_ρ, F_ρ+16)); it can read lower than the high-order ε_B(F)."
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
