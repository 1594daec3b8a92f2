"""SHRM files (``.shrm.npz``): save and load a global SHRM exactly.

Layout (see ``data_specs/shrm_file.md``): a NumPy ``.npz`` archive with

- ``coeffs``: float32 ((P+1)², H, W, 3), the global SHRM B̃_pq(α, β), real basis, flat
  index p² + p + q, lat-long pixel centres, z-up frame;
- ``header``: a JSON string with ``format`` ("shrmkit-shrm"), ``version`` (1), ``F``,
  ``P``, ``tolerance``, ``eps`` (dict), ``grid`` ("latlong"), ``orientation`` and
  ``meta`` (provenance, timings).
"""

from __future__ import annotations

import json
import zipfile
from pathlib import Path
from typing import Any

import numpy as np

from ..brdf_io.atomic import atomic_path
from ..brdf_io.errors import BadInputError
from ..brdf_io.jsonutil import to_jsonable

__all__ = ["save_shrm", "read_shrm_fields", "FORMAT", "VERSION"]

FORMAT = "shrmkit-shrm"
VERSION = 1
ORIENTATION = "z-up; row i at theta=(i+1/2)pi/H, column j at phi=2pi(j+1/2)/W from +x toward +y"


def save_shrm(path: str | Path, shrm: Any) -> Path:
    """Write ``shrm`` (an :class:`~shrmkit.analysis.shrm.SHRM`: ``F``, ``P``, ``coeffs``, ``tolerance``,
    ``eps``, ``meta``, ``cube``) to ``path`` (``.shrm.npz``) atomically; returns the path."""
    path = Path(path)
    header = {
        "format": FORMAT,
        "version": VERSION,
        "F": int(shrm.F),
        "P": int(shrm.P),
        "tolerance": float(shrm.tolerance),
        "eps": to_jsonable(shrm.eps),
        "grid": "latlong",
        "orientation": ORIENTATION,
        "meta": to_jsonable(shrm.meta),
        "cube": None if shrm.cube is None else "faces +x,-x,+y,-y,+z,-z of the z-up frame, OpenGL texel axes",
    }
    arrays = {"coeffs": np.asarray(shrm.coeffs, dtype=np.float32)}
    if shrm.cube is not None:
        arrays["cube"] = np.asarray(shrm.cube, dtype=np.float32)
    with atomic_path(path, suffix=".npz") as tmp:
        with open(tmp, "wb") as handle:
            np.savez_compressed(handle, header=json.dumps(header), **arrays)
    return path


def read_shrm_fields(path: str | Path) -> dict[str, Any]:
    """Read and validate a file written by :func:`save_shrm`; returns the keyword arguments of
    :class:`~shrmkit.analysis.shrm.SHRM` (``shrmkit.load_shrm`` builds the object).

    Raises
    ------
    BadInputError
        Missing or unreadable file, wrong format or version, inconsistent shapes,
        non-finite coefficients.
    """
    path = Path(path)
    if not path.is_file():
        raise BadInputError(path, "no such SHRM file")
    try:
        with np.load(path, allow_pickle=False) as archive:
            coeffs = archive["coeffs"]
            header = json.loads(str(archive["header"]))
            cube = archive["cube"] if "cube" in archive.files else None
    except (OSError, ValueError, KeyError, zipfile.BadZipFile, json.JSONDecodeError, EOFError) as err:
        raise BadInputError(path, f"not a readable .shrm.npz file ({type(err).__name__}: {err})") from None
    if not isinstance(header, dict) or header.get("format") != FORMAT:
        raise BadInputError(path, f"not a shrmkit SHRM file (format {header.get('format')!r})")
    if header.get("version") != VERSION:
        raise BadInputError(path, f"unsupported SHRM format version {header.get('version')!r} (expected {VERSION})")
    F, P = int(header["F"]), int(header["P"])
    if coeffs.dtype != np.float32 or coeffs.ndim != 4 or coeffs.shape[0] != (P + 1) ** 2 or coeffs.shape[3] != 3:
        raise BadInputError(path, f"coefficient array {coeffs.dtype} {coeffs.shape} does not match P={P}")
    if cube is not None and (cube.dtype != np.float32 or cube.shape[:2] != ((P + 1) ** 2, 6) or cube.ndim != 5):
        raise BadInputError(path, f"cube array {cube.dtype} {cube.shape} does not match P={P}")
    for name, array in (("coefficients", coeffs), ("cube coefficients", cube)):
        if array is not None and not np.all(np.isfinite(array)):
            raise BadInputError(path, f"{int(np.count_nonzero(~np.isfinite(array)))} non-finite {name}")
    return {"F": F, "P": P, "coeffs": coeffs, "tolerance": float(header["tolerance"]), "eps": header["eps"],
            "meta": header["meta"], "cube": cube}
