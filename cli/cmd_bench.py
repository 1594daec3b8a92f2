"""``shrm bench``: run the speed-against-error benchmarks in one process and print their tables.

The benchmark scripts live in the source tree's ``benchmarks/`` folder (they are not part
of the installed package): ``prefilter_speed.py`` (shrmkit's prefiltering, order choice
included, against the best angular methods — [RH02] Table 4's lobe-truncated sum and the
engines' split sum — each time beside its measured error and the stated one, and the current
targets of issue 22 marked met / NO with what explains a NO), ``fit_speed.py`` (fit times and errors) and
``render_speed.py`` (frames per second; needs an offscreen OpenGL context and is skipped
without one). Each is loaded from its file and its ``main`` called with ``--quick`` when
asked; a benchmark that fails is reported and the others still run (exit status 1 if any
failed). A missing folder, or a folder without the scripts of the chosen benchmarks, is a
usage error: one line naming the folder and the missing scripts, exit status 2, nothing run.

``--json``: one JSON object on stdout (data_specs/benchmarks_json.md) with, per benchmark, its status,
seconds, the tables it printed (every ``rich`` table: title, column headers, rows of cell text) and
the lines of its other output; what the benchmarks print goes to stderr meanwhile.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib.util
import io
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from rich.console import Console
from rich.table import Table
from rich.text import Text

from ..brdf_io.errors import BadInputError
from ..render.offscreen import probe_offscreen
from .common import print_json, say
from .options_bench import BENCHMARKS


def _default_folder() -> Path:
    """``benchmarks/`` next to the package's top folder (the source checkout)."""
    return Path(__file__).resolve().parents[1] / "benchmarks"


def _load(path: Path):
    spec = importlib.util.spec_from_file_location(f"shrm_bench_{path.stem}", path)
    assert spec is not None and spec.loader is not None  # a .py file always has a spec and a loader
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


def _cell(value: Any) -> str:
    """A rich table cell as plain text (markup and styles dropped)."""
    if isinstance(value, Text):
        return value.plain
    return Text.from_markup(value).plain if isinstance(value, str) else str(value)


def table_record(table: Table) -> dict[str, Any]:
    """A rich table as JSON: ``title``, ``columns`` (header texts) and ``rows`` (lists of cell texts)."""
    columns = [_cell(c.header) for c in table.columns]
    cells = [[_cell(v) for v in c.cells] for c in table.columns]
    return {"title": _cell(table.title) if table.title is not None else "", "columns": columns,
            "rows": [list(row) for row in zip(*cells, strict=True)] if cells else []}


class _Tee(io.TextIOBase):
    """Text written to it goes to ``echo`` and is kept (:attr:`text`)."""

    def __init__(self, echo: Any) -> None:
        super().__init__()
        self.echo = echo
        self.parts: list[str] = []

    def write(self, text: str) -> int:
        self.parts.append(text)
        self.echo.write(text)
        return len(text)

    def flush(self) -> None:
        self.echo.flush()

    @property
    def text(self) -> str:
        return "".join(self.parts)


@contextlib.contextmanager
def captured(tables: list[dict[str, Any]]) -> Iterator[_Tee]:
    """While a benchmark runs under ``--json``: its stdout goes to stderr (and is kept), and every
    rich table any console prints is appended to ``tables`` as :func:`table_record` (the consoles
    are the benchmarks' own, so ``Console.print`` is wrapped for the duration, then restored)."""
    original = Console.print

    def recording(self: Console, *objects: Any, **kwargs: Any) -> None:
        tables.extend(table_record(o) for o in objects if isinstance(o, Table))
        original(self, *objects, **kwargs)

    tee = _Tee(sys.stderr)
    Console.print = recording  # type: ignore[method-assign]
    try:
        with contextlib.redirect_stdout(tee):
            yield tee
    finally:
        Console.print = original  # type: ignore[method-assign]


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
    records = []
    for name in names:
        file, what = BENCHMARKS[name]
        path = folder / file
        if not args.json:
            say(f"\n=== {name}: {what} ({path}){' --quick' if args.quick else ''}")
        record: dict[str, Any] = {"name": name, "script": str(path), "quick": args.quick, "tables": [], "text": []}
        records.append(record)
        if name == "render":
            ok, message = probe_offscreen(timeout=60.0)
            if not ok:
                results.append((name, "skipped", 0.0, f"no offscreen OpenGL: {message}"))
                if not args.json:
                    say(f"skipped: no offscreen OpenGL context ({message})")
                continue
        t0 = time.perf_counter()
        capture = captured(record["tables"]) if args.json else contextlib.nullcontext()
        try:
            with capture as tee:
                try:
                    run_benchmark(path, args.quick)
                finally:
                    if tee is not None:
                        record["text"] = tee.text.splitlines()
        except Exception as err:  # one failing benchmark must not hide the others
            results.append((name, "FAILED", time.perf_counter() - t0, f"{type(err).__name__}: {err}"))
            if not args.json:
                say(f"FAILED: {type(err).__name__}: {err}")
            continue
        results.append((name, "ok", time.perf_counter() - t0, ""))
    failed = any(status == "FAILED" for _, status, _, _ in results)
    if args.json:
        for record, (_, status, seconds, note) in zip(records, results, strict=True):
            record.update(status=status, seconds=seconds, note=note)
        print_json({"benchmarks": records, "failed": failed})
        return 1 if failed else 0
    say("\n=== summary")
    for name, status, seconds, note in results:
        say(f"{name:10s} {status:8s} {seconds:7.1f} s  {note}")
    return 1 if failed else 0
