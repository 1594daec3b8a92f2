"""CPU cost of ``RGLBRDF.eval`` per point on the RGL files of ../shared/data (measured, never asserted).

For each RGL file (``../shared/data/brdf/rgl/*.bsdf``) and each table direction (``view``, the
default, and ``light``): the CPU time (``time.process_time``: user + system, so page faults count)
per point of ``eval`` at ``--points`` random direction pairs (about 5 % of each direction below
the surface, lengths 0.5-2: the normalization and the horizon test are exercised), the best of
``--repeats`` runs. Then the workloads that call it in a report: the order choice's reparameterized
grid (``sample_rho_hat_grid`` on ``ReparamGrid.for_orders(100, 40)``, 224 x 96 x 176 nodes, half of
them evaluated), the brute-force reference's pattern (3000 map directions against each of 40
fixed views), ``eval`` called on 100 pairs at a time (the fixed cost of a call) and
``halfdiff_to_directions`` on the GL preview table's slices (90 x 90 x 180).

``--against DIR``: also time the ``shrmkit`` checkout in DIR (e.g. ``git worktree add /tmp/old
HEAD~3``), interleaved with this one in the same process (old, new, old, new, ...), and print the
ratio of the best times and the largest relative difference of the values (``bit-identical`` when
equal bit for bit). Each checkout runs the workloads with its own ``sample_rho_hat_grid`` and
``halfdiff_to_directions``. One untimed call of each first (the allocator's first page faults
are not counted).

Run:  .venv/bin/python benchmarks/rgl_eval_speed.py [--points N] [--repeats N] [--against DIR] [--quick]
"""

from __future__ import annotations

import argparse
import importlib
import sys
import tempfile
import time
import warnings
from collections.abc import Callable
from pathlib import Path
from types import ModuleType

import numpy as np
from rich.console import Console
from rich.table import Table

from shrmkit.brdf_io import halfdiff, reparam, rgl
from shrmkit.brdf_io.reparam import ReparamGrid

__all__ = ["main"]

RGL = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "brdf" / "rgl"

console = Console(width=160, highlight=False)


def pairs(rng: np.random.Generator, n: int) -> tuple[np.ndarray, np.ndarray]:
    """n random (L, V) pairs (n, 3): cos θ uniform in [−0.05, 1], lengths uniform in [0.5, 2]."""

    def directions() -> np.ndarray:
        c = rng.uniform(-0.05, 1.0, n)
        p = rng.uniform(-np.pi, np.pi, n)
        s = np.sqrt(1.0 - c * c)
        return np.stack((s * np.cos(p), s * np.sin(p), c), axis=-1) * rng.uniform(0.5, 2.0, (n, 1))

    return directions(), directions()


def against(folder: str) -> ModuleType:
    """The package ``shrmkit`` of the checkout ``folder``, imported under another name."""
    link = Path(tempfile.mkdtemp(prefix="rgl_eval_speed_")) / "shrmkit_against"
    link.symlink_to(Path(folder).resolve())
    sys.path.append(str(link.parent))
    return importlib.import_module("shrmkit_against")


def best_of(runs: dict[str, Callable[[], np.ndarray]], repeats: int) -> dict[str, tuple[float, np.ndarray]]:
    """Per name: the best CPU time of ``repeats`` calls (interleaved across names) and the last value."""
    best = dict.fromkeys(runs, np.inf)
    values = {name: run() for name, run in runs.items()}  # a first call untimed: allocator and caches warm
    for _ in range(repeats):
        for name, run in runs.items():
            start = time.process_time()
            values[name] = run()
            best[name] = min(best[name], time.process_time() - start)
    return {name: (best[name], values[name]) for name in runs}


def difference(a: np.ndarray, b: np.ndarray) -> str:
    """Largest |a − b| / |a| (where a ≠ 0), or 'bit-identical' (the same bytes: −0.0 ≠ 0.0)."""
    if a.shape == b.shape and a.dtype == b.dtype and a.tobytes() == b.tobytes():
        return "bit-identical"
    nonzero = a != 0
    rel = np.abs(a - b)[nonzero] / np.abs(a[nonzero])
    return f"{float(np.max(rel, initial=0.0)):.1e} (zeros {int(np.count_nonzero(b[~nonzero]))})"


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--points", type=int, default=65536)
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--against", metavar="DIR", help="an older shrmkit checkout to compare with")
    parser.add_argument("--quick", action="store_true", help="one file, 3 repeats")
    args = parser.parse_args(argv)
    if args.points < 100 or args.repeats < 1:
        parser.error("--points must be at least 100 and --repeats at least 1")
    warnings.filterwarnings("ignore", message=".*RGB values are negative")  # either checkout's warning class
    files = sorted(RGL.glob("*.bsdf"))[: 1 if args.quick else None]
    repeats = 3 if args.quick else args.repeats
    if not files:
        console.print(f"no RGL files in {RGL}")
        return
    old = against(args.against) if args.against else None
    old_rgl = importlib.import_module(old.__name__ + ".brdf_io.rgl") if old else None
    old_halfdiff = importlib.import_module(old.__name__ + ".brdf_io.halfdiff") if old else None
    old_reparam = importlib.import_module(old.__name__ + ".brdf_io.reparam") if old else None
    L, V = pairs(np.random.default_rng(1), args.points)

    table = Table(title=f"RGLBRDF.eval, {args.points} random pairs: CPU per point (best of {repeats})")
    for column in ("file", "ω_i", "ns/point", "points/s") + (("against", "ratio", "max rel. diff"),)[0] * bool(old):
        table.add_column(column, justify="left" if column in ("file", "ω_i") else "right")
    for path in files:
        for direction in ("view", "light"):
            brdfs = {"new": rgl.read_rgl(path, table_direction=direction)}
            if old_rgl is not None:
                brdfs["old"] = old_rgl.read_rgl(path, table_direction=direction)
            result = best_of({k: (lambda b=b: b.eval(L, V)) for k, b in brdfs.items()}, repeats)
            new_t, new_v = result["new"]
            row = [path.stem, direction, f"{new_t / args.points * 1e9:.0f}", f"{args.points / new_t:.3g}"]
            if "old" in result:
                old_t, old_v = result["old"]
                row += [f"{old_t / args.points * 1e9:.0f}", f"{old_t / new_t:.2f}", difference(old_v, new_v)]
            table.add_row(*row)
    console.print(table)

    path = next((p for p in files if "iris" in p.name), files[0])
    grid = ReparamGrid.for_orders(100, 40)
    xi, xo = grid.theta_i()[0], grid.theta_o()[0]
    rng = np.random.default_rng(0)
    map_dirs = rng.normal(size=(3000, 3))
    map_dirs /= np.linalg.norm(map_dirs, axis=1)[:, None]
    views = rng.normal(size=(40, 3))
    views[:, 2] = np.abs(views[:, 2])
    views /= np.linalg.norm(views, axis=1)[:, None]
    th = (np.arange(90) / 89.0) ** 2 * (np.pi / 2)
    td, pd = np.linspace(0.0, np.pi / 2, 90)[:, None], np.linspace(0.0, np.pi, 180)[None, :]

    def workloads(brdf: rgl.RGLBRDF, hd: ModuleType, rp: ModuleType) -> dict[str, Callable[[], np.ndarray]]:
        return {
            "order choice's reparam grid (224x96x176)": lambda: rp.sample_rho_hat_grid(brdf, xi, xo, grid.n_phi)[0],
            "reference pattern (3000 dirs x 40 views)": lambda: np.stack(
                [brdf.eval(map_dirs, np.broadcast_to(v, map_dirs.shape)) for v in views]),
            "eval of 100 pairs, 200 calls (fixed cost)": lambda: np.stack(
                [brdf.eval(L[k : k + 100], V[k : k + 100]) for k in range(0, min(20000, L.shape[0] - 99), 100)]),
            "halfdiff_to_directions (90 slices 90x180)": lambda: np.stack(
                [np.stack(hd.halfdiff_to_directions(t, td, pd)) for t in th]),
        }

    table = Table(title=f"workloads on {path.stem}: CPU s (best of {repeats})")
    for column in ("workload", "s") + (("against", "ratio", "max rel. diff"),)[0] * bool(old):
        table.add_column(column, justify="left" if column == "workload" else "right")
    new_work = workloads(rgl.read_rgl(path), halfdiff, reparam)
    old_work = {}
    if old_rgl is not None and old_halfdiff is not None and old_reparam is not None:
        old_work = workloads(old_rgl.read_rgl(path), old_halfdiff, old_reparam)
    for name, run in new_work.items():
        result = best_of({"new": run, **({"old": old_work[name]} if old_work else {})}, repeats)
        row = [name, f"{result['new'][0]:.3f}"]
        if "old" in result:
            row += [f"{result['old'][0]:.3f}", f"{result['old'][0] / result['new'][0]:.2f}",
                    difference(result["old"][1], result["new"][1])]
        table.add_row(*row)
    console.print(table)


if __name__ == "__main__":
    main()
