"""Conversion of results (numpy scalars and arrays, nested containers) to JSON types."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

__all__ = ["to_jsonable"]


def to_jsonable(value: Any, *, digits: int | None = None) -> Any:
    """Convert numpy scalars/arrays and nested dicts/lists/tuples to JSON types.

    Non-finite floats become ``None`` (strict JSON has no NaN/Inf); dict keys become
    strings. With ``digits``, every float is rounded to that many significant digits
    (reports keep 10, so that re-runs compare equal); 0.0 stays 0.0.
    """
    if isinstance(value, dict):
        return {str(k): to_jsonable(v, digits=digits) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [to_jsonable(v, digits=digits) for v in value]
    if isinstance(value, np.ndarray):
        return to_jsonable(value.tolist(), digits=digits)
    if isinstance(value, np.generic):
        return to_jsonable(value.item(), digits=digits)
    if isinstance(value, float):
        if not math.isfinite(value):
            return None
        if digits is not None and value != 0.0:
            return float(f"{value:.{digits - 1}e}")
    return value
