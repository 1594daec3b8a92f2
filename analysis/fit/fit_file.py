"""The fit JSON document (``data_specs/fit_json.md``): build it and write it atomically.

``shrmkit.load_brdf("fit.json")`` reads the document back as the fitted model through its
string key ``model_spec`` (``brdf_io/specs.py``).
"""

from __future__ import annotations

import json
import math
import os
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

import nlopt

from ..._version import __version__
from ...brdf_io.atomic import atomic_path
from ...brdf_io.errors import BadInputError
from ...brdf_io.specs import brdf_from_spec
from .optimize import FitResult

__all__ = ["FIT_FORMAT", "FIT_FORMAT_VERSION", "fit_document", "write_fit_json"]

FIT_FORMAT = "shrmkit-fit"
FIT_FORMAT_VERSION = 1


def _clean(value: Any) -> Any:
    """JSON-safe copy: NaN/Inf become null (strict JSON has no NaN)."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {str(k): _clean(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_clean(v) for v in value]
    return value


def fit_document(result: FitResult, source: str | os.PathLike[str] | None = None) -> dict[str, Any]:
    """The JSON document of a fit (``data_specs/fit_json.md``, format version 1).

    Parameters
    ----------
    result
        A :class:`~shrmkit.analysis.fit.FitResult`.
    source
        What was fitted (a path or spec string) for the provenance block.
    """
    doc = {
        "format": FIT_FORMAT,
        "format_version": FIT_FORMAT_VERSION,
        "model_spec": result.brdf.to_spec(),
        "model": result.model,
        "params": result.params,
        "errors": result.errors,
        "bands": [b.as_dict() for b in result.bands],
        "fit": {
            "status": result.status,
            "success": result.success,
            "converged": result.converged,
            "message": result.message,
            "worst_band": None if result.worst is None else result.worst.as_dict(),
            "at_bounds": list(result.at_bounds),
            "evaluations": result.evaluations,
            "seconds": result.seconds,
            "n_samples": result.n_samples,
            "n_dropped": result.n_dropped,
        },
        "options": result.options,
        "provenance": {
            "source": None if source is None else str(source),
            "shrmkit_version": __version__,
            "nlopt_version": f"{nlopt.version_major()}.{nlopt.version_minor()}.{nlopt.version_bugfix()}",
            "created_utc": datetime.now(timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
        },
    }
    return _clean(doc)


def write_fit_json(
    path: str | os.PathLike[str], result: FitResult, source: str | os.PathLike[str] | None = None
) -> Path:
    """Write :func:`fit_document` to ``path`` atomically (temporary file + ``os.replace``).

    Raises
    ------
    BadInputError
        The fitted model's ``model_spec`` would not load back (a parameter outside the
        bounds of ``data_specs/spec_strings.md``): nothing is written.
    """
    doc = fit_document(result, source)
    try:
        brdf_from_spec(doc["model_spec"])  # what load_brdf("fit.json") will do
    except BadInputError as err:
        raise BadInputError(path, f"the fitted model would not load back: {err.problem}") from None
    text = json.dumps(doc, indent=2, allow_nan=False) + "\n"
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return Path(path)
