"""RH02 Fig. 8 on CURET: accuracy 1 − ε(F = 30, P), P = 0…5, of the 61 CURET BRDFs.

Each CURET sample (``brdf/curet/{abrdf.dat,table.txt}`` of ../shared/data, read with
``shrmkit.brdf_io.curet.read_curet_all``: 205 grey measurements, negatives clamped to 0) is
fitted with Koenderink's reciprocal isotropic Zernike expansion
(``shrmkit.analysis.fit.zernike.fit_zernike``; default 55 coefficients = order 8, plain least
squares on ρ, CURET's published fit), and the fit is analysed like any BRDF:
``orders_on_grid_for(fit, F=30, P=5)`` gives, on one quadrature grid sized for (30, 5),

- RH02's unweighted table ε(F, P) (criterion ``"rh02"``, the energy over all views; RH02 §5.1),
- the default ``"bands"`` table (worst θ_v band inside 80° under a point light).

Prints one row per sample (fit error, fraction of direction pairs where the polynomial fit is
negative, 1 − ε(30, P) for P = 0…5 under both criteria), the count of BRDFs above 90 % per P
for both criteria, the run time, and as its last line

    CURET: N of 61 BRDFs above 90 % accuracy at F = 30, P = 5 (RH02: 56 of 61)

It plots the accuracies like RH02 Fig. 8 (one curve per P over the BRDFs, sorted by their
accuracy at P = 5; left RH02's criterion, right the bands criterion) to ``--out`` (default
``<tempdir>/fig8_curet.png``; never into the repository).

Options: ``--n-coeffs`` (5, 14, 30, 55, ...; default 55), ``--ridge`` (Tikhonov damping of the
fit, relative; default 0), ``--metric`` (``rho`` or ``rel``), ``--data``, ``--out``.

Run:  .venv/bin/python benchmarks/fig8_curet.py [--n-coeffs 55] [--ridge 0] [--out /tmp/fig8.png]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from shrmkit.analysis.fit.zernike import fit_zernike  # noqa: E402
from shrmkit.analysis.orders import orders_on_grid_for  # noqa: E402
from shrmkit.brdf_io.curet import CURET_SAMPLE_NAMES, read_curet_all  # noqa: E402

__all__ = ["main"]

CURET = Path("/work/shared/data/brdf/curet")
F = 30
P_MAX = 5
THRESHOLD = 0.9
RH02_COUNT = 56


def plot(acc: np.ndarray, acc_bands: np.ndarray, out: Path, title: str) -> None:
    """Accuracy curves per P over the BRDFs sorted by accuracy at P = 5 (RH02 Fig. 8 layout)."""
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.5), sharey=True)
    for ax, table, label in ((axes[0], acc, "RH02 criterion (energy over all views)"),
                             (axes[1], acc_bands, "bands criterion (worst θ_v band ≤ 80°)")):
        order = np.argsort(-table[:, P_MAX], kind="stable")
        x = np.arange(1, len(order) + 1)
        for p in range(P_MAX + 1):
            ax.plot(x, table[order, p], marker="o", markersize=2.5, linewidth=1, label=f"P = {p}")
        ax.axhline(THRESHOLD, color="k", linestyle="--", linewidth=0.8)
        ax.set_xlabel("CURET BRDFs, sorted by accuracy at P = 5")
        ax.set_title(f"{label}\n{int(np.sum(table[:, P_MAX] > THRESHOLD))} of {len(table)} above 90 % at P = 5",
                     fontsize=9)
        ax.set_ylim(0.0, 1.0)
        ax.grid(alpha=0.3)
    axes[0].set_ylabel(f"accuracy 1 − ε(F = {F}, P)")
    axes[0].legend(loc="lower center", ncol=3, fontsize=8)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path, default=CURET, help=f"CURET folder (default {CURET})")
    parser.add_argument("--out", type=Path, default=Path(tempfile.gettempdir()) / "fig8_curet.png",
                        help="PNG to write (default <tempdir>/fig8_curet.png)")
    parser.add_argument("--n-coeffs", type=int, default=55, help="Zernike coefficients per fit (default 55 = order 8)")
    parser.add_argument("--ridge", type=float, default=0.0, help="relative Tikhonov damping of the fit (default 0)")
    parser.add_argument("--metric", choices=("rho", "rel"), default="rho", help="fit objective (default rho)")
    args = parser.parse_args(argv)
    if not args.data.is_dir():
        print(f"{args.data}: CURET data folder not found (only in the project workspace); nothing to do")
        return 1
    t_start = time.perf_counter()
    brdfs = read_curet_all(args.data)
    rows = []
    for brdf in brdfs:
        sample = int(brdf.source.rsplit("#", 1)[1])
        fit = fit_zernike(brdf, n_coeffs=args.n_coeffs, ridge=args.ridge, metric=args.metric)
        choice = orders_on_grid_for(fit.brdf, F, P_MAX, criterion="bands")
        rows.append((sample, fit, 1.0 - choice.rh02_table[F, : P_MAX + 1], 1.0 - choice.table[F, : P_MAX + 1],
                     fit.brdf.negative_fraction(), brdf.n_clipped // 3))
    elapsed = time.perf_counter() - t_start
    acc = np.array([r[2] for r in rows])
    acc_bands = np.array([r[3] for r in rows])

    print(f"CURET Zernike fits: {args.n_coeffs} coefficients, metric {args.metric}, ridge {args.ridge:g}; "
          f"accuracy 1 − ε(F = {F}, P) on a ReparamGrid.for_orders({F}, {P_MAX})")
    header = " ".join(f"P={p:<4d}" for p in range(P_MAX + 1))
    print(f"{'#':>2} {'name':<22} {'relRMS':>6} {'neg%':>5} {'clamp':>5} | rh02: {header} | bands: {header}")
    for sample, fit, a, b, neg, clamped in rows:
        print(f"{sample:2d} {CURET_SAMPLE_NAMES.get(sample, ''):<22.22} {fit.rel_rms_rho:6.3f} {100 * neg:5.1f} "
              f"{clamped:5d} |       " + " ".join(f"{v:6.3f}" for v in a) + " |        "
              + " ".join(f"{v:6.3f}" for v in b))
    n = len(rows)
    median_rms = float(np.median([r[1].rel_rms_rho for r in rows]))
    median_neg = 100 * float(np.median([r[4] for r in rows]))
    print(f"\nmedian relative RMS of the fits over the measurements: {median_rms:.3f}; "
          f"median fraction of direction pairs where a fit is negative: {median_neg:.1f} %")
    for label, table in (("rh02 ", acc), ("bands", acc_bands)):
        counts = ", ".join(f"P={p}: {int(np.sum(table[:, p] > THRESHOLD))}" for p in range(P_MAX + 1))
        print(f"{label} criterion, BRDFs above 90 % at F = {F}: {counts} (of {n})")
    n_bands = int(np.sum(acc_bands[:, P_MAX] > THRESHOLD))
    print(f"bands criterion: {n_bands} of {n} BRDFs above 90 % accuracy at F = {F}, P = {P_MAX}")
    args.out.parent.mkdir(parents=True, exist_ok=True)
    damping = f", ridge {args.ridge:g}" if args.ridge else ""
    plot(acc, acc_bands, args.out, f"CURET, Zernike fits ({args.n_coeffs} coefficients{damping}): RH02 Fig. 8 analog")
    print(f"plot: {args.out}")
    print(f"time: {elapsed:.1f} s for {n} fits and tables ({time.perf_counter() - t_start:.1f} s with the plot)")
    n_rh02 = int(np.sum(acc[:, P_MAX] > THRESHOLD))
    print(f"CURET: {n_rh02} of {n} BRDFs above 90 % accuracy at F = {F}, P = {P_MAX} (RH02: {RH02_COUNT} of 61)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
