"""``shrm compare``: the SHRM [RH02] against Kautz–McCool [KM00], RSIBR [Cabral99] and Gaussian
lobes [Green07], the published methods of ``analysis.baselines.methods`` under their keys there.

Prints one table (rich on stdout, or one JSON object with ``--json``): for each
representation the relative RMS radiance error against the angular reference on sampled
(R, V) pairs (all, grazing, frontal), storage, precompute seconds and per-frame update
seconds. ``--strip out.png`` also writes the side-by-side image strip (reference, each
representation, difference images not amplified) from the representations the comparison
built, and adds its description as the ``strip`` entry. ``--markdown FILE`` writes the
table as a Markdown section for reports. Exit 0, or 2 on bad input.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from rich.progress import Progress, SpinnerColumn, TextColumn, TimeElapsedColumn
from rich.table import Table

from ..analysis.compare import CompareOptions, compare_representations
from ..analysis.order_rule import OrderRule
from ..brdf_io.atomic import atomic_path, check_writable
from ..brdf_io.errors import BadInputError
from ..render.mesh import load_mesh
from ..render.strip import write_comparison_strip
from .common import (
    load_analysis_brdf,
    load_env_arg,
    print_json,
    print_table,
    progress_shown,
    stderr,
    stdout,
)
from .view_bands_table import print_view_bands


def _lobes(text: str) -> tuple[int, ...]:
    """Parse ``--lobes`` (the range is checked by :class:`CompareOptions`)."""
    if text.strip().lower() in ("none", ""):
        return ()
    try:
        return tuple(int(t) for t in text.split(","))
    except ValueError:
        raise BadInputError(None, f"--lobes must be integers separated by commas, got {text!r}") from None


def _options(args: argparse.Namespace) -> CompareOptions:
    return CompareOptions(
        rule=OrderRule(eps=args.eps, criterion=args.criterion, max_view_deg=args.max_view_deg),
        env_height=args.env_height, n_pairs=args.pairs, sample_max_view_deg=args.max_view, seed=args.seed,
        lower_P=args.lower_p, lobes=_lobes(args.lobes), elevations=args.elevations,
        rsibr_reference_height=args.rsibr_reference_height or None, window=args.window, lights=args.lights,
    )


def _note_dropped_lower_p(args: argparse.Namespace, result: dict) -> None:
    """``--lower-p N`` not below the SHRM's P gives no lower-order row (the library omits it,
    so the table and the JSON stay as documented): say why on stderr, one line."""
    keys = [r["key"] for r in result["rows"]]
    if args.lower_p is None or "shrm_low_p" in keys or "shrm" not in keys:
        return
    P = result["rows"][keys.index("shrm")]["params"]["P"]
    hint = f"use --lower-p {P - 1} or less" if P > 0 else "P = 0 has no lower order"
    stderr.print(f"shrm compare: note: no lower-order SHRM row: --lower-p {args.lower_p} is not below the "
                 f"SHRM's P = {P} (chosen for eps {result['eps']:g}); {hint}",
                 markup=False, highlight=False, soft_wrap=True)


def run(args: argparse.Namespace) -> int:
    for note in getattr(args, "deprecation_notes", None) or []:
        stderr.print(f"shrm compare: note: {note}", markup=False, highlight=False, soft_wrap=True)
    options = _options(args)
    if args.strip and Path(args.strip).suffix.lower() != ".png":
        raise BadInputError(args.strip, "--strip must name a .png file")
    mesh = load_mesh(args.mesh) if args.mesh else None
    _, brdf, choice = load_analysis_brdf(args.brdf, args, quiet=args.json)  # scattered data: its representation
    for path in (args.strip, args.markdown):
        if path:
            check_writable(path)
    env = load_env_arg(args.env, args)
    with Progress(SpinnerColumn(), TextColumn("{task.description}"), TimeElapsedColumn(), console=stderr,
                  disable=not progress_shown(args)) as bar:
        task = bar.add_task("comparing", total=None)

        def progress(stage: str) -> None:
            bar.update(task, description=f"comparing: {stage}")

        comparison = compare_representations(brdf, env, options, progress=progress)
        result = comparison.result
        if args.strip:
            progress("image strip")
            result = write_comparison_strip(comparison, args.strip, size=args.strip_size, mesh=mesh)
    _note_dropped_lower_p(args, result)
    if args.markdown:
        with atomic_path(args.markdown) as tmp:
            Path(tmp).write_text(result["markdown"], encoding="utf-8")
    if args.json:
        print_json({"representation": None if choice is None else choice.as_dict(), **result})
        return 0
    if choice is not None:
        stdout.print(choice.line(), markup=False, soft_wrap=True)
    table = Table(title=f"{result['brdf']} under {result['environment']}, eps {result['eps']:g}, "
                        f"window {result['window']}, {result['n_pairs']} pairs "
                        f"(reference {result['reference']['seconds']:.2f} s)")
    for key in ("representation", "rel RMS", "grazing >70°", "<45°", "storage MB", "precompute s", "update ms",
                "eval µs"):
        table.add_column(key, justify="left" if key == "representation" else "right")
    for r in result["rows"]:
        table.add_row(
            r["label"], f"{r['rel_rms']:.4f}", f"{r['rel_rms_grazing']:.4f}", f"{r['rel_rms_frontal']:.4f}",
            f"{r['storage_bytes'] / 1e6:.3f}", f"{r['precompute_s']:.3f}", f"{1e3 * r['update_s']:.3f}",
            f"{r['eval_us_per_pair']:.1f}",
        )
    print_table(table)
    shrm_row = next((r for r in result["rows"] if r.get("view_bands") and "predicted_rel_rms" in r["view_bands"][0]),
                    None)
    if shrm_row is not None:
        print_view_bands(shrm_row["view_bands"], f"{shrm_row['label']} by view band (rule {result['criterion']})",
                         measured=True)
    if "strip" in result:
        stdout.print(f"wrote {result['strip']['path']}")
    if args.markdown:
        stdout.print(f"wrote {args.markdown}")
    return 0
