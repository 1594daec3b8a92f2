"""Fixtures of the command-line tests."""

from __future__ import annotations

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
