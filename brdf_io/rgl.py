"""RGL measured materials (``.bsdf``, Mitsuba 3's ``tensor_file`` container): reader and
evaluation ([DJ18]).

The EPFL RGL material database (rgl.epfl.ch/materials) stores each material in the
adaptive parameterization of [DJ18]: for every measured incident direction ω_i the outgoing
directions are not tabulated on an angle grid but on a *warped* unit square, the preimage of the
half-vector under the sampling map of the material's visible-normal distribution (VNDF).
:func:`read_rgl` reads a file (:func:`read_tensor_file`, the container) into an :class:`RGLBRDF`,
whose ``eval`` reproduces Mitsuba 3's ``measured`` plugin to float32 precision, with the table's
incident direction ω_i played by the view by default, as Mitsuba renders it (``table_direction``;
the formula, the choice and its sources: :class:`RGLBRDF` and ``data_specs/rgl_bsdf.md``).

References: [DJ18]; [Mitsuba3]: ``src/bsdfs/measured.cpp`` (the ``measured`` BSDF: ω_i =
``si.wi``), ``include/mitsuba/render/interaction.h`` (``si.wi = to_local(-ray.d)``: toward the
camera), ``src/integrators/path.cpp`` (``bsdf->eval_pdf(ctx, si, wo = to_local(ds.d))``: wo toward
the light), ``include/mitsuba/core/distr_2d.h`` (``Marginal2D``, continuous variant) and
``src/core/tensor.cpp`` (the ``tensor_file`` container). Citation keys: ``data_specs/bibliography.md``.
"""

from __future__ import annotations

import os
import struct
import warnings
from pathlib import Path
from typing import Literal

import numpy as np

from .atomic import atomic_path
from .brdf import BRDF, Kind, as_directions
from .errors import BadInputError
from .limits import check_elements, read_bytes

#: Peak bytes per byte of an RGL tensor file while it is read and set up (21 measured on the shared
#: files): the memory plan of data_specs/limits.md.
RGL_PEAK_PER_BYTE = 32

__all__ = [
    "DEFAULT_TABLE_DIRECTION",
    "GRAZING_COS",
    "RGLBRDF",
    "RGL_INCIDENT",
    "RGLGamutWarning",
    "TENSOR_DTYPES",
    "read_rgl",
    "read_tensor_file",
    "rgl_anisotropy",
    "ANISO_PROBES",
    "write_tensor_file",
]

TENSOR_MAGIC = b"tensor_file\x00"
TENSOR_VERSION = (1, 0)
_PREAMBLE = 12 + 2 + 4  # magic, version (2 x u8), field count (u32)
_MIN_ENTRY = 2 + 2 + 1 + 8  # name length, ndim, dtype, offset (an empty name, no shape)

#: dtype code -> numpy dtype (little-endian): Mitsuba's ``Struct::Type`` enumeration
#: (0 = invalid), as written by ``mitsuba/python/tensor_io.py``.
TENSOR_DTYPES: dict[int, np.dtype] = {
    1: np.dtype("u1"),
    2: np.dtype("i1"),
    3: np.dtype("<u2"),
    4: np.dtype("<i2"),
    5: np.dtype("<u4"),
    6: np.dtype("<i4"),
    7: np.dtype("<u8"),
    8: np.dtype("<i8"),
    9: np.dtype("<f2"),
    10: np.dtype("<f4"),
    11: np.dtype("<f8"),
}
_DTYPE_CODES = {dt: code for code, dt in TENSOR_DTYPES.items()}

_REQUIRED = ("description", "theta_i", "phi_i", "ndf", "sigma", "vndf", "rgb", "jacobian")
_BLOCK = 1 << 16  # query points per evaluation block

#: Floor on cos θ of the non-table direction in ρ = R·D/(4σ cos θ): the stored R does
#: not fall to 0 at the horizon (data_specs/rgl_bsdf.md, "Grazing angles"), so ρ grows
#: like 1/cos θ there; the floor keeps it finite (it acts only within 0.00006° of the
#: horizon).
GRAZING_COS = 1e-6


#: Which argument of ``RGLBRDF.eval(L, V)`` plays the file's incident direction ω_i by default:
#: ``"view"``, as Mitsuba 3 renders the format (data_specs/rgl_bsdf.md, "Which direction is incident").
DEFAULT_TABLE_DIRECTION: Literal["light", "view"] = "view"
#: The command line's and spec strings' names (``--rgl-incident``, ``file.bsdf#light``) -> ``table_direction``.
RGL_INCIDENT: dict[str, Literal["light", "view"]] = {"camera": "view", "light": "light"}
_INCIDENT_NAME = {direction: name for name, direction in RGL_INCIDENT.items()}


#: A negative RGB value larger than this fraction of the table's largest value is corruption, not an
#: out-of-gamut colour (the RGL files of ../shared/data: at most 0.023).
CORRUPT_NEGATIVE = 0.5
#: Largest RGB value a measured file may hold: the spectral reflectance factor R of the format is at
#: most a few units for real materials (the RGL files of ../shared/data: at most 4.7, paper_white); a value of
#: 10⁶ or more is corruption (a flipped exponent), and it would overflow the sums of the analysis.
MAX_MEASURED_RGB = 1e6


class RGLGamutWarning(UserWarning):
    """An RGL RGB table holds negative (out-of-gamut) values; they were clamped to 0."""


# --------------------------------------------------------------------------------------
# the tensor_file container
# --------------------------------------------------------------------------------------


def _parse_tensor_file(data: bytes, source: object) -> dict[str, np.ndarray]:
    size = len(data)
    if size < _PREAMBLE:
        raise BadInputError(
            source, f"{size} bytes, shorter than the 18-byte tensor_file header (magic, version, field count)"
        )
    if data[:12] != TENSOR_MAGIC:
        raise BadInputError(
            source, f"starts with {data[:12]!r}, not the tensor_file magic {TENSOR_MAGIC!r}: not a Mitsuba "
            "tensor file (RGL .bsdf)"
        )
    version = (data[12], data[13])
    if version != TENSOR_VERSION:
        raise BadInputError(source, f"tensor_file version {version[0]}.{version[1]}; only version 1.0 is known")
    (n_fields,) = struct.unpack_from("<I", data, 14)
    if n_fields == 0:
        raise BadInputError(source, "tensor_file declares no fields")
    if n_fields > (size - _PREAMBLE) // _MIN_ENTRY:
        raise BadInputError(
            source, f"tensor_file declares {n_fields:,} fields, more than its {size:,} bytes can hold "
            f"({_MIN_ENTRY} header bytes each at least): truncated or corrupt"
        )

    def need(pos: int, count: int, what: str) -> None:
        if pos + count > size:
            raise BadInputError(
                source, f"truncated header: {what} needs bytes {pos}..{pos + count - 1}, the file has {size}"
            )

    entries: list[tuple[str, np.dtype, int, tuple[int, ...]]] = []
    seen: set[str] = set()
    pos = _PREAMBLE
    for index in range(n_fields):
        where = f"field {index + 1} of {n_fields}"
        need(pos, 2, f"{where} (name length)")
        (name_length,) = struct.unpack_from("<H", data, pos)
        pos += 2
        need(pos, name_length + 2 + 1 + 8, f"{where} (name, ndim, dtype, offset)")
        try:
            name = data[pos : pos + name_length].decode("utf-8")
        except UnicodeDecodeError:
            raise BadInputError(source, f"{where}: name {data[pos : pos + name_length]!r} is not UTF-8") from None
        pos += name_length
        if not name:
            raise BadInputError(source, f"{where} has an empty name")
        if name in seen:
            raise BadInputError(source, f"field {name!r} appears twice")
        seen.add(name)
        ndim, code, offset = struct.unpack_from("<HBQ", data, pos)
        pos += 11
        if code not in TENSOR_DTYPES:
            known = ", ".join(f"{c} {dt.name}" for c, dt in TENSOR_DTYPES.items())
            raise BadInputError(source, f"field {name!r} has unknown dtype code {code} (known: {known})")
        need(pos, 8 * ndim, f"field {name!r} (shape of {ndim} axes)")
        shape = struct.unpack_from(f"<{ndim}Q", data, pos)
        pos += 8 * ndim
        entries.append((name, TENSOR_DTYPES[code], int(offset), tuple(int(n) for n in shape)))

    header_end = pos
    fields: dict[str, np.ndarray] = {}
    for name, dtype, offset, shape in entries:
        count = check_elements(source, shape, f"field {name!r}")
        nbytes = count * dtype.itemsize
        if count and offset < header_end:
            raise BadInputError(
                source, f"field {name!r}: data offset {offset} lies inside the header (which ends at byte "
                f"{header_end})"
            )
        if offset + nbytes > size:
            raise BadInputError(
                source, f"field {name!r} ({dtype.name}, shape {shape}, {nbytes:,} bytes at offset {offset:,}) "
                f"extends past the end of the file ({size:,} bytes): truncated?"
            )
        fields[name] = np.frombuffer(data, dtype=dtype, count=count, offset=offset if count else 0).reshape(shape)
    return fields


def read_tensor_file(path: str | os.PathLike[str]) -> dict[str, np.ndarray]:
    """Read every field of a Mitsuba ``tensor_file`` (data_specs/rgl_bsdf.md, "Container").

    Returns
    -------
    dict
        Field name -> read-only array of the stored dtype and shape, in file order.

    Raises
    ------
    BadInputError
        Unreadable or oversized file, wrong magic or version, a header that runs past
        the end of the file, an unknown dtype code, a non-UTF-8, empty or repeated name,
        a shape over the element limit, data that overlaps the header or runs past the
        end of the file.
    """
    path = Path(path)
    # memory plan: the file, its fields and the interpolation tables (21 B per file byte measured)
    return _parse_tensor_file(read_bytes(path, "tensor file", peak_per_byte=RGL_PEAK_PER_BYTE), path)


def write_tensor_file(path: str | os.PathLike[str], fields: dict[str, object], *, align: int = 8) -> Path:
    """Write a Mitsuba ``tensor_file`` atomically: the header, then each field's C-order
    little-endian data at an offset aligned to ``align`` bytes (as Mitsuba's
    ``tensor_io.write`` does). A ``str`` value is stored as a uint8 array of its UTF-8.

    Raises
    ------
    BadInputError
        A dtype with no tensor_file code (e.g. bool, complex, object).
    """
    path = Path(path)
    arrays: dict[str, np.ndarray] = {}
    for name, value in fields.items():
        if isinstance(value, str):
            value = np.frombuffer(value.encode("utf-8"), dtype=np.uint8)
        a = np.asarray(value)
        a = np.ascontiguousarray(a) if a.ndim else a  # ascontiguousarray would make a scalar 1-D
        dtype = a.dtype.newbyteorder("<") if a.dtype.byteorder == ">" else a.dtype
        if dtype not in _DTYPE_CODES:
            raise BadInputError(path, f"field {name!r}: dtype {a.dtype} has no tensor_file code")
        arrays[name] = a.astype(dtype, copy=False)
    header = bytearray(TENSOR_MAGIC + bytes(TENSOR_VERSION) + struct.pack("<I", len(arrays)))
    header_size = len(header) + sum(2 + len(n.encode()) + 2 + 1 + 8 + 8 * a.ndim for n, a in arrays.items())
    offset = header_size
    blobs = []
    for name, a in arrays.items():
        offset = -(-offset // align) * align
        label = name.encode("utf-8")
        header += struct.pack("<H", len(label)) + label
        header += struct.pack("<HBQ", a.ndim, _DTYPE_CODES[a.dtype], offset)
        header += struct.pack(f"<{a.ndim}Q", *a.shape)
        blobs.append((offset, a.tobytes()))
        offset += a.nbytes
    out = bytearray(offset)
    out[: len(header)] = header
    for start, blob in blobs:
        out[start : start + len(blob)] = blob
    with atomic_path(path) as tmp:
        tmp.write_bytes(bytes(out))
    return path


# --------------------------------------------------------------------------------------
# interpolants (the continuous Marginal2D of Mitsuba, re-derived)
# --------------------------------------------------------------------------------------


def _theta_to_u(theta: np.ndarray) -> np.ndarray:
    """Elevation θ ∈ [0, π/2] -> unit coordinate sqrt(θ / (π/2)) (denser near the pole)."""
    return np.sqrt(np.maximum(theta, 0.0) * (2.0 / np.pi))


def _phi_to_u(phi: np.ndarray) -> np.ndarray:
    """Azimuth φ -> unit coordinate (φ + π)/2π, wrapped into [0, 1)."""
    u = (phi + np.pi) * (0.5 / np.pi)
    return u - np.floor(u)


def _param_weights(grid: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Lower/upper grid index and the weight of the upper one for linear interpolation in
    a sorted 1-D parameter grid; clamped (constant) outside the grid."""
    n = grid.size
    if n == 1:
        zero = np.zeros(x.shape, dtype=np.intp)
        return zero, zero, np.zeros(x.shape)
    lo = np.clip(np.searchsorted(grid, x, side="right") - 1, 0, n - 2)
    w = np.clip((x - grid[lo]) / (grid[lo + 1] - grid[lo]), 0.0, 1.0)
    return lo, lo + 1, w


def _cells(u: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Patch index (0..n−2) and fraction of unit coordinates u on an axis of n vertices
    spanning [0, 1]; u is clamped to [0, 1]."""
    t = np.clip(u, 0.0, 1.0) * (n - 1)
    i = np.minimum(t.astype(np.intp), n - 2)
    return i, t - i


def _patch_columns(cols: list[np.ndarray]) -> np.ndarray:
    """(n_cols, n_patches) contiguous float64: one row per per-patch quantity (structure of arrays:
    a gather per quantity gives contiguous columns, ~6× faster arithmetic than strided (n, k) rows)."""
    return np.ascontiguousarray(np.stack([np.ravel(c) for c in cols]), dtype=np.float64)


def _gather(columns: np.ndarray, slice_size: int, cell: np.ndarray,
            param: tuple[np.ndarray, np.ndarray, np.ndarray]) -> list[np.ndarray]:
    """Each per-patch quantity at the patches ``cell`` (N,), linear between the parameter slices
    ``lo`` and ``hi`` of ``param`` with weight ``w`` of ``hi``: (1 − w)·v_lo + w·v_hi."""
    lo, hi, w = param
    at_lo = lo * slice_size + cell
    out = [np.take(row, at_lo) for row in columns]
    if np.any(w > 0):
        at_hi = hi * slice_size + cell
        keep = 1.0 - w
        for k, row in enumerate(columns):
            value = out[k]
            value *= keep
            value += w * np.take(row, at_hi)
    return out


class _Bilinear:
    """Bilinear interpolation of vertex values on [0, 1]², linear between parameter slices.

    ``values`` has shape (T, H, W, C): T parameter slices, H rows (the y coordinate), W
    columns (x, fastest), C channels; vertex (j, i) sits at (x, y) = (i/(W−1), j/(H−1)).
    """

    def __init__(self, values: np.ndarray) -> None:
        T, H, W, C = values.shape
        self.shape = (H, W)
        # per patch: the C values of its corners (0,0), (1,0), (0,1), (1,1) (x, y), corner-major
        corners = (values[:, :-1, :-1], values[:, :-1, 1:], values[:, 1:, :-1], values[:, 1:, 1:])
        self._columns = _patch_columns([corner[..., c] for corner in corners for c in range(C)])
        self._channels = C
        self._slice = (H - 1) * (W - 1)

    def __call__(self, x: np.ndarray, y: np.ndarray, param: tuple[np.ndarray, np.ndarray, np.ndarray]) -> np.ndarray:
        H, W = self.shape
        i, fx = _cells(x, W)
        j, fy = _cells(y, H)
        C = self._channels
        v = _gather(self._columns, self._slice, j * (W - 1) + i, param)
        out = np.empty((x.shape[0], C))
        for c in range(C):
            v00, v10, v01, v11 = v[c], v[C + c], v[2 * C + c], v[3 * C + c]
            bottom = v00 + (v10 - v00) * fx
            top = v01 + (v11 - v01) * fx
            out[:, c] = bottom + (top - bottom) * fy
        return out


class _InverseWarp:
    """The inverse of the continuous marginal/conditional sampling warp of a bilinear
    density on [0, 1]², per parameter slice (Mitsuba ``Marginal2D<…, Continuous=true>``,
    normalized; data_specs/rgl_bsdf.md, "The VNDF warp").

    The density p(x, y) is the bilinear interpolant of the vertex values, normalized per
    slice to integrate to 1. Sampling draws y from the marginal m(y) = ∫ p(x, y) dx, then
    x from p(x | y); its inverse maps a point (x, y) to

        s_x = ∫_0^x p(x', y) dx' / ∫_0^1 p(x', y) dx',      s_y = ∫_0^y m(y') dy'.

    Both integrals are exact for the bilinear density: along x the row integrals are
    trapezoidal cumulative sums at the two rows of the patch, linear in y between them;
    m(y) is linear within a patch row. Between parameter slices every stored quantity
    (density, cumulative sums) is interpolated linearly, as Mitsuba does.
    """

    def __init__(self, density: np.ndarray) -> None:
        T, H, W = density.shape
        self.shape = (H, W)
        cond = np.zeros((T, H, W))
        np.cumsum(0.5 / (W - 1) * (density[:, :, :-1] + density[:, :, 1:]), axis=2, out=cond[:, :, 1:])
        rows = cond[:, :, -1]  # ∫_0^1 p(x, y_j) dx at each vertex row
        marg = np.zeros((T, H))
        np.cumsum(0.5 / (H - 1) * (rows[:, :-1] + rows[:, 1:]), axis=1, out=marg[:, 1:])
        total = marg[:, -1].copy()
        self.totals = total
        norm = (1.0 / np.where(total > 0, total, 1.0))[:, None, None]
        d, cond, rows, marg = density * norm, cond * norm, rows * norm[:, :, 0], marg * norm[:, :, 0]
        # per patch (j, i), one row each: density at its 4 corners, the conditional CDF at its
        # left edge on both rows, the two row totals and the marginal CDF at its bottom row
        cols = [
            d[:, :-1, :-1], d[:, :-1, 1:], d[:, 1:, :-1], d[:, 1:, 1:],
            cond[:, :-1, :-1], cond[:, 1:, :-1],
            np.broadcast_to(rows[:, :-1, None], (T, H - 1, W - 1)),
            np.broadcast_to(rows[:, 1:, None], (T, H - 1, W - 1)),
            np.broadcast_to(marg[:, :-1, None], (T, H - 1, W - 1)),
        ]  # fmt: skip
        self._columns = _patch_columns(cols)
        self._slice = (H - 1) * (W - 1)

    def __call__(
        self, x: np.ndarray, y: np.ndarray, param: tuple[np.ndarray, np.ndarray, np.ndarray]
    ) -> tuple[np.ndarray, np.ndarray]:
        H, W = self.shape
        i, fx = _cells(x, W)
        j, fy = _cells(y, H)
        v00, v10, v01, v11, c0, c1, r0, r1, m0 = _gather(self._columns, self._slice, j * (W - 1) + i, param)
        left = v00 + (v01 - v00) * fy  # density along the patch's left and right edges at y
        right = v10 + (v11 - v10) * fy
        partial = fx * (left + (right - left) * (0.5 * fx)) / (W - 1)
        row = r0 + (r1 - r0) * fy
        sx = (c0 + (c1 - c0) * fy + partial) / np.where(row > 0, row, 1.0)
        sx = np.where(row > 0, sx, x)  # a row without mass: the identity (no data to warp by)
        sy = m0 + fy * (r0 + (r1 - r0) * (0.5 * fy)) / (H - 1)
        return np.clip(sx, 0.0, 1.0), np.clip(sy, 0.0, 1.0)


# --------------------------------------------------------------------------------------
# the BRDF
# --------------------------------------------------------------------------------------


def _float_table(source: object, name: str, value: object, ndim: int) -> np.ndarray:
    a = np.asarray(value)
    if a.dtype.kind != "f":
        raise BadInputError(source, f"field {name!r} has dtype {a.dtype}, expected floating point (float32)")
    if a.ndim != ndim:
        raise BadInputError(source, f"field {name!r} has shape {a.shape}, expected {ndim} axes")
    a = a.astype(np.float64)
    bad = ~np.isfinite(a)
    if np.any(bad):
        first = tuple(int(k[0]) for k in np.nonzero(bad))
        raise BadInputError(source, f"field {name!r} has {int(bad.sum())} non-finite value(s), first at {first}")
    return a


def _check_grid(source: object, name: str, shape: tuple[int, ...]) -> None:
    if min(shape[-2:]) < 2:
        raise BadInputError(source, f"field {name!r}: the 2-D table is {shape[-2]} x {shape[-1]}, needs >= 2 x 2")


class RGLBRDF(BRDF):
    """An isotropic RGL measured material ([DJ18]), RGB.

    The container and the evaluation are specified in
    ``data_specs/rgl_bsdf.md``; in short, for light L and view V (unit vectors, normal +z,
    both pointing away from the surface) with half vector H = normalize(L + V)::

        u   = (sqrt(θ_h / (π/2)), frac((φ_h − φ_L + π) / 2π))     half vector in unit coordinates
        s   = W⁻¹_{θ_L}(u)                                        inverse VNDF warp (``vndf`` field)
        R   = rgb_{θ_L}(s)                                        bilinear in s, linear in θ_L
        ρ(L, V) = R · D(u) / (4 σ(L) cos θ_V)                     D = ``ndf``, σ = ``sigma``

    (without the factor D/(4σ) when the file's ``jacobian`` flag is 0), written here with
    the table direction ω_i = L. The stored R is the Monte Carlo weight
    f_r cos θ_o / p(ω_o | ω_i) of VNDF sampling, whose density is p = D(ω_h) / (4 σ(ω_i)), so
    dividing by cos θ_o gives ρ without the cosine. R · D/(4σ) is what Mitsuba 3's
    ``measured`` plugin (and the authors' reference code ``powitacq``) returns as
    ``eval(si.wi, wo)`` = ρ · cos θ_o; this module reproduces it to float32 precision.

    **Which direction is ω_i.** Mitsuba's integrators call ``eval`` with ``si.wi`` pointing
    toward the camera (the previous path vertex) and ``wo`` toward the light, so Mitsuba
    renders the data with ω_i = V. The default ``table_direction="view"`` does the same
    (``eval(L, V)`` = the formula above at ω_i = V, ω_o = L), so renders agree with Mitsuba's;
    ``table_direction="light"`` (ω_i = L, the direction the gonio-photometer lit the sample
    from) is the explicit alternative. The data are not reciprocal (8–19 % for the vinyls),
    so the two differ; the choice and its sources are in data_specs/rgl_bsdf.md. R does not
    vanish at the horizon, so ρ grows like 1/cos θ_o at grazing ω_o (floored at
    :data:`GRAZING_COS`); θ_i outside the measured range uses the nearest measured slice.

    ``eval(L, V)`` implements data_specs/rgl_bsdf.md, "Evaluation": the half vector is
    mapped through the inverse VNDF warp of the incident elevation θ_L, the RGB table is
    interpolated there, and ρ = R · D / (4 σ(L) cos θ_V). Tables are interpolated as
    Mitsuba 3's ``measured`` plugin does: bilinearly on their unit squares, linearly in
    θ_i between measured incident angles and *clamped* (constant) outside the measured
    θ_i range; the result is 0 unless L_z > 0 and V_z > 0.

    Parameters
    ----------
    theta_i
        Measured incident elevations (T,), radians, strictly increasing in [0, π/2].
    ndf, sigma
        D(ω_m) on (θ_m, φ_m) unit coordinates, shape (H, W) (rows φ, columns θ), 1/sr;
        σ(ω_i), projected area, same layout, > 0.
    vndf
        Visible-normal density per incident elevation, (T, H, W), ≥ 0 (the warp).
    rgb
        R per incident elevation on the warped unit square, (T, 3, h, w).
    jacobian
        The file's ``jacobian`` flag: multiply R by D/(4σ) (true in RGL files).
    clip_negative
        Clamp negative (out-of-gamut) RGB values to 0 with a :class:`RGLGamutWarning`
        (the count stays in ``n_negative``); if false they are kept.
    table_direction
        Which argument of ``eval`` plays the file's incident direction ω_i: ``"view"``
        (default, :data:`DEFAULT_TABLE_DIRECTION`; ρ(L, V) = R(θ_V, …) D / (4 σ(V) cos θ_L):
        ρ cos θ_L is exactly what Mitsuba 3 renders, ``eval(si.wi = V, wo = L)`` with
        ``si.wi`` toward the camera, bounded at grazing L) or ``"light"`` (ω_i = L, the
        direction the sample was lit from: ρ(L, V) = R(θ_L, …) D / (4 σ(L) cos θ_V), the
        view-mode value at (V, L)).

    Attributes
    ----------
    n_negative
        Number of negative values in the stored RGB table (before any clamping).
    description, name, source
        The file's description text, the file stem (``read_rgl`` appends ``#light`` for
        ``table_direction="light"``, the spec string that loads it) and path (or a given
        name, ``None``).
    theta_i, ndf, sigma, vndf, rgb, luminance, jacobian
        The tables as float64 (``rgb`` after clamping); ``luminance`` (the sampling
        density of Mitsuba's ``sample``) is kept when given, not used by ``eval``.
    valid
        The file's raw ``valid`` bytes (or ``None``), not used by ``eval``: a bit-packed
        mask whose polarity differs between the database's files
        (data_specs/rgl_bsdf.md, "Fields").
    table_direction
        ``"light"`` or ``"view"``, as given.
    """

    kind: Kind = "tabulated"

    def __init__(
        self,
        theta_i: np.ndarray,
        ndf: np.ndarray,
        sigma: np.ndarray,
        vndf: np.ndarray,
        rgb: np.ndarray,
        *,
        jacobian: bool = True,
        clip_negative: bool = True,
        description: str = "",
        luminance: np.ndarray | None = None,
        valid: np.ndarray | None = None,
        table_direction: Literal["light", "view"] = DEFAULT_TABLE_DIRECTION,
        name: str = "rgl",
        source: str | None = None,
    ) -> None:
        where = source or name
        if table_direction not in ("light", "view"):
            raise BadInputError(where, f"table_direction must be 'light' or 'view', got {table_direction!r}")
        theta_i = _float_table(where, "theta_i", theta_i, 1)
        if theta_i.size < 1:
            raise BadInputError(where, "field 'theta_i' is empty")
        if np.any(np.diff(theta_i) <= 0):
            raise BadInputError(where, f"field 'theta_i' is not strictly increasing: {theta_i.tolist()}")
        if theta_i[0] < -1e-6 or theta_i[-1] > np.pi / 2 + 1e-6:
            raise BadInputError(
                where, f"field 'theta_i' spans [{theta_i[0]!r}, {theta_i[-1]!r}], outside [0, π/2] radians"
            )
        T = theta_i.size
        ndf = _float_table(where, "ndf", ndf, 2)
        sigma = _float_table(where, "sigma", sigma, 2)
        vndf = _float_table(where, "vndf", vndf, 3)
        rgb = _float_table(where, "rgb", rgb, 4)
        for key, table in (("ndf", ndf), ("sigma", sigma), ("vndf", vndf), ("rgb", rgb)):
            _check_grid(where, key, table.shape)
        if vndf.shape[0] != T:
            raise BadInputError(where, f"field 'vndf' has {vndf.shape[0]} incident-angle slices, theta_i has {T}")
        if rgb.shape[:2] != (T, 3):
            raise BadInputError(where, f"field 'rgb' has shape {rgb.shape}, expected ({T}, 3, h, w)")
        if np.any(ndf < 0) or np.any(vndf < 0):
            raise BadInputError(where, "fields 'ndf' and 'vndf' must be non-negative densities")
        if np.any(sigma <= 0):
            raise BadInputError(where, f"field 'sigma' (projected area) must be positive, min {sigma.min()!r}")
        warp = _InverseWarp(vndf)
        if np.any(warp.totals <= 0):
            k = int(np.argmax(warp.totals <= 0))
            raise BadInputError(where, f"field 'vndf' slice {k} (θ_i = {theta_i[k]!r}) is zero everywhere")
        self.n_negative = int(np.sum(rgb < 0))
        peak = float(rgb.max())
        huge = rgb > MAX_MEASURED_RGB
        if np.any(huge):
            raise BadInputError(
                where, f"field 'rgb' holds {int(huge.sum())} value(s) above {MAX_MEASURED_RGB:g} (largest {peak:.4g}): "
                "no measured reflectance is that large; the file is corrupt"
            )
        if self.n_negative and (peak <= 0.0 or -float(rgb.min()) > CORRUPT_NEGATIVE * peak):
            # an out-of-gamut channel is a small fraction of the colour beside it (≤ 0.023 of the
            # table's largest value in every RGL file of ../shared/data); −2.5e38 is corruption
            raise BadInputError(
                where, f"field 'rgb' holds {float(rgb.min()):.4g} beside a largest value of {peak:.4g}: not an "
                f"out-of-gamut colour (|min| > {CORRUPT_NEGATIVE:g} x max); the file is corrupt"
            )
        if self.n_negative and clip_negative:
            warnings.warn(
                f"{where}: {self.n_negative} of {rgb.size} RGB values are negative (out of gamut, min "
                f"{rgb.min():.4g}); clamped to 0",
                RGLGamutWarning,
                stacklevel=3,
            )
            rgb = np.maximum(rgb, 0.0)
        self.theta_i, self.ndf, self.sigma, self.vndf, self.rgb = theta_i, ndf, sigma, vndf, rgb
        self.jacobian = bool(jacobian)
        self.table_direction = table_direction
        self.description = description
        self.luminance = None if luminance is None else np.asarray(luminance, dtype=np.float64)
        self.valid = None if valid is None else np.asarray(valid)
        self.name = name
        self.source = source
        self._warp = warp
        self._rgb = _Bilinear(np.moveaxis(rgb, 1, -1))
        self._ndf = _Bilinear(ndf[None, :, :, None])
        self._sigma = _Bilinear(sigma[None, :, :, None])

    def warped_coordinates(self, W_i: np.ndarray, W_o: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Where direction pairs (N, 3), both above the surface, fall on the warped unit
        square, with ``W_i`` the table direction (L when ``table_direction="light"``):
        the half vector's unit coordinates u (N, 2) and the inverse-warped sample
        s = W⁻¹_{θ_i}(u) (N, 2), each as (x = θ part, y = φ part)."""
        u, s, _, _ = self._coordinates(*_unit(W_i, W_o))
        return u, s

    def _coordinates(
        self, Wi: np.ndarray, Wo: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, tuple[np.ndarray, np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]:
        """Half-vector unit coordinates u, warped sample s, the θ_i interpolation weights
        and the table direction's unit coordinates, for unit Wi, Wo (N, 3) above the surface."""
        H = _unit(Wi + Wo)[0]  # H_z > 0: never zero
        theta_i = np.arctan2(np.hypot(Wi[:, 0], Wi[:, 1]), Wi[:, 2])
        phi_i = np.arctan2(Wi[:, 1], Wi[:, 0])
        theta_h = np.arctan2(np.hypot(H[:, 0], H[:, 1]), H[:, 2])
        phi_h = np.arctan2(H[:, 1], H[:, 0])
        # isotropic: the half vector's azimuth is taken relative to the incident one
        u = np.stack((_theta_to_u(theta_h), _phi_to_u(phi_h - phi_i)), axis=-1)
        param = _param_weights(self.theta_i, theta_i)
        s = np.stack(self._warp(u[:, 0], u[:, 1], param), axis=-1)
        return u, s, param, (_theta_to_u(theta_i), _phi_to_u(phi_i))

    def _eval_block(self, Wi: np.ndarray, Wo: np.ndarray) -> np.ndarray:
        """ρ for unit Wi (table direction), Wo (N, 3), both above the surface."""
        u, s, param, u_i = self._coordinates(Wi, Wo)
        value = self._rgb(s[:, 0], s[:, 1], param)  # R
        if self.jacobian:
            none = _param_weights(np.zeros(1), u[:, 0])  # ndf, sigma: no θ_i dependence
            d = self._ndf(u[:, 0], u[:, 1], none)[:, 0]
            sig = self._sigma(u_i[0], u_i[1], none)[:, 0]
            value *= (d / (4.0 * sig))[:, None]  # R · D / (4σ) = ρ cos θ_o
        value /= np.maximum(Wo[:, 2:3], GRAZING_COS)
        return value

    def eval(self, L: np.ndarray, V: np.ndarray) -> np.ndarray:
        """RGB ρ(L, V) in 1/sr, shape (..., 3); 0 unless L_z > 0 and V_z > 0.

        With ``table_direction="view"`` (default) V is the file's incident direction ω_i
        and ρ = R(θ_V, …) · D / (4 σ(V) cos θ_L), as Mitsuba renders it; with ``"light"``
        the roles of L and V swap.
        Directions are normalized first. Where the stored R does not fall to 0 at the
        horizon ρ grows like 1/cos θ of the other direction; cos θ is floored at
        :data:`GRAZING_COS`, so ρ is finite for every pair above the surface.
        """
        L, V = as_directions(L, V)
        shape = L.shape[:-1]
        L, V = L.reshape(-1, 3), V.reshape(-1, 3)
        if not (np.all(np.isfinite(L)) and np.all(np.isfinite(V))):
            raise ValueError("directions must be finite")
        Wi, Wo = (V, L) if self.table_direction == "view" else (L, V)
        out = np.zeros((L.shape[0], 3))
        above = np.flatnonzero((L[:, 2] > 0) & (V[:, 2] > 0))
        for start in range(0, above.size, _BLOCK):
            sel = above[start : start + _BLOCK]
            out[sel] = self._eval_block(*_unit(Wi[sel], Wo[sel]))
        return out.reshape(*shape, 3)


#: Outgoing directions per measured incident direction probed by :func:`rgl_anisotropy`
#: (a Fibonacci set on the upper hemisphere, in the incident direction's azimuthal frame).
ANISO_PROBES = 256


def _fibonacci_hemisphere(n: int) -> np.ndarray:
    """n nearly uniform unit directions (n, 3) with z in (0, 1)."""
    k = np.arange(n) + 0.5
    z = 1.0 - k / n
    phi = np.pi * (3.0 - np.sqrt(5.0)) * k
    r = np.sqrt(1.0 - z * z)
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=-1)


def rgl_anisotropy(
    theta_i: np.ndarray, phi_i: np.ndarray, ndf: np.ndarray, sigma: np.ndarray, vndf: np.ndarray,
    rgb: np.ndarray, *, jacobian: bool = True, probes: int = ANISO_PROBES,
) -> float:
    """How far an anisotropic RGL material is from isotropic: the energy fraction of the part of
    ρ cos θ_o that changes with the incident azimuth (data_specs/rgl_bsdf.md, "Anisotropic files").

    For every stored incident azimuth φ_k and elevation θ_t (exactly on the table's slices: no
    interpolation in φ_i) ρ cos θ_o = R · D / (4σ) is evaluated at outgoing directions
    R_z(φ_k) ω_j, the same :data:`ANISO_PROBES` directions ω_j turned with the incident one, the
    half vector's azimuth taken absolute as Mitsuba 3's ``measured`` plugin does for anisotropic
    files. An isotropic material gives the same values for every φ_k; the result is

        A = Σ_{t,j,c} Σ_k (v_ktjc − v̄_tjc)² / Σ_{t,j,c} Σ_k v_ktjc²,

    v̄ the mean over the azimuths (a last azimuth 2π after the first, the same one, is left out).

    Parameters
    ----------
    theta_i, phi_i
        The file's incident elevations (T,) and azimuths (P,), radians.
    ndf, sigma
        D and σ tables (H, W) on absolute (θ, φ) unit coordinates.
    vndf, rgb
        (P, T, H', W') and (P, T, 3, h, w): the warp and the RGB table per (φ_i, θ_i).
    jacobian
        The file's ``jacobian`` flag.
    probes
        Outgoing directions per incident direction.

    Returns
    -------
    float
        A in [0, 1): 0 for identical azimuth slices; NaN when every value is 0.
    """
    theta_i = np.asarray(theta_i, dtype=np.float64)
    phi_i = np.asarray(phi_i, dtype=np.float64)
    P, T = phi_i.size, theta_i.size
    if P > 2 and abs(phi_i[-1] - phi_i[0] - 2.0 * np.pi) < 1e-3:
        P -= 1  # the closing azimuth repeats the first
    rel = _fibonacci_hemisphere(probes)
    d_ndf = _Bilinear(np.asarray(ndf, dtype=np.float64)[None, :, :, None])
    d_sigma = _Bilinear(np.asarray(sigma, dtype=np.float64)[None, :, :, None])
    values = np.zeros((P, T, probes, 3))
    for k in range(P):
        warp = _InverseWarp(np.asarray(vndf[k], dtype=np.float64))
        table = _Bilinear(np.moveaxis(np.asarray(rgb[k], dtype=np.float64), 1, -1))
        c, s = np.cos(phi_i[k]), np.sin(phi_i[k])
        Wo = np.stack([c * rel[:, 0] - s * rel[:, 1], s * rel[:, 0] + c * rel[:, 1], rel[:, 2]], axis=-1)
        for t in range(T):
            Wi = np.broadcast_to([np.sin(theta_i[t]) * c, np.sin(theta_i[t]) * s, np.cos(theta_i[t])], Wo.shape)
            H = _unit(Wi + Wo)[0]
            u = np.stack((_theta_to_u(np.arctan2(np.hypot(H[:, 0], H[:, 1]), H[:, 2])),
                          _phi_to_u(np.arctan2(H[:, 1], H[:, 0]))), axis=-1)
            node = (np.full(probes, t, dtype=np.intp), np.full(probes, t, dtype=np.intp), np.zeros(probes))
            sx, sy = warp(u[:, 0], u[:, 1], node)
            v = table(sx, sy, node)
            if jacobian:
                none = _param_weights(np.zeros(1), u[:, 0])
                ui = (np.full(probes, _theta_to_u(theta_i[t])), np.full(probes, _phi_to_u(phi_i[k])))
                v = v * (d_ndf(u[:, 0], u[:, 1], none)[:, 0] / (4.0 * d_sigma(ui[0], ui[1], none)[:, 0]))[:, None]
            values[k, t] = v
    total = float(np.sum(values**2))
    if total <= 0:
        return float("nan")
    return float(np.sum((values - values.mean(axis=0)) ** 2) / total)


def _unit(*ws: np.ndarray) -> tuple[np.ndarray, ...]:
    """The (N, 3) arrays (no zero rows) scaled to unit length."""
    out = []
    for w in ws:
        w = np.asarray(w, dtype=np.float64).reshape(-1, 3)
        a = np.abs(w)
        w = w / np.maximum(np.maximum(a[:, 0], a[:, 1]), a[:, 2])[:, None]  # to O(1) first: no underflow
        out.append(w / np.sqrt(np.einsum("ij,ij->i", w, w))[:, None])
    return tuple(out)


# --------------------------------------------------------------------------------------
# the reader
# --------------------------------------------------------------------------------------


def _expect(source: object, fields: dict[str, np.ndarray], name: str, dtype: str, ndim: int) -> np.ndarray:
    a = fields[name]
    if a.dtype != np.dtype(dtype):
        raise BadInputError(source, f"field {name!r} has dtype {a.dtype.name}, expected {np.dtype(dtype).name}")
    if a.ndim != ndim:
        raise BadInputError(source, f"field {name!r} has shape {a.shape}, expected {ndim} axes")
    return a


def _anisotropic_message(path: Path, fields: dict[str, np.ndarray], phi_i: np.ndarray, theta_i: np.ndarray) -> str:
    """The refusal of an anisotropic file, with its anisotropy when the tables allow computing it."""
    head = f"anisotropic material ({phi_i.size} incident azimuths φ_i)"
    tail = "; only isotropic files (one φ_i) are supported"
    P, T = phi_i.size, theta_i.size
    try:
        ndf = _float_table(path, "ndf", _expect(path, fields, "ndf", "<f4", 2), 2)
        sigma = _float_table(path, "sigma", _expect(path, fields, "sigma", "<f4", 2), 2)
        vndf = _float_table(path, "vndf", _expect(path, fields, "vndf", "<f4", 4), 4)
        rgb = _float_table(path, "rgb", _expect(path, fields, "rgb", "<f4", 5), 5)
        if vndf.shape[:2] != (P, T) or rgb.shape[:3] != (P, T, 3) or not np.all(np.isfinite(phi_i)):
            raise BadInputError(path, "table shapes do not match phi_i x theta_i")
        for key, table in (("ndf", ndf), ("sigma", sigma), ("vndf", vndf), ("rgb", rgb)):
            _check_grid(path, key, table.shape)
        if np.any(sigma <= 0) or np.any(vndf < 0):
            raise BadInputError(path, "non-positive sigma or negative vndf")
        jac = bool(_expect(path, fields, "jacobian", "u1", 1)[0])
        share = rgl_anisotropy(theta_i, phi_i, ndf, sigma, vndf, np.maximum(rgb, 0.0), jacobian=jac)
    except BadInputError as err:
        return f"{head} (anisotropy not measured: {err.problem}){tail}"
    return (f"{head}: anisotropy {share:.3g} (the share of the energy of ρ cos θ_o that changes with the incident "
            f"azimuth at fixed relative geometry){tail}")


def read_rgl(
    path: str | os.PathLike[str],
    *,
    clip_negative: bool = True,
    table_direction: Literal["light", "view"] = DEFAULT_TABLE_DIRECTION,
) -> RGLBRDF:
    """Read an isotropic RGB RGL material (``*_rgb.bsdf``; data_specs/rgl_bsdf.md).

    Parameters
    ----------
    path
        The ``.bsdf`` file.
    clip_negative
        Clamp negative (out-of-gamut) RGB values to 0, with a :class:`RGLGamutWarning`
        naming the count (kept in ``n_negative`` either way).
    table_direction
        ``"view"`` (default: V is the table's ω_i, as Mitsuba 3 renders the format) or
        ``"light"`` (L is ω_i) (:class:`RGLBRDF`). ``load_brdf("file.bsdf#light")`` and
        ``--rgl-incident light`` on the command line select ``"light"``.

    Raises
    ------
    BadInputError
        Any container problem (:func:`read_tensor_file`); a missing field; a dtype or
        shape other than the format's (float32 tables, uint8 ``description`` and
        ``jacobian``, ``vndf`` (n_φ, n_θ, H, W), ``rgb`` (n_φ, n_θ, 3, h, w)); an
        anisotropic file (more than one φ_i: the message states its anisotropy,
        :func:`rgl_anisotropy`); a spectral file (``spectra`` and
        ``wavelengths`` instead of ``rgb``); non-finite values, a negative density, a
        non-positive σ or an all-zero VNDF slice.

    Examples
    --------
    A tiny synthetic file: a uniform VNDF (the warp is then the identity), R = 0.5, 0.25,
    0.125 everywhere, D = 1/π, σ = 1, one incident angle:

    >>> import pathlib, tempfile
    >>> import numpy as np
    >>> folder = tempfile.TemporaryDirectory()
    >>> rgb = np.ones((1, 1, 3, 2, 2), np.float32) * np.float32([0.5, 0.25, 0.125])[:, None, None]
    >>> path = write_tensor_file(pathlib.Path(folder.name) / "flat_rgb.bsdf", {
    ...     "description": "flat", "jacobian": np.uint8([1]),
    ...     "theta_i": np.float32([0.0]), "phi_i": np.float32([0.0]),
    ...     "ndf": np.full((2, 2), 1 / np.pi, np.float32), "sigma": np.ones((2, 2), np.float32),
    ...     "vndf": np.ones((1, 1, 2, 2), np.float32), "rgb": rgb})
    >>> brdf = read_rgl(path)
    >>> brdf.name, brdf.description, brdf.kind
    ('flat_rgb', 'flat', 'tabulated')

    With the default ``table_direction="view"`` the view V is ω_i and
    ρ = R · D / (4 σ cos θ_L); at cos θ_L = 0.8, 0.5/(4π · 0.8) = 0.0497 in red, and with
    ``"light"`` (ω_i = L) ρ = R · D / (4 σ cos θ_V) = 0.5/(4π) = 0.0398 at V = normal:

    >>> brdf.eval(np.array([0.6, 0.0, 0.8]), np.array([0.0, 0.0, 1.0])).round(5)
    array([0.04974, 0.02487, 0.01243])
    >>> lit = read_rgl(path, table_direction="light")
    >>> lit.name, lit.eval(np.array([0.6, 0.0, 0.8]), np.array([0.0, 0.0, 1.0])).round(5)
    ('flat_rgb#light', array([0.03979, 0.01989, 0.00995]))
    >>> brdf.eval(np.array([0.6, 0.0, 0.8]), np.array([0.0, 0.0, -1.0]))  # V below the surface
    array([0., 0., 0.])
    >>> folder.cleanup()
    """
    path = Path(path)
    fields = read_tensor_file(path)
    if "rgb" not in fields and ("spectra" in fields or "wavelengths" in fields):
        raise BadInputError(
            path, "spectral RGL file (fields 'spectra', 'wavelengths'); only the RGB version (*_rgb.bsdf) is "
            "supported"
        )
    missing = [name for name in _REQUIRED if name not in fields]
    if missing:
        raise BadInputError(
            path, f"missing field(s) {', '.join(map(repr, missing))}: not an RGL measured-material file "
            f"(fields: {', '.join(fields)})"
        )
    description = _expect(path, fields, "description", "u1", 1).tobytes().decode("utf-8", errors="replace")
    jacobian = _expect(path, fields, "jacobian", "u1", 1)
    if jacobian.shape != (1,):
        raise BadInputError(path, f"field 'jacobian' has shape {jacobian.shape}, expected (1,)")
    phi_i = _expect(path, fields, "phi_i", "<f4", 1)
    theta_i = _expect(path, fields, "theta_i", "<f4", 1)
    if phi_i.size != 1:
        raise BadInputError(path, _anisotropic_message(path, fields, phi_i, theta_i))
    if not np.isfinite(phi_i[0]):
        raise BadInputError(path, f"field 'phi_i' is not finite ({phi_i[0]!r})")
    T = theta_i.size
    ndf = _expect(path, fields, "ndf", "<f4", 2)
    sigma = _expect(path, fields, "sigma", "<f4", 2)
    vndf = _expect(path, fields, "vndf", "<f4", 4)
    rgb = _expect(path, fields, "rgb", "<f4", 5)
    if vndf.shape[:2] != (1, T):
        raise BadInputError(path, f"field 'vndf' has shape {vndf.shape}, expected (1, {T}, H, W) (n_φ_i, n_θ_i, …)")
    if rgb.shape[:3] != (1, T, 3):
        raise BadInputError(path, f"field 'rgb' has shape {rgb.shape}, expected (1, {T}, 3, h, w)")
    luminance = None
    if "luminance" in fields:
        luminance = _expect(path, fields, "luminance", "<f4", 4)
        if luminance.shape != (1, T, *rgb.shape[3:]):
            raise BadInputError(
                path, f"field 'luminance' has shape {luminance.shape}, expected (1, {T}, {rgb.shape[3]}, "
                f"{rgb.shape[4]}) like 'rgb'"
            )
        luminance = luminance[0]
    return RGLBRDF(
        theta_i,
        ndf,
        sigma,
        vndf[0],
        rgb[0],
        jacobian=bool(jacobian[0]),
        clip_negative=clip_negative,
        description=description,
        luminance=luminance,
        valid=fields.get("valid"),
        table_direction=table_direction,
        # the convention is part of the name where it is not the default: "paper_white_rgb#light"
        name=path.stem if table_direction == DEFAULT_TABLE_DIRECTION
        else f"{path.stem}#{_INCIDENT_NAME.get(table_direction)}",
        source=str(path),
    )
