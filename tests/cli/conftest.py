"""Fixtures of the command-line tests."""

from __future__ import annotations

import json
import subprocess
import sys
from collections.abc import Callable

import pytest

from shrmkit.cli.main import main


@pytest.fixture
def run_main(capsys) -> Callable[..., tuple[int, str]]:
    """``run_main(*args)``: `shrm ARGS` in this process (the process path is
    tests/cli/test_cli_main.py's), giving the exit code and stderr; a usage error exits through
    argparse's SystemExit."""
    def run(*args: str) -> tuple[int, str]:
        try:
            code = main(list(args))
        except SystemExit as stop:
            code = stop.code
        return code, capsys.readouterr().err

    return run


#: runs main(argv) for each argv of the JSON list argv[1], one after the other in one fresh
#: interpreter, and prints [exit code, stderr] of each as JSON: each its own stderr (warnings
#: included), stdout and warnings registry, as if each were its own process; an exception main
#: does not turn into an exit code escapes, printing its traceback on the real stderr (exit 1)
RUN_EACH = (
    "import contextlib, io, json, sys, warnings\n"
    "from shrmkit.cli.main import main\n"
    "done = []\n"
    "for argv in json.loads(sys.argv[1]):\n"
    "    err = io.StringIO()\n"
    "    with warnings.catch_warnings(), contextlib.redirect_stderr(err), "
    "contextlib.redirect_stdout(io.StringIO()):\n"
    "        try:\n"
    "            code = main(argv)\n"
    "        except SystemExit as stop:\n"
    "            code = stop.code\n"
    "    done.append([code, err.getvalue()])\n"
    "print(json.dumps(done))\n"
)


@pytest.fixture(scope="session")
def run_each() -> Callable[..., list[tuple[int, str]]]:
    """``run_each(cases, timeout=120)``: `shrm ARGV` for each ARGV of ``cases`` (lists of str) in one
    fresh interpreter (:data:`RUN_EACH`), giving [(exit code, stderr)] in order. One interpreter
    start and one set of imports for all of them instead of ~1.5 s CPU each, with the isolation a
    subprocess gives: a reader that blocks or crashes the process fails the test (timeout or exit
    code), and anything written to the real stderr (a traceback, output below Python) fails it too."""
    def run(cases: list[list[str]], timeout: float = 120.0) -> list[tuple[int, str]]:
        proc = subprocess.run([sys.executable, "-c", RUN_EACH, json.dumps(cases)], capture_output=True, text=True,
                              timeout=timeout)
        assert proc.returncode == 0 and not proc.stderr, proc.stderr[-3000:]
        done = [(code, err) for code, err in json.loads(proc.stdout)]
        assert len(done) == len(cases)
        return done

    return run
