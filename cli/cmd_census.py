"""``shrm census``: a BRDF library tabulated as [RH02] Fig. 8 does, with the orders, fits and reasons.

For every material of the arguments (files, folders of BRDF files, whole multi-BRDF files such as
CURET's ``abrdf.dat``: ``analysis.census.census_sources``) one row (``analysis.census``): the
accuracy 1 − ε(F, p) for p = 0…P ([RH02]'s energy over all views and the worst view band), the
orders needed at ``--eps``, the representation analysed and its held-out worst view band, the
anisotropy, and the reason for every miss or failure. Written to ``--out``: ``census.csv``,
``census.json`` (``data_specs/census_json.md``) and ``census.png`` (accuracy against P per
material, [RH02] Fig. 8's layout; matplotlib, 100 dpi). The last line counts the materials above
the threshold at (F, P), with the fit settings. ``--workers N`` computes the rows in N spawned
processes (the same numbers as one); progress goes to stderr (a live bar on a terminal, else one
line per row).

Exit status: 0 when every row was analysed, 1 when some could not be (each is a failed row, with
its error, in the table and the files), 2 for bad usage (unknown options, bad values, a named
file that does not exist, an output folder that cannot be written: nothing is written).

Reference: [RH02] Fig. 8 (``data_specs/bibliography.md``).
"""

from __future__ import annotations

import argparse
import csv
import functools
import json
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn
from rich.table import Table

if TYPE_CHECKING:
    from rich.console import JustifyMethod

from ..analysis.census import (
    CSV_COLUMNS,
    Census,
    CensusRow,
    census_sources,
    run_census,
)
from ..analysis.order_rule import OrderRule
from ..brdf_io.atomic import atomic_paths, check_writable
from ..brdf_io.brdf import BRDF
from ..brdf_io.errors import BadInputError
from ..brdf_io.jsonutil import to_jsonable
from ..brdf_io.specs import BRDF_FILE_TYPES, load_brdf
from .common import (
    order_rule,
    print_json,
    print_table,
    progress_shown,
    rgl_brdf_arg,
    say,
    stderr,
    stdout,
)
from .options_census import CSV_NAME, JSON_NAME, PLOT_NAME

__all__ = ["load_census_brdf", "run", "plot_census", "write_census"]


def _check_sources(sources: list[str]) -> None:
    """A BRDF named by a file path that does not exist is a usage error (exit 2, nothing written);
    a file that exists but cannot be read is one failed row."""
    for source in sources:
        base, sep, _ = source.rpartition("#")
        path = Path(base if sep and Path(base).suffix.lower() in BRDF_FILE_TYPES else source)
        if path.suffix.lower() in BRDF_FILE_TYPES and not path.exists():
            raise BadInputError(path, "no such BRDF file")
        if not path.suffix and not path.exists() and ":" not in source and ("/" in source or "\\" in source):
            raise BadInputError(path, "no such file or folder")


def load_census_brdf(source: str, rgl_incident: str = "camera") -> BRDF:
    """``load_brdf`` with ``--rgl-incident`` attached to an RGL file that names no incident
    direction (``rgl_brdf_arg``); module-level, so that census worker processes can receive it."""
    return load_brdf(rgl_brdf_arg(source, argparse.Namespace(rgl_incident=rgl_incident)))


def run(args: argparse.Namespace) -> int:
    _check_sources(args.brdfs)
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise BadInputError(out, "is a file, not an output folder")
    sources = census_sources(args.brdfs)
    if not sources:
        raise BadInputError(", ".join(args.brdfs), "no BRDF files found (suffixes " + ", ".join(BRDF_FILE_TYPES) + ")")
    check_writable(out / CSV_NAME)  # before the long work (creates the folder)
    show = progress_shown(args)
    columns = (TextColumn("[bold]census"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
               TextColumn("{task.fields[last]}"))
    with Progress(*columns, console=stderr, transient=True, disable=not show) as bar:
        task = bar.add_task("census", total=len(sources), last="")

        def progress(done: int, total: int, row: CensusRow) -> None:
            bar.update(task, completed=done, last=f"{row.name or row.source}: {row.status}")
            if show and not stderr.is_terminal:  # a log, not a live bar: one line per row
                stderr.print(f"census {done}/{total}: {row.name or row.source}: {row.status} ({row.seconds:.1f} s)",
                             markup=False, highlight=False, soft_wrap=True)

        census = run_census(
            sources, F=args.F, P=args.P, threshold=args.threshold, candidates=args.candidates,
            rule=OrderRule(eps=args.eps, max_F=args.max_F, max_P=args.max_P, **order_rule(args)),
            folds=args.folds, seed=args.seed, max_theta_deg=args.max_theta,
            load=functools.partial(load_census_brdf, rgl_incident=args.rgl_incident), progress=progress,
            workers=args.workers,
        )
    files = write_census(census, out, plot=not args.no_plot)
    if args.json:
        print_json(census_doc(census, files))
        return 0 if census.n_failed == 0 else 1
    print_census(census)
    say(f"written: {', '.join(str(p) for p in files.values())}")
    say(f"census: {census.count_line()} ({census.seconds:.1f} s)")
    return 0 if census.n_failed == 0 else 1


def write_census(census: Census, out: Path, *, plot: bool = True) -> dict[str, Path]:
    """Write ``census.csv``, ``census.json`` and (with ``plot``) ``census.png`` into ``out``,
    all together or none (``atomic_paths``); returns ``{"csv": path, "json": path[, "plot": path]}``.

    Raises
    ------
    BadInputError
        The folder cannot be written (nothing is then changed).
    """
    out.mkdir(parents=True, exist_ok=True)
    files = {"csv": out / CSV_NAME, "json": out / JSON_NAME} | ({"plot": out / PLOT_NAME} if plot else {})
    with atomic_paths(list(files.values())) as temps:
        tmp = dict(zip(files, temps, strict=True))
        rows = census.csv_rows()
        fields = list(rows[0]) if rows else list(CSV_COLUMNS)
        with open(tmp["csv"], "w", newline="", encoding="utf-8") as f:
            writer = csv.DictWriter(f, fieldnames=fields)
            writer.writeheader()
            writer.writerows(rows)
        tmp["json"].write_text(json.dumps(to_jsonable(census.as_dict()), indent=1) + "\n", encoding="utf-8")
        if plot:
            plot_census(census, tmp["plot"])
    return files


def plot_census(census: Census, path: Path, title: str | None = None) -> None:
    """RH02 Fig. 8's layout: 1 − ε(F, p) per material for each p = 0…P, the materials sorted by
    their accuracy at P, with the threshold; left RH02's criterion (energy over all views),
    right the worst view band. Failed rows are left out. PNG at 100 dpi (matplotlib's object API on
    the Agg canvas, as the report's plots)."""
    ok = [r for r in census.rows if r.ok]
    fig = Figure(figsize=(12, 4.5))  # the object API and the Agg canvas: no display, no pyplot state
    FigureCanvasAgg(fig)
    axes = fig.subplots(1, 2, sharey=True)
    panels = (("accuracy_rh02", "RH02's criterion: energy over all views", "rh02"),
              ("accuracy_bands", f"worst view band to {census.max_view_deg:g}° (point light)", "bands"))
    for ax, (key, label, criterion) in zip(axes, panels, strict=True):
        table = np.array([getattr(r, key) for r in ok]).reshape(len(ok), census.P + 1)
        order = np.argsort(-table[:, census.P], kind="stable")
        x = np.arange(1, len(ok) + 1)
        for p in range(census.P + 1):
            ax.plot(x, table[order, p], marker="o", markersize=2.5, linewidth=1, label=f"P = {p}")
        ax.axhline(census.threshold, color="k", linestyle="--", linewidth=0.8)
        ax.set_xlabel(f"materials, sorted by accuracy at P = {census.P}")
        ax.set_title(f"{label}\n{census.count_above(criterion)} of {len(census.rows)} above "
                     f"{census.threshold:.0%} at F = {census.F}, P = {census.P}", fontsize=9)
        ax.set_ylim(0.0, 1.0)
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
        ax.grid(alpha=0.3)
    axes[0].set_ylabel(f"accuracy 1 − ε(F = {census.F}, P)")
    axes[0].legend(loc="lower center", ncol=3, fontsize=8)
    fig.suptitle(title or f"census of {len(census.rows)} materials (RH02 Fig. 8 layout)", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=100, format="png")


def _fit_cell(row: CensusRow) -> str:
    if row.fit_worst is None:
        return "" if row.fit_ok is None else "n/a"
    w = row.fit_worst
    return f"{w['rel_rms']:.2g} {w['lo_deg']:g}–{w['hi_deg']:g}°" + ("" if row.fit_ok else " FAILED")


def _model_cell(row: CensusRow) -> str:
    """``"zernike 6"`` (its order), ``"cook-torrance"``, or ``"as given"``."""
    if row.model == "zernike" and row.representation_record is not None:
        return f"zernike {row.representation_record['label'].split()[2]}"
    return row.model or row.representation


def print_census(census: Census) -> None:
    """The census table on stdout: one row per material (the reasons spelt out below it)."""
    P = census.P
    table = Table(title=f"census: accuracy 1 − ε(F = {census.F}, P), RH02's energy over all views and the worst "
                  f"view band; orders needed at ε = {census.eps:g} ({census.criterion} rule)")
    columns: tuple[tuple[str, JustifyMethod], ...] = (
        ("material", "left"), ("analysed as", "left"), ("fit: worst band", "right"), (f"RH02 %, P = 0…{P}", "left"),
        (f"band P={P}", "right"), ("F, P needed", "right"), ("aniso.", "right"), ("reasons", "left"))
    for key, justify in columns:
        table.add_column(key, justify=justify)
    for r in census.rows:
        if not r.ok:
            table.add_row(r.name or Path(r.source).name, "[red]failed[/red]", "", "", "", "", "", ", ".join(r.reasons))
            continue
        acc = " ".join(f"{100 * v:.0f}" for v in r.accuracy_rh02)
        needed = f"{r.F_needed}, {r.P_needed}" + (" capped" if r.capped else "")
        aniso = "" if r.anisotropy is None else f"{r.anisotropy:.1g}" + (" A" if r.anisotropic else "")
        table.add_row(r.name, _model_cell(r), _fit_cell(r), acc, f"{r.accuracy('bands'):.2f}", needed, aniso,
                      ", ".join(r.reasons))
    print_table(table)
    for r in census.rows:
        if r.reason_text:
            stdout.print(f"{r.name or r.source}: {r.reason_text}", markup=False, soft_wrap=True, highlight=False)


def census_doc(census: Census, files: dict[str, Path]) -> dict[str, Any]:
    """The ``--json`` object: census.json's with the files written."""
    return census.as_dict() | {"files": {k: str(v) for k, v in files.items()}}
