"""JSON in and out: conversion of results (numpy scalars and arrays, nested containers) to
JSON types, and the one strict parser every reader of a JSON document or header uses."""

from __future__ import annotations

import json
import math
from typing import Any

import numpy as np

from .errors import BadInputError

__all__ = ["to_jsonable", "loads_strict", "MAX_INT_DIGITS"]

#: Longest integer literal :func:`loads_strict` accepts, in digits (Python refuses to convert
#: more than 4300 digits; no document of ours holds more than about 20).
MAX_INT_DIGITS = 64


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


class _Refused(ValueError):
    """A literal that strict JSON (RFC 8259) or our documents do not allow."""


def _constant(name: str) -> Any:
    raise _Refused(f"non-finite literal {name} (strict JSON has none)")


def _float(text: str) -> float:
    value = float(text)
    if not math.isfinite(value):
        raise _Refused(f"number {text[:40]!r} overflows a 64-bit float")
    return value


def _int(text: str) -> int:
    digits = len(text.lstrip("-"))
    if digits > MAX_INT_DIGITS:
        raise _Refused(f"integer literal of {digits} digits (at most {MAX_INT_DIGITS})")
    return int(text)


def loads_strict(text: str | bytes, source: object, what: str = "JSON document") -> Any:
    """Parse strict JSON (RFC 8259) from a reader's input.

    Parameters
    ----------
    text
        The document; ``bytes`` must be UTF-8 (no byte-order mark).
    source
        The file (or spec) named in every error.
    what
        What the text is, for the messages ("fit document", "SHRM header").

    Returns
    -------
    Any
        The parsed value (any JSON type: callers check that it is the object they expect).

    Raises
    ------
    BadInputError
        Not UTF-8, not JSON, the non-standard literals ``NaN``/``Infinity``, a number that
        overflows a float, an integer of more than :data:`MAX_INT_DIGITS` digits, or nesting
        deeper than Python's recursion limit allows.

    Examples
    --------
    >>> loads_strict('{"a": [1, 2.5, null]}', "doc.json")
    {'a': [1, 2.5, None]}
    >>> loads_strict('{"a": NaN}', "d.json", "header")
    Traceback (most recent call last):
    ...
    shrmkit.brdf_io.errors.BadInputError: d.json: not a valid header: non-finite literal NaN (strict JSON has none)
    """
    if isinstance(text, bytes | bytearray):
        try:
            text = bytes(text).decode("utf-8")
        except UnicodeDecodeError as err:
            raise BadInputError(source, f"{what} is not UTF-8 text ({err.reason} at byte {err.start})") from None
    try:
        return json.loads(text, parse_constant=_constant, parse_float=_float, parse_int=_int)
    except RecursionError:
        raise BadInputError(source, f"{what} is nested too deeply") from None
    except ValueError as err:  # json.JSONDecodeError, and the literals refused above
        raise BadInputError(source, f"not a valid {what}: {err}") from None
