"""``shrm bench``: run the speed-against-error benchmarks in one process and print their tables.

The benchmark scripts live in the source tree's ``benchmarks/`` folder (they are not part
of the installed package): ``prefilter_speed.py`` (shrmkit's prefiltering, order choice
included, against the best angular methods — RH02 Table 4's lobe-truncated sum and the
engines' split sum — each time beside its measured error and the stated one, and the current
targets of issue 22 marked met / NO with what explains a NO; RH02 = Ramamoorthi & Hanrahan
2002, doi:10.1145/566654.566611), ``fit_speed.py`` (fit times and errors) and
``render_speed.py`` (frames per second; needs an offscreen OpenGL context and is skipped
without one). Each is loaded from its file and its ``main`` called with ``--quick`` when
asked; a benchmark that fails is reported and the others still run (exit status 1 if any
failed). A missing folder, or a folder without the scripts of the chosen benchmarks, is a
usage error: one line naming the folder and the missing scripts, exit status 2, nothing run.
"""

from __future__ import annotations

import argparse
import importlib.util
import sys
import time
from pathlib import Path

from ..brdf_io.errors import BadInputError
from ..render.offscreen import probe_offscreen
from .common import say

HELP = ("run the speed-against-error benchmarks (prefilter vs the best angular methods, with targets; fits; "
        "render fps) and print tables")

BENCHMARKS = {
    "prefilter": ("prefilter_speed.py", "prefiltering vs lobe-truncated sum and split sum, errors beside times, "
                  "targets"),
    "fit": ("fit_speed.py", "fit times and errors"),
    "render": ("render_speed.py", "SHRM shader frames per second"),
}


def _default_folder() -> Path:
    """``benchmarks/`` next to the package's top folder (the source checkout)."""
    return Path(__file__).resolve().parents[1] / "benchmarks"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--quick", action="store_true", help="the benchmarks' quick variants (about a minute each)")
    p.add_argument("--only", choices=tuple(BENCHMARKS), nargs="+", default=None, help="run only these benchmarks")
    p.add_argument("--benchmarks", default=None, metavar="DIR",
                   help="folder of the benchmark scripts (default: benchmarks/ of the source checkout)")


def _load(path: Path):
    spec = importlib.util.spec_from_file_location(f"shrm_bench_{path.stem}", path)
    module = importlib.util.module_from_spec(spec)
    # registered before it runs, as an import would be: dataclasses (and pickling) look the
    # module up in sys.modules while its classes are being defined
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


def run_benchmark(path: Path, quick: bool) -> None:
    """Load a benchmark script and call its ``main`` (with ``--quick`` if asked)."""
    args = ["--quick"] if quick else []
    module = _load(path)
    main = getattr(module, "main", None)
    if main is None:
        raise RuntimeError(f"{path.name} has no main() entry point")
    rc = main(args)
    if isinstance(rc, int) and rc != 0:
        raise RuntimeError(f"{path.name} exited with status {rc}")


def run(args: argparse.Namespace) -> int:
    folder = Path(args.benchmarks) if args.benchmarks else _default_folder()
    if not folder.is_dir():
        raise BadInputError(folder, "no benchmarks folder (shrm bench needs a source checkout; pass --benchmarks DIR)")
    names = args.only or list(BENCHMARKS)
    missing = [BENCHMARKS[name][0] for name in names if not (folder / BENCHMARKS[name][0]).is_file()]
    if missing:  # checked before any benchmark runs: a wrong folder is a usage error
        raise BadInputError(folder, f"benchmark script{'s' if len(missing) > 1 else ''} missing: {', '.join(missing)} "
                            "(pass --benchmarks DIR holding them, or --only the ones present)")
    results = []
    for name in names:
        file, what = BENCHMARKS[name]
        path = folder / file
        say(f"\n=== {name}: {what} ({path}){' --quick' if args.quick else ''}")
        if name == "render":
            ok, message = probe_offscreen(timeout=60.0)
            if not ok:
                results.append((name, "skipped", 0.0, f"no offscreen OpenGL: {message}"))
                say(f"skipped: no offscreen OpenGL context ({message})")
                continue
        t0 = time.perf_counter()
        try:
            run_benchmark(path, args.quick)
        except Exception as err:  # one failing benchmark must not hide the others
            results.append((name, "FAILED", time.perf_counter() - t0, f"{type(err).__name__}: {err}"))
            say(f"FAILED: {type(err).__name__}: {err}")
            continue
        results.append((name, "ok", time.perf_counter() - t0, ""))
    say("\n=== summary")
    for name, status, seconds, note in results:
        say(f"{name:10s} {status:8s} {seconds:7.1f} s  {note}")
    return 1 if any(status == "FAILED" for _, status, _, _ in results) else 0
