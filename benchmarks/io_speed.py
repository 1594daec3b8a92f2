"""Speed of the brdf_io readers, writers and table lookups (measured, never asserted in tests).

The unit tests check what these functions compute; how fast they run depends on the
machine and its load, so it is measured here instead. For each case: the work done, the
best and the median wall time over ``--repeats`` runs (``time.perf_counter``), a rate, and
the budget the case was once held to in the unit tests (a loaded 2-core machine can miss
it; compare within one run).

Cases:

- MerlBRDF.eval at 10⁶ random direction pairs (upper hemisphere), random table values
  (budget 4 s; data_specs/merl_binary.md quotes about 0.8 s);
- TableBRDF.eval at 10⁶ pairs on a 46 × 46 × 91 RGB table;
- write_merl and read_merl of a full 90 × 90 × 180 file (35 MB) in a temporary folder;
- write_hdr / read_hdr (run-length encoded) and write_exr / read_exr of a 512 × 1024 map;
- real files from ../shared/data/env when present: load_env of grace_latlong.exr with
  flip=True, up="y" (budget 1 s), read_image of polyhaven_cc0/venice_sunset_1k.hdr
  (budget 1 s), load_env of the 256² debevec1999 Grace cube to 512 × 1024.

Run:  .venv/bin/python benchmarks/io_speed.py [--quick] [--repeats N]
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
from rich.console import Console
from rich.table import Table

from shrmkit.brdf_io.envmap import load_env
from shrmkit.brdf_io.hdr_codecs import read_exr, read_hdr, read_image, write_exr, write_hdr
from shrmkit.brdf_io.merl import MERL_DIMS, MerlBRDF, read_merl, write_merl
from shrmkit.brdf_io.table import TableBRDF

__all__ = ["main"]

ENV = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "env"

console = Console(width=160, highlight=False)


def hemisphere(rng: np.random.Generator, n: int) -> np.ndarray:
    """n directions uniform on the upper hemisphere, (n, 3)."""
    cos_t = rng.uniform(0.0, 1.0, n)
    phi = rng.uniform(-np.pi, np.pi, n)
    sin_t = np.sqrt(1.0 - cos_t**2)
    return np.stack((sin_t * np.cos(phi), sin_t * np.sin(phi), cos_t), axis=-1)


def timed(run: Callable[[], object], repeats: int) -> tuple[float, float]:
    """(best, median) wall time of ``run()`` in seconds over ``repeats`` calls."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        run()
        times.append(time.perf_counter() - start)
    return min(times), statistics.median(times)


def cases(quick: bool, folder: Path) -> list[tuple[str, str, Callable[[], object], float, str, float | None]]:
    """(name, work, run, amount, unit of the rate, budget in s or None)."""
    rng = np.random.default_rng(14)
    n = 200_000 if quick else 1_000_000
    L, V = hemisphere(rng, n), hemisphere(rng, n)
    merl_brdf = MerlBRDF(rng.uniform(size=(3, *MERL_DIMS)), name="random")
    grid = (np.linspace(0, np.pi / 2, 46), np.linspace(0, np.pi / 2, 46), np.linspace(0, np.pi, 91))
    table = TableBRDF(*grid, rng.uniform(size=(46, 46, 91, 3)), name="random")
    merl_path = folder / "random.binary"
    write_merl(merl_path, merl_brdf.values)
    image = rng.uniform(0.0, 4.0, size=(512, 1024, 3)).astype(np.float32)
    image[:, :512] = 0.5  # long runs for the RLE encoder
    hdr_path, exr_path = folder / "map.hdr", folder / "map.exr"
    write_hdr(hdr_path, image)
    write_exr(exr_path, image)
    out: list[tuple[str, str, Callable[[], object], float, str, float | None]] = [
        ("MerlBRDF.eval", f"{n:,} pairs", lambda: merl_brdf.eval(L, V), n, "pairs/s", 4.0 * n / 1e6),
        ("TableBRDF.eval", f"{n:,} pairs, 46x46x91", lambda: table.eval(L, V), n, "pairs/s", None),
        ("write_merl", "90x90x180, 35 MB", lambda: write_merl(merl_path, merl_brdf.values), 35e6, "B/s", None),
        ("read_merl", "90x90x180, 35 MB", lambda: read_merl(merl_path), 35e6, "B/s", None),
        ("write_hdr (RLE)", "512x1024", lambda: write_hdr(hdr_path, image), image[..., 0].size, "px/s", None),
        ("read_hdr (RLE)", "512x1024", lambda: read_hdr(hdr_path), image[..., 0].size, "px/s", None),
        ("write_exr (float)", "512x1024", lambda: write_exr(exr_path, image), image[..., 0].size, "px/s", None),
        ("read_exr", "512x1024", lambda: read_exr(exr_path), image[..., 0].size, "px/s", None),
    ]
    grace, venice, cube = ENV / "grace_latlong.exr", ENV / "polyhaven_cc0" / "venice_sunset_1k.hdr", None
    if (ENV / "debevec1999_cubes" / "grace").is_dir():
        cube = ENV / "debevec1999_cubes" / "grace"
    if grace.is_file():
        out.append(("load_env grace_latlong.exr", "flip, up=y, 512x1024",
                    lambda: load_env(grace, flip=True, up="y"), 512 * 1024, "px/s", 1.0))
    if venice.is_file():
        out.append(("read_image venice_sunset_1k.hdr", "RLE 512x1024", lambda: read_image(venice),
                    512 * 1024, "px/s", 1.0))
    if cube is not None and not quick:
        out.append(("load_env grace cube", "6x256^2 -> 512x1024", lambda: load_env(cube), 512 * 1024, "px/s", None))
    if not (grace.is_file() and venice.is_file()):
        console.print(f"[shared data not found under {ENV}: real-file cases skipped]")
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="2e5 lookups, no cube-map case")
    parser.add_argument("--repeats", type=int, default=3, help="runs per case (default 3)")
    args = parser.parse_args(argv)
    if args.repeats < 1:
        parser.error("--repeats must be at least 1")
    table = Table(title="brdf_io speed (wall time, best and median of repeats)")
    for column in ("case", "work", "best s", "median s", "rate", "old test budget s", "within"):
        table.add_column(column, justify="left" if column in ("case", "work") else "right")
    with tempfile.TemporaryDirectory() as tmp:
        for name, work, run, amount, unit, budget in cases(args.quick, Path(tmp)):
            best, median = timed(run, args.repeats)
            within = "" if budget is None else ("yes" if best <= budget else "NO")
            table.add_row(
                name, work, f"{best:.3f}", f"{median:.3f}", f"{amount / best:.3g} {unit}",
                "" if budget is None else f"{budget:g}", within,
            )
    console.print(table)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
