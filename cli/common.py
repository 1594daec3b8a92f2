"""Shared CLI helpers: argument types, consoles and JSON output (the CLI's only I/O layer)."""

from __future__ import annotations

import argparse
import json
import sys
from typing import Any

import numpy as np
from rich.console import Console

__all__ = ["stdout", "stderr", "positive_float", "tolerance", "print_json", "to_jsonable"]

stdout = Console(highlight=False)
stderr = Console(stderr=True, highlight=False)


def tolerance(text: str) -> float:
    """argparse type for ε: a number in (0, 1)."""
    value = positive_float(text)
    if value >= 1.0:
        raise argparse.ArgumentTypeError(f"eps must be in (0, 1), got {text}")
    return value


def positive_float(text: str) -> float:
    """argparse type: a finite number > 0."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not np.isfinite(value) or value <= 0:
        raise argparse.ArgumentTypeError(f"must be a finite number > 0, got {text}")
    return value


def to_jsonable(value: Any) -> Any:
    """Convert numpy scalars/arrays (and nested containers) to JSON types."""
    if isinstance(value, dict):
        return {str(k): to_jsonable(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [to_jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return to_jsonable(value.tolist())
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, float) and not np.isfinite(value):
        return None
    return value


def print_json(doc: dict[str, Any]) -> None:
    """One JSON object on stdout."""
    sys.stdout.write(json.dumps(to_jsonable(doc)) + "\n")
