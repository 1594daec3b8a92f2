"""Terminal output that survives a pipe and a narrow terminal (issue 13 §3): tables keep every
number whole — no cell squeezed to "…" — whether stdout is a pipe (logs, ``| cat``) or an
80-column console."""

from __future__ import annotations

import io
import subprocess
import sys

from rich.console import Console
from rich.table import Table

from shrmkit.cli import common


def run_cli(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "shrmkit.cli.main", *args], capture_output=True, text=True)


def test_orders_and_prefilter_through_a_pipe_have_no_cut_cells(tmp_path):
    proc = run_cli("orders", "cook-torrance:alpha=0.3,dist=ggx", "--env", "builtin:sky,height=16")
    assert proc.returncode == 0, proc.stderr
    assert "…" not in proc.stdout and "eps(F, P)" in proc.stdout and "view band" in proc.stdout
    assert max(len(line) for line in proc.stdout.splitlines()) <= common.PIPE_WIDTH
    proc = run_cli("prefilter", "--env", "builtin:sky,height=16", "--brdf", "phong:s=16", "-o",
                   str(tmp_path / "a.shrm.npz"))
    assert proc.returncode == 0, proc.stderr
    assert "…" not in proc.stdout and "eps reflected" in proc.stdout


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
