"""SHRM files (``.shrm.npz``): save and load a global SHRM exactly.

Layout (see ``data_specs/shrm_file.md``): a NumPy ``.npz`` archive with

- ``coeffs``: float32 ((P+1)², H, W, 3), the global SHRM B̃_pq(α, β), real basis, flat
  index p² + p + q, lat-long pixel centres, z-up frame;
- ``header``: a JSON string with ``format`` ("shrmkit-shrm"), ``version`` (1), ``F``,
  ``P``, ``tolerance``, ``eps`` (dict), ``grid`` ("latlong"), ``orientation`` and
  ``meta`` (provenance, timings; ``lights`` describes the explicit lights, ``lights_brdf``
  names the BRDF that shades them);
- optional ``light_directions`` (n, 3), ``light_power`` (n, 3) float64 and ``light_index``
  (n,) int64: the explicit lights' samples (DESIGN §5a), all three or none.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from ..brdf_io.atomic import atomic_path
from ..brdf_io.errors import BadInputError
from ..brdf_io.jsonutil import loads_strict, to_jsonable
from ..brdf_io.npz_safe import NpzMember, read_npz
from .lights import Light, LightSet

__all__ = ["save_shrm", "read_shrm_fields", "check_header", "FORMAT", "VERSION", "MAX_ORDER"]

FORMAT = "shrmkit-shrm"
VERSION = 1
ORIENTATION = "z-up; row i at theta=(i+1/2)pi/H, column j at phi=2pi(j+1/2)/W from +x toward +y"
#: Largest order F or P a header may state (no array is sized by F; P is also bounded by the
#: element limit through the (P+1)² coefficient planes).
MAX_ORDER = 100_000
# 0-d unicode header: 2**24 characters is far more than a header ever needs
_MEMBERS = {
    "coeffs": NpzMember("f", "float32", ndim=4, itemsize=4),
    "header": NpzMember("U", "a JSON string", ndim=0, max_bytes=4 * 2**24),
    "cube": NpzMember("f", "float32", ndim=5, itemsize=4, required=False),
    # explicit lights (DESIGN §5a): sample directions, RGB powers, the light of each sample
    "light_directions": NpzMember("f", "float64", ndim=2, itemsize=8, required=False, max_bytes=1 << 24),
    "light_power": NpzMember("f", "float64", ndim=2, itemsize=8, required=False, max_bytes=1 << 24),
    "light_index": NpzMember("i", "int64", ndim=1, itemsize=8, required=False, max_bytes=1 << 22),
}
_LIGHT_KEYS = ("light_directions", "light_power", "light_index")
_REQUIRED_KEYS = ("format", "version", "F", "P", "tolerance", "eps", "grid", "orientation", "meta")


def _is_int(value: Any) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _is_number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)


def check_header(source: object, header: Any, has_cube: bool) -> None:
    """Validate a parsed SHRM header (``data_specs/shrm_file.md``, "Load checks").

    Parameters
    ----------
    source
        The file named in the errors.
    header
        The parsed JSON header.
    has_cube
        Whether the archive holds a ``cube`` array (the header's ``cube`` must agree).

    Raises
    ------
    BadInputError
        Not an object; another format or version; a missing key; ``F``/``P`` not whole
        numbers in [0, :data:`MAX_ORDER`]; ``tolerance`` not null or a number in (0, 1);
        ``eps`` not an object of finite numbers or nulls; ``grid`` not ``"latlong"``;
        ``orientation`` not a string; ``meta`` not an object; ``cube`` not null or a string,
        or disagreeing with the arrays.
    """
    if not isinstance(header, dict):
        raise BadInputError(source, f"not a shrmkit SHRM file (the header is a JSON {type(header).__name__})")
    if header.get("format") != FORMAT:
        raise BadInputError(source, f"not a shrmkit SHRM file (format {header.get('format')!r})")
    version = header.get("version")
    if not _is_int(version) or version != VERSION:
        raise BadInputError(source, f"unsupported SHRM format version {version!r} (expected {VERSION})")
    missing = [k for k in _REQUIRED_KEYS if k not in header]
    if missing:
        raise BadInputError(source, f"SHRM header lacks key(s) {', '.join(missing)}")
    for key in ("F", "P"):
        value = header[key]
        if not _is_int(value) or not 0 <= value <= MAX_ORDER:
            raise BadInputError(source, f"header {key}={value!r} is not a whole number in [0, {MAX_ORDER}]")
    tolerance = header["tolerance"]
    if tolerance is not None and not (_is_number(tolerance) and 0.0 < tolerance < 1.0):
        raise BadInputError(source, f"header tolerance={tolerance!r} is not null or a number in (0, 1)")
    eps = header["eps"]
    if not isinstance(eps, dict):
        raise BadInputError(source, f"header eps is a JSON {type(eps).__name__}, expected an object")
    for key, value in eps.items():
        if value is not None and not _is_number(value):
            raise BadInputError(source, f"header eps[{key!r}]={value!r} is not a finite number or null")
    if header["grid"] != "latlong":
        raise BadInputError(source, f"header grid={header['grid']!r}; only 'latlong' is supported")
    if not isinstance(header["orientation"], str):
        raise BadInputError(source, "header orientation is not a string")
    if not isinstance(header["meta"], dict):
        raise BadInputError(source, f"header meta is a JSON {type(header['meta']).__name__}, expected an object")
    cube = header.get("cube")
    if cube is not None and not isinstance(cube, str):
        raise BadInputError(source, f"header cube={cube!r} is not null or a string")
    if (cube is not None) != has_cube:
        raise BadInputError(
            source, "header describes a cube map but the file has no cube array" if cube is not None
            else "the file has a cube array but its header says cube null",
        )


def _check_arrays(source: object, P: int, coeffs: np.ndarray, cube: np.ndarray | None) -> None:
    n = (P + 1) ** 2
    if coeffs.ndim != 4 or coeffs.shape[0] != n or coeffs.shape[3] != 3:
        raise BadInputError(source, f"coefficient array {coeffs.dtype} {coeffs.shape} does not match P={P}: "
                            f"expected ({n}, H, W, 3)")
    H, W = coeffs.shape[1:3]
    if H < 1 or W != 2 * H:
        raise BadInputError(source, f"coefficient map of {H} x {W} (rows x columns); expected H >= 1, W = 2H")
    if cube is not None and (
        cube.ndim != 5 or cube.shape[:2] != (n, 6) or cube.shape[2] != cube.shape[3] or cube.shape[2] < 1
        or cube.shape[4] != 3
    ):
        raise BadInputError(source, f"cube array {cube.dtype} {cube.shape} does not match P={P}: "
                            f"expected ({n}, 6, S, S, 3), S >= 1")
    for name, array in (("coefficients", coeffs), ("cube coefficients", cube)):
        if array is not None and not np.all(np.isfinite(array)):
            raise BadInputError(source, f"{int(np.count_nonzero(~np.isfinite(array)))} non-finite {name}")


def save_shrm(path: str | Path, shrm: Any) -> Path:
    """Write ``shrm`` (an :class:`~shrmkit.analysis.shrm.SHRM`: ``F``, ``P``, ``coeffs``, ``tolerance``,
    ``eps``, ``meta``, ``cube``) to ``path`` (``.shrm.npz``) atomically; returns the path.

    A tolerance that is not finite (an SHRM built by hand) is written as ``null``; non-finite
    ``eps`` and ``meta`` numbers as ``null``.

    Raises
    ------
    BadInputError
        What :func:`read_shrm_fields` would refuse (negative orders, shapes, non-finite
        coefficients): nothing is written.
    """
    path = Path(path)
    header = {
        "format": FORMAT,
        "version": VERSION,
        "F": int(shrm.F),
        "P": int(shrm.P),
        "tolerance": to_jsonable(float(shrm.tolerance)),
        "eps": to_jsonable(shrm.eps),
        "grid": "latlong",
        "orientation": ORIENTATION,
        "meta": to_jsonable(shrm.meta),
        "cube": None if shrm.cube is None else "faces +x,-x,+y,-y,+z,-z of the z-up frame, OpenGL texel axes",
    }
    arrays = {"coeffs": np.asarray(shrm.coeffs, dtype=np.float32)}
    if shrm.cube is not None:
        arrays["cube"] = np.asarray(shrm.cube, dtype=np.float32)
    lights = getattr(shrm, "lights", None)
    if lights is not None and len(lights):
        arrays["light_directions"] = np.asarray(lights.directions, dtype=np.float64)
        arrays["light_power"] = np.asarray(lights.power, dtype=np.float64)
        arrays["light_index"] = np.asarray(lights.light, dtype=np.int64)
    text = json.dumps(header, allow_nan=False)
    check_header(path, loads_strict(text, path, "SHRM header"), "cube" in arrays)
    _check_arrays(path, header["P"], arrays["coeffs"], arrays.get("cube"))
    with atomic_path(path, suffix=".npz") as tmp:
        with open(tmp, "wb") as handle:
            # numpy's stubs: **arrays could fill the keyword allow_pickle (bool); its keys are array names
            np.savez_compressed(handle, header=text, **arrays)  # type: ignore[arg-type]
    return path


def read_shrm_fields(path: str | Path) -> dict[str, Any]:
    """Read and validate a file written by :func:`save_shrm`; returns the keyword arguments of
    :class:`~shrmkit.analysis.shrm.SHRM` (``shrmkit.load_shrm`` builds the object).

    Every member's declared dtype, shape and size are checked against the limits before it is
    read (:func:`~shrmkit.brdf_io.npz_safe.read_npz`), then the whole header
    (:func:`check_header`) and the arrays against it.

    Returns
    -------
    dict
        ``F``, ``P`` (int), ``coeffs`` (float32 ((P+1)², H, W, 3)), ``tolerance`` (float; NaN
        when the header says null), ``eps``, ``meta`` (dicts), ``cube`` (float32
        ((P+1)², 6, S, S, 3) or None).

    Raises
    ------
    BadInputError
        Missing, special or unreadable file; a member of the wrong dtype or with a declared
        size over the limits or unlike the archive's; a header that is not strict JSON or
        fails :func:`check_header`; array shapes that disagree with P (or an empty map);
        non-finite coefficients.
    """
    path = Path(path)
    arrays = read_npz(path, _MEMBERS, what="an SHRM file")
    header = loads_strict(str(arrays["header"][()]), path, "SHRM header")
    coeffs = np.asarray(arrays["coeffs"], dtype=np.float32)
    cube = None if "cube" not in arrays else np.asarray(arrays["cube"], dtype=np.float32)
    check_header(path, header, cube is not None)
    F, P = header["F"], header["P"]
    _check_arrays(path, P, coeffs, cube)
    tolerance = math.nan if header["tolerance"] is None else float(header["tolerance"])
    return {"F": F, "P": P, "coeffs": coeffs, "tolerance": tolerance, "eps": header["eps"],
            "meta": header["meta"], "cube": cube, "lights": _read_lights(path, arrays, header["meta"])}


def _three(values: Any) -> tuple[float, float, float]:
    """Three numbers (a light's direction or RGB power); ValueError for another count."""
    x, y, z = (float(v) for v in values)
    return x, y, z


def _read_lights(path: Path, arrays: dict[str, np.ndarray], meta: dict) -> Any:
    """The file's :class:`~shrmkit.analysis.lights.LightSet`, or None; all three arrays or none,
    matching shapes, finite, non-negative power, a BRDF named to shade them."""
    present = [key for key in _LIGHT_KEYS if key in arrays]
    if not present:
        return None
    if len(present) != len(_LIGHT_KEYS):
        raise BadInputError(path, f"light arrays incomplete: has {', '.join(present)}, needs {', '.join(_LIGHT_KEYS)}")
    d, e, k = (np.asarray(arrays[key]) for key in _LIGHT_KEYS)
    if d.ndim != 2 or d.shape[1] != 3 or e.shape != d.shape or k.shape != (d.shape[0],):
        raise BadInputError(path, f"light arrays disagree: directions {d.shape}, power {e.shape}, index {k.shape}")
    if not isinstance(meta.get("lights_brdf"), str) or not meta["lights_brdf"]:
        raise BadInputError(path, "the file has lights but its meta names no BRDF to shade them (lights_brdf)")
    described = meta.get("lights")
    if not isinstance(described, list):
        described = []
    lights = []
    for item in described:
        try:
            lights.append(Light(
                direction=_three(item["direction"]), elevation_deg=float(item["elevation_deg"]),
                azimuth_deg=float(item["azimuth_deg"]), power=_three(item["power"]),
                radius_deg=float(item["radius_deg"]), solid_angle=float(item["solid_angle_sr"]),
                share=float(item["flux_share"]), pixels=int(item["pixels"]), samples=int(item["samples"]),
                merge_deg=float(item["merge_deg"]),
            ))
        except (KeyError, TypeError, ValueError):
            raise BadInputError(path, f"light description {item!r} is not one the format defines") from None
    if k.size and (k.min() < 0 or (lights and k.max() >= len(lights))):
        raise BadInputError(path, "light_index names a light the header does not describe")
    try:
        return LightSet(d.astype(np.float64), e.astype(np.float64), k.astype(np.int64), tuple(lights))
    except (BadInputError, ValueError) as err:
        raise BadInputError(path, f"bad lights: {err}") from None
