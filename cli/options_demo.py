"""``shrm demo``'s parser (numpy-free; the verb's work is in ``cmd_demo.py``)."""

from __future__ import annotations

import argparse

__all__ = ["HELP", "add_arguments"]

HELP = "run orders, a fit, a prefilter, a preview render and reports on built-in data (default ./shrm-demo)"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--out", default="shrm-demo", help="output folder (default ./shrm-demo)")
    p.add_argument("--size", type=int, default=384, help="preview render size in pixels (default 384)")
    p.add_argument("--no-progress", action="store_true", help="no progress messages on stderr")
    p.add_argument("--json", action="store_true",
                   help="print one JSON object (each step's files, numbers and seconds; data_specs/report_json.md) "
                   "instead of the text lines; no progress messages")
