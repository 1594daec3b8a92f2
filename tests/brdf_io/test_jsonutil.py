"""The one JSON converter (``brdf_io.jsonutil.to_jsonable``) used by every JSON the project writes."""

from __future__ import annotations

import json

import numpy as np

from shrmkit.brdf_io.jsonutil import to_jsonable


def test_numpy_types_and_non_finite_values() -> None:
    doc = {"a": np.float32(0.5), "b": float("nan"), "c": np.int64(3), "d": np.bool_(True),
           "e": np.array([[1.0, np.inf], [2.0, -3.0]]), 7: (np.float64(-np.inf), "x")}
    out = to_jsonable(doc)
    assert out == {"a": 0.5, "b": None, "c": 3, "d": True, "e": [[1.0, None], [2.0, -3.0]], "7": [None, "x"]}
    assert type(out["c"]) is int and type(out["d"]) is bool
    json.dumps(out, allow_nan=False)  # strict JSON


def test_significant_digits() -> None:
    out = to_jsonable({"a": np.float64(1.23456789012345), "z": 0.0, "n": [-9.87654321e-20]}, digits=4)
    assert out == {"a": 1.235, "z": 0.0, "n": [-9.877e-20]}
    assert to_jsonable(1.23456789012345, digits=10) == 1.234567890
    assert to_jsonable(1.23456789012345) == 1.23456789012345  # no rounding unless asked
