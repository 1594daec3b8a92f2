"""The command line's start-up imports no numpy for --help, --version and a misspelt verb (issue 26: start-up
<= 0.3 s CPU, benchmarks/startup.py; numpy alone costs about that)."""

from __future__ import annotations

import subprocess
import sys

import pytest


@pytest.mark.parametrize("argv", [["--version"], ["--help"], ["ordres"]])
def test_startup_imports_no_numpy(argv):
    code = ("import sys, contextlib, io\n"
            "from shrmkit.cli.main import main\n"
            "with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):\n"
            "    try:\n"
            f"        main({argv!r})\n"
            "    except SystemExit:\n"
            "        pass\n"
            "print(sorted(m for m in ('numpy', 'scipy', 'matplotlib', 'vtkmodules') if m in sys.modules))\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"
