"""``shrm compare``: the SHRM against Kautz–McCool, Cabral et al. and Green et al. (issue 7).

Prints one table (rich on stdout, or one JSON object with ``--json``): for each
representation the relative RMS radiance error against the angular reference on sampled
(R, V) pairs (all, grazing, frontal), storage, precompute seconds and per-frame update
seconds. ``--strip out.png`` also writes the side-by-side image strip (reference, each
representation, difference images not amplified). ``--markdown FILE`` writes the table as a
Markdown section for reports. Exit 0, or 2 on bad input.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from rich.progress import Progress, SpinnerColumn, TextColumn, TimeElapsedColumn
from rich.table import Table

from ..brdf_io.atomic import check_writable
from ..brdf_io.errors import BadInputError
from .common import add_env_orientation, load_env_arg, number_in, print_json, stderr, stdout, tolerance

HELP = "compare the SHRM with Kautz-McCool, Cabral (12 maps) and Gaussian-lobe representations"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("brdf", metavar="BRDF", help="BRDF file (.binary, .npz, .json) or spec string")
    parser.add_argument("--env", required=True, help="environment map spec or file")
    add_env_orientation(parser)
    parser.add_argument("--env-height", type=number_in(8, 512, integer=True), default=64,
                        help="resample the environment to this many rows (default 64; the reference is O(W S_L^2))")
    parser.add_argument("--mesh", help="mesh for the image strip (default: a sphere); brute-force ray casting, "
                        "keep it small")
    parser.add_argument("--eps", type=tolerance, default=0.03, help="SHRM tolerance (default 0.03)")
    parser.add_argument("--pairs", type=number_in(10, 10**6, integer=True), default=2000,
                        help="sampled (R, V) pairs (default 2000)")
    parser.add_argument("--max-view", type=number_in(1.0, 90.0, hi_open=True), default=88.0,
                        help="largest view angle from the normal, degrees (default 88)")
    parser.add_argument("--lower-p", type=number_in(0, 64, integer=True), help="P of the lower-order SHRM "
                        "(default P-2)")
    parser.add_argument("--lobes", default="1,2,3,4", help="Gaussian-lobe counts K, comma separated "
                        "(default 1,2,3,4; 'none' skips)")
    parser.add_argument("--elevations", type=number_in(2, 64, integer=True), default=15,
                        help="view elevations of the Gaussian-lobe fits (default 15)")
    parser.add_argument("--cabral-reference-height", type=number_in(0, 256, integer=True), default=16,
                        help="rows of Cabral's maps by the angular reference (default 16; 0 skips)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--json", action="store_true", help="print one JSON object instead of the table")
    parser.add_argument("--strip", help="write the image strip to this PNG")
    parser.add_argument("--strip-size", type=number_in(16, 1024, integer=True), default=64,
                        help="strip panel size in pixels (default 64)")
    parser.add_argument("--markdown", help="write the table as Markdown to this file")


def _lobes(text: str) -> tuple[int, ...]:
    if text.strip().lower() in ("none", ""):
        return ()
    try:
        ks = tuple(int(t) for t in text.split(","))
    except ValueError:
        raise BadInputError(None, f"--lobes must be integers separated by commas, got {text!r}") from None
    if any(not 1 <= k <= 8 for k in ks):
        raise BadInputError(None, f"--lobes values must be in [1, 8], got {text!r}")
    return ks


def run(args: argparse.Namespace) -> int:
    from ..analysis.compare import compare
    from ..brdf_io.specs import load_brdf

    lobes = _lobes(args.lobes)
    if args.strip and Path(args.strip).suffix.lower() != ".png":
        raise BadInputError(args.strip, "--strip must name a .png file")
    mesh = None
    if args.mesh:
        from ..render.mesh import load_mesh

        mesh = load_mesh(args.mesh)
    brdf = load_brdf(args.brdf)
    for path in (args.strip, args.markdown):
        if path:
            check_writable(path)
    env = load_env_arg(args.env, args)
    with Progress(SpinnerColumn(), TextColumn("{task.description}"), TimeElapsedColumn(), console=stderr,
                  disable=args.json) as bar:
        task = bar.add_task("comparing", total=None)
        result = compare(
            brdf, env, eps=args.eps, env_height=args.env_height, n_pairs=args.pairs, max_view_deg=args.max_view,
            seed=args.seed, lower_P=args.lower_p, lobes=lobes, n_elevations=args.elevations,
            cabral_reference_height=args.cabral_reference_height or None, strip=args.strip,
            strip_size=args.strip_size, mesh=mesh,
            progress=lambda stage: bar.update(task, description=f"comparing: {stage}"),
        )
    if args.markdown:
        from ..brdf_io.atomic import atomic_path

        with atomic_path(args.markdown) as tmp:
            Path(tmp).write_text(result["markdown"], encoding="utf-8")
    if args.json:
        print_json(result)
        return 0
    table = Table(title=f"{result['brdf']} under {result['environment']}, eps {result['eps']:g}, "
                        f"{result['n_pairs']} pairs (reference {result['reference']['seconds']:.2f} s)")
    for key in ("representation", "rel RMS", "grazing >70°", "<45°", "storage MB", "precompute s", "update ms",
                "eval µs"):
        table.add_column(key, justify="left" if key == "representation" else "right")
    for r in result["rows"]:
        table.add_row(
            r["label"], f"{r['rel_rms']:.4f}", f"{r['rel_rms_grazing']:.4f}", f"{r['rel_rms_frontal']:.4f}",
            f"{r['storage_bytes'] / 1e6:.3f}", f"{r['precompute_s']:.3f}", f"{1e3 * r['update_s']:.3f}",
            f"{r['eval_us_per_pair']:.1f}",
        )
    stdout.print(table)
    if "strip" in result:
        stdout.print(f"wrote {result['strip']['path']}")
    if args.markdown:
        stdout.print(f"wrote {args.markdown}")
    return 0
