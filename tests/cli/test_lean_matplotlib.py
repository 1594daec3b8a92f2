"""The console script's lean matplotlib import (``shared_state.lean_matplotlib``): the same plots,
byte for byte, as a process that builds matplotlib's docstrings; a library process left alone."""

from __future__ import annotations

import json
import subprocess
import sys

from shrmkit.cli import console_state
from shrmkit.cli.report import shared_state

#: a small report document with the fields the energy and accuracy-by-P plots read
_DOC = {
    "status": "ok",
    "orders": [{"tolerance": 0.03, "F": 6, "P": 2, "criterion": "bands"}],
    "eps_table": {"eps": [[1.0 / (1.0 + f + 3 * p) for p in range(5)] for f in range(12)]},
    "environments": [{"name": "sky", "eps_L_curve": [0.5 / (1 + f) for f in range(12)]}],
}

_DRAW = """
import hashlib, json, sys
from shrmkit.cli import console_state
from shrmkit.cli.report import shared_state
console_state.CONSOLE_PROCESS = {console}
shared_state.lean_matplotlib()
from shrmkit.cli.report.plots import make_plots
import matplotlib.lines
doc = json.loads(sys.argv[1])
pngs = make_plots(doc, ["energy", "accuracy_by_p"])
print(json.dumps({{k: hashlib.sha256(v).hexdigest() for k, v in sorted(pngs.items())}}))
print(bool(matplotlib.lines.Line2D.set.__doc__ and "Properties" in matplotlib.lines.Line2D.set.__doc__))
"""


def _draw(console: bool) -> tuple[str, str]:
    proc = subprocess.run([sys.executable, "-c", _DRAW.format(console=console), json.dumps(_DOC)],
                          capture_output=True, text=True, check=True)
    digests, has_table = proc.stdout.strip().splitlines()[-2:]
    return digests, has_table


def test_lean_import_draws_the_same_bytes_and_only_in_the_console_process() -> None:
    lean, lean_table = _draw(console=True)
    full, full_table = _draw(console=False)
    assert "energy" in lean and "accuracy_by_p" in lean
    assert lean == full  # the same PNG bytes: only docstrings differ
    assert (lean_table, full_table) == ("False", "True")


def test_library_process_is_left_alone() -> None:
    # this test process is not the console script: nothing is patched even when asked
    assert console_state.CONSOLE_PROCESS is False
    shared_state.lean_matplotlib()
    import matplotlib.artist

    assert matplotlib.artist.kwdoc is not shared_state._no_property_table
