"""Terminal output that survives a pipe and a narrow terminal (issue 13 §3): tables keep every
number whole — no cell squeezed to "…" — whether stdout is a pipe (logs, ``| cat``) or an
80-column console."""

from __future__ import annotations

import io
import json
import subprocess
import sys

from rich.console import Console
from rich.table import Table

from shrmkit.cli import common

#: `shrm ARGV` for each ARGV of the JSON list argv[1], one after the other in one fresh interpreter
#: whose stdout is a pipe; after each, a line "\0EXIT <code>" (one interpreter start instead of two)
RUN_VERBS = (
    "import json, sys\n"
    "from shrmkit.cli.main import main\n"
    "for argv in json.loads(sys.argv[1]):\n"
    "    code = main(argv)\n"
    "    sys.stdout.flush()\n"
    "    print(f'\\0EXIT {code}', flush=True)\n"
)


def run_verbs(*argvs: list[str]) -> list[str]:
    """The stdout of each `shrm ARGV` (in order) run with stdout a pipe; each must exit 0."""
    proc = subprocess.run([sys.executable, "-c", RUN_VERBS, json.dumps(argvs)], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    *outs, last = proc.stdout.split("\0EXIT ")  # out 1, "code 1\nout 2", …, "code n\n"
    codes = [int(part.partition("\n")[0]) for part in [*outs[1:], last]]
    assert codes == [0] * len(argvs), proc.stderr
    return [outs[0], *(part.partition("\n")[2] for part in outs[1:])]


def test_orders_and_prefilter_through_a_pipe_have_no_cut_cells(tmp_path):
    orders, prefilter = run_verbs(
        ["orders", "cook-torrance:alpha=0.3,dist=ggx", "--env", "builtin:sky,height=16"],
        ["prefilter", "--env", "builtin:sky,height=16", "--brdf", "phong:s=16", "-o", str(tmp_path / "a.shrm.npz")])
    assert "…" not in orders and "eps(F, P)" in orders and "view band" in orders
    assert max(len(line) for line in orders.splitlines()) <= common.PIPE_WIDTH
    assert "…" not in prefilter and "eps reflected" in prefilter


def test_a_wide_table_on_an_80_column_console_is_printed_whole(monkeypatch):
    out = io.StringIO()
    monkeypatch.setattr(common, "stdout", Console(file=out, width=80, highlight=False))
    table = Table(title="wide")
    names = [f"column number {k}" for k in range(9)]
    for name in names:
        table.add_column(name)
    table.add_row(*[f"{1.0 / (k + 7):.6g}" for k in range(9)])
    common.print_table(table)
    text = out.getvalue()
    assert "…" not in text and all(name in text for name in names)
    assert all(f"{1.0 / (k + 7):.6g}" in text for k in range(9))
    assert max(len(line) for line in text.splitlines()) <= 80
    # a table that fits is printed as it is
    out.truncate(0)
    small = Table(title="small")
    small.add_column("F")
    small.add_row("12")
    common.print_table(small)
    assert "┃" in out.getvalue() or "│" in out.getvalue()
