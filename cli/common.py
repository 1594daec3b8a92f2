"""Shared CLI helpers: argument types, consoles and JSON output (the CLI's only I/O layer)."""

from __future__ import annotations

import argparse
import json
import sys
from typing import Any

import numpy as np
from rich.console import Console

from ..brdf_io.jsonutil import to_jsonable

__all__ = ["stdout", "stderr", "number_in", "positive_float", "tolerance", "print_json", "to_jsonable"]

stdout = Console(highlight=False)
stderr = Console(stderr=True, highlight=False)


def number_in(
    lo: float, hi: float, *, integer: bool = False, lo_open: bool = False, hi_open: bool = False, unit: str = ""
):
    """argparse type factory: a finite number (or integer) in [lo, hi]; ``lo_open``/``hi_open``
    exclude the ends."""
    kind = "an integer" if integer else "a number"

    def parse(text: str) -> float:
        try:
            value = int(text) if integer else float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"not {kind}: {text!r}") from None
        if not np.isfinite(value) or value > hi or value < lo or (lo_open and value == lo) or (hi_open and value == hi):
            left, right = "(" if lo_open else "[", ")" if hi_open else "]"
            raise argparse.ArgumentTypeError(f"must be in {left}{lo:g}, {hi:g}{right}{unit}, got {text}")
        return value

    return parse


tolerance = number_in(0.0, 1.0, lo_open=True, hi_open=True)
"""argparse type for ε: a number in (0, 1)."""

positive_float = number_in(0.0, np.inf, lo_open=True)
"""argparse type: a finite number > 0."""


def print_json(doc: dict[str, Any]) -> None:
    """One JSON object on stdout."""
    sys.stdout.write(json.dumps(to_jsonable(doc)) + "\n")
