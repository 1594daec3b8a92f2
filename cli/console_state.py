"""Whether this process is the ``shrm`` console script's own (set by ``cli.main.console_main``).

Its own module so that ``cli.main`` sets it without importing the report package (``shrm --help``
imports no verb's work: ``tests/cli/test_cli_main.py``)."""

from __future__ import annotations

__all__ = ["CONSOLE_PROCESS"]

#: True in the ``shrm`` console script's process: nothing there shows library docstrings
#: (``cli.report.shared_state.lean_matplotlib``).
CONSOLE_PROCESS = False
