"""MERL BRDF database ``.binary`` format input/output.

The format ([MERL03]; layout in ``data_specs/merl_binary.md``): a header of
3 little-endian int32 dimensions (90, 90, 180), then 3 · 90·90·180 little-endian
float64, all red, then all green, then all blue; each channel is indexed
[θ_half][θ_diff][φ_diff] with φ_diff fastest. Sample (i, j, k) sits at
θ_h = (i/90)² π/2, θ_d = j π/180, φ_d = k π/180 (the lower bin edges of the reference
reader's floor lookup). Stored numbers are scaled: rho = stored · (1, 1.15, 1.66)/1500
for (R, G, B). Negative numbers mark missing measurements.

Public objects: :class:`MerlBRDF`, :func:`read_merl`, :func:`write_merl`,
:func:`tabulate_merl`, :func:`merl_sample_angles`, :func:`merl_index_coordinates`.

Reference: [MERL03] (the paper and the database's reference reader ``BRDFRead.cpp``).
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np

from .atomic import atomic_path
from .brdf import BRDF, Kind
from .errors import BadInputError
from .halfdiff import directions_to_halfdiff, halfdiff_to_directions
from .limits import check_elements, check_memory, regular_file
from .masked_grid import MaskedTableBRDF, MissingAwareGrid, eval_with_mask
from .table import MAX_TABLE_RHO, MIN_TABLE_PEAK_RHO

__all__ = [
    "MERL_DIMS",
    "MERL_SCALE",
    "MerlBRDF",
    "merl_index_coordinates",
    "merl_missing_above_surface",
    "merl_sample_angles",
    "read_merl",
    "tabulate_merl",
    "write_merl",
]

# (θ_half, θ_diff, φ_diff) resolution; BRDFRead.cpp: BRDF_SAMPLING_RES_THETA_H = 90,
# BRDF_SAMPLING_RES_THETA_D = 90, BRDF_SAMPLING_RES_PHI_D / 2 = 180
MERL_DIMS = (90, 90, 180)
#: Peak bytes per stored value while a MERL file is read and set up (measured: see data_specs/limits.md).
MERL_PEAK_BYTES_PER_VALUE = 48
# rho = stored value * scale, per channel R, G, B (BRDFRead.cpp RED/GREEN/BLUE_SCALE)
MERL_SCALE = np.array([1.0 / 1500.0, 1.15 / 1500.0, 1.66 / 1500.0])
_N = MERL_DIMS[0] * MERL_DIMS[1] * MERL_DIMS[2]
_HEADER = np.dtype("<i4")  # 3 little-endian int32 dims
_SAMPLE = np.dtype("<f8")  # little-endian float64 samples
_HEADER_BYTES = 3 * _HEADER.itemsize


def merl_sample_angles() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(θ_h, θ_d, φ_d) of the table samples, 1-D arrays of 90, 90 and 180 radians.

    θ_h = (i/90)² π/2 (square-root scale), θ_d = j π/180, φ_d = k π/180: the lower bin
    edges of BRDFRead.cpp's floor lookup (data_specs/merl_binary.md).
    """
    i, j, k = (np.arange(n, dtype=np.float64) for n in MERL_DIMS)
    return (i / MERL_DIMS[0]) ** 2 * (np.pi / 2), j * (np.pi / 2) / MERL_DIMS[1], k * np.pi / MERL_DIMS[2]


def merl_index_coordinates(
    theta_h: np.ndarray, theta_d: np.ndarray, phi_d: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Continuous table index coordinates of half/difference angles.

    The inverse of :func:`merl_sample_angles`: u = 90 sqrt(θ_h/(π/2)), v = 90 θ_d/(π/2),
    w = 180 (φ_d mod π)/π. ``floor`` of these is BRDFRead.cpp's lookup (before its
    clamping to the table); φ_d is folded into [0, π) by reciprocity (φ_d ~ φ_d + π).
    """
    u = MERL_DIMS[0] * np.sqrt(np.maximum(theta_h, 0.0) / (np.pi / 2))
    v = MERL_DIMS[1] * np.asarray(theta_d, dtype=np.float64) / (np.pi / 2)
    w = MERL_DIMS[2] * np.mod(phi_d, np.pi) / np.pi
    return u, v, w


class MerlBRDF(MaskedTableBRDF):
    """A MERL-format tabulated BRDF, interpolated in index space excluding missing samples.

    Attributes
    ----------
    values
        rho in 1/sr, shape (3, 90, 90, 180) (channel, θ_h, θ_d, φ_d index), NaN where missing.
    n_missing
        Number of table samples (of 90·90·180) with at least one channel missing.
    name, source
        The file stem and path (or a given name and ``None``).
    """

    kind: Kind = "tabulated"

    def __init__(self, values: np.ndarray, *, name: str = "merl", source: str | None = None) -> None:
        values = np.asarray(values, dtype=np.float64)
        if values.shape != (3, *MERL_DIMS):
            raise BadInputError(source or name, f"MERL values must have shape (3, 90, 90, 180), got {values.shape}")
        self.values = values
        grid = np.moveaxis(values, 0, -1)  # (θ_h, θ_d, φ_d, channel)
        self.n_missing = int(np.any(np.isnan(grid), axis=-1).sum())
        # φ_d periodic: φ_d and φ_d + π are one sample by reciprocity
        self._interpolate = MissingAwareGrid(grid, periodic=(False, False, True))
        self.name = name
        self.source = source

    def index_coordinates(self, L: np.ndarray, V: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Continuous table indices (:func:`merl_index_coordinates`) of (N, 3) direction pairs.

        Interpolation is trilinear in these indices, periodic in φ_d (sample 179 neighbours
        sample 0 = φ_d π), clamped in θ_h and θ_d; missing samples are left out and the
        weights renormalized (:class:`~shrmkit.brdf_io.masked_grid.MissingAwareGrid`).
        """
        return merl_index_coordinates(*directions_to_halfdiff(L, V))


def read_merl(path: str | os.PathLike[str]) -> MerlBRDF:
    """Read a MERL ``.binary`` file (data_specs/merl_binary.md).

    Returns
    -------
    MerlBRDF
        ``values`` of shape (3, 90, 90, 180), rho in 1/sr, NaN where the file stores a
        negative number (a missing measurement).

    Raises
    ------
    BadInputError
        Missing file, a FIFO, device or folder (refused before it is opened, by
        :func:`~shrmkit.brdf_io.limits.regular_file`), a file over the size limit, a length
        other than the 12 + 3·8·n bytes the header implies (truncated or trailing bytes;
        checked against the file size before any data is read), header dims other than
        (90, 90, 180), NaN or Inf, rho above :data:`~shrmkit.brdf_io.table.MAX_TABLE_RHO`.

    Examples
    --------
    The format fixes the table at 90 × 90 × 180 (35 MB), so the example writes one into a
    temporary folder: ρ = i/1000 · (1, 2, 3) at θ_h index i, and one missing sample.

    >>> import pathlib, tempfile
    >>> import numpy as np
    >>> values = np.empty((3, 90, 90, 180))
    >>> values[:] = np.arange(90)[None, :, None, None] / 1000 * np.array([1.0, 2.0, 3.0])[:, None, None, None]
    >>> values[:, 0, 0, 0] = np.nan
    >>> folder = tempfile.TemporaryDirectory()
    >>> brdf = read_merl(write_merl(pathlib.Path(folder.name) / "ramp.binary", values))
    >>> brdf.name, brdf.values.shape, brdf.n_missing
    ('ramp', (3, 90, 90, 180), 1)

    θ_h index 45 is θ_h = (45/90)² · 90° = 22.5°; with θ_d = 0 that is L = V tilted by
    22.5° from the normal:

    >>> L = np.array([np.sin(np.pi / 8), 0.0, np.cos(np.pi / 8)])
    >>> brdf.eval(L, L)
    array([0.045, 0.09 , 0.135])
    >>> brdf.eval_counted(L, np.array([-L[0], 0.0, -L[2]]))  # V below the surface
    (array([0., 0., 0.]), 0)
    >>> folder.cleanup()
    """
    path = Path(path)
    size = regular_file(path, "MERL .binary file")
    if size < _HEADER_BYTES:
        raise BadInputError(path, f"{size} bytes, shorter than the 12-byte MERL header")
    try:
        with path.open("rb") as handle:
            head = handle.read(_HEADER_BYTES)
            dims = tuple(int(d) for d in np.frombuffer(head, dtype=_HEADER, count=3))
            if min(dims) <= 0:
                raise BadInputError(path, f"header dims {dims} are not positive: not a MERL .binary file")
            # 3 channels of n float64 after the header (Python integers: no overflow)
            expected = _HEADER_BYTES + 3 * _SAMPLE.itemsize * dims[0] * dims[1] * dims[2]
            if size != expected:
                raise BadInputError(
                    path,
                    f"{'truncated' if size < expected else 'trailing bytes'}: header dims {dims} imply "
                    f"{expected} bytes (12 + 3*8*n), the file has {size}",
                )
            if dims != MERL_DIMS:
                raise BadInputError(path, f"header dims {dims}; only the MERL sampling {MERL_DIMS} is supported")
            check_elements(path, (3, *dims), "MERL table")
            # the memory plan: the file's bytes, the values, the missing mask and the grid
            check_memory(path, MERL_PEAK_BYTES_PER_VALUE * 3 * math.prod(dims), "reading a MERL table")
            data = handle.read(expected - _HEADER_BYTES + 1)
    except OSError as err:
        raise BadInputError(path, f"cannot read MERL file ({err.strerror or err})") from None
    if len(data) != expected - _HEADER_BYTES:
        raise BadInputError(path, "file changed size while being read")
    # channel-major planes (R, G, B), each [θ_h][θ_d][φ_d] with φ_d fastest (C order)
    stored = np.frombuffer(data, dtype=_SAMPLE).reshape(3, *MERL_DIMS)
    bad = ~np.isfinite(stored)
    if np.any(bad):
        c, i, j, k = (int(x[0]) for x in np.nonzero(bad))
        raise BadInputError(
            path, f"{int(bad.sum())} non-finite value(s), first {float(stored[c, i, j, k])!r} at channel {c}, "
            f"index ({i}, {j}, {k})"
        )
    # negative = missing measurement; scale per channel R, G, B
    values = np.where(stored < 0, np.nan, stored * MERL_SCALE[:, None, None, None])
    huge = values > MAX_TABLE_RHO
    if np.any(huge):
        c, i, j, k = (int(x[0]) for x in np.nonzero(huge))
        raise BadInputError(
            path, f"{int(huge.sum())} value(s) above rho = {MAX_TABLE_RHO:g} 1/sr, first stored "
            f"{float(stored[c, i, j, k])!r} at channel {c}, index ({i}, {j}, {k})"
        )
    if np.all(np.isnan(values)):
        raise BadInputError(path, "every sample is missing (negative): no measured value to analyse")
    largest = float(np.nanmax(values))
    if not largest > MIN_TABLE_PEAK_RHO:
        raise BadInputError(
            path, f"the largest value is {largest!r} 1/sr, at most {MIN_TABLE_PEAK_RHO:g}: nothing a measurement "
            "can hold (an all-zero file)",
        )
    return MerlBRDF(values, name=path.stem, source=str(path))


def tabulate_merl(brdf: BRDF) -> np.ndarray:
    """rho of ``brdf`` at the MERL sample positions, shape (3, 90, 90, 180), NaN missing.

    Each sample (θ_h, θ_d, φ_d) of :func:`merl_sample_angles` is turned into (L, V) with
    φ_h = 0 by :func:`~shrmkit.brdf_io.halfdiff.halfdiff_to_directions`. Samples with L or
    V below the surface (tan θ_h tan θ_d |cos φ_d| ≥ 1), where rho is undefined, and
    points where a tabulated source had no data are marked missing.

    Raises
    ------
    BadInputError
        The BRDF returned negative, infinite or above
        :data:`~shrmkit.brdf_io.table.MAX_TABLE_RHO` values.
    """
    th, td, pd = merl_sample_angles()
    L, V = halfdiff_to_directions(th[:, None, None], td[None, :, None], pd[None, None, :])
    rho, has = eval_with_mask(brdf, L, V)
    above = (L[..., 2] > 0) & (V[..., 2] > 0)
    rho = np.where((has & above)[..., None], rho, np.nan)
    if np.any(np.isinf(rho)) or np.any(rho < 0) or np.any(rho > MAX_TABLE_RHO):
        raise BadInputError(
            brdf.name,
            f"the BRDF returned negative, infinite or above-{MAX_TABLE_RHO:g} values at MERL sample positions",
        )
    return np.ascontiguousarray(np.moveaxis(rho, -1, 0))


def write_merl(path: str | os.PathLike[str], brdf_or_values: BRDF | np.ndarray) -> Path:
    """Write a MERL ``.binary`` file, atomically (temporary file + ``os.replace``).

    Parameters
    ----------
    path
        Output file.
    brdf_or_values
        A BRDF, tabulated with :func:`tabulate_merl`, or rho values of shape
        (3, 90, 90, 180) in 1/sr with NaN for missing samples (written as −1).

    Raises
    ------
    BadInputError
        Wrong shape, negative or infinite values, values above
        :data:`~shrmkit.brdf_io.table.MAX_TABLE_RHO` (what :func:`read_merl` refuses).

    Examples
    --------
    A Lambertian BRDF (ρ = albedo/π) tabulated at MERL resolution, in a temporary folder:
    a 12-byte header of three int32 dims, then 3 · 90·90·180 float64 stored as ρ · 1500 /
    (1, 1.15, 1.66), red plane first, θ_h-major; samples with V below the surface are
    missing (−1).

    >>> import pathlib, tempfile
    >>> import numpy as np
    >>> from shrmkit.brdf_io.models import Lambert, rgb
    >>> folder = tempfile.TemporaryDirectory()
    >>> path = write_merl(pathlib.Path(folder.name) / "grey.binary", Lambert(albedo=rgb(0.3)))
    >>> path.stat().st_size  # 12 + 3 * 8 * 90 * 90 * 180
    34992012
    >>> np.fromfile(path, "<i4", count=3)
    array([ 90,  90, 180], dtype=int32)
    >>> green = 12 + 8 * 90 * 90 * 180  # byte offset of the green plane
    >>> np.fromfile(path, "<f8", count=1, offset=green) * 1.15 / 1500  # 0.3/π
    array([0.09549297])
    >>> read_merl(path).eval(np.array([0.0, 0.0, 1.0]), np.array([0.6, 0.0, 0.8]))
    array([0.09549297, 0.09549297, 0.09549297])
    >>> folder.cleanup()
    """
    path = Path(path)
    if isinstance(brdf_or_values, BRDF):
        values = tabulate_merl(brdf_or_values)
    else:
        values = np.asarray(brdf_or_values, dtype=np.float64)
        if values.shape != (3, *MERL_DIMS):
            raise BadInputError(path, f"MERL values must have shape (3, 90, 90, 180), got {values.shape}")
        if np.any(np.isinf(values)) or np.any(values < 0) or np.any(values > MAX_TABLE_RHO):
            raise BadInputError(
                path, f"MERL values must be finite, non-negative and at most {MAX_TABLE_RHO:g} (NaN marks missing)"
            )
    # divide by the per-channel scale; missing -> -1 (any negative number means missing)
    stored = np.where(np.isnan(values), -1.0, values / MERL_SCALE[:, None, None, None])

    with atomic_path(path) as tmp, tmp.open("wb") as f:
        f.write(np.array(MERL_DIMS, dtype=_HEADER).tobytes())
        # channel-major R, G, B planes, each C-ordered [θ_h][θ_d][φ_d], φ_d fastest
        f.write(np.ascontiguousarray(stored, dtype=_SAMPLE).tobytes())
    return path


def merl_missing_above_surface(brdf: BRDF) -> int | None:
    """Missing MERL table samples whose (L, V) are both above the surface (``None`` if not MERL).

    Samples with tan θ_h tan θ_d |cos φ_d| >= 1 put L or V below the surface; they are
    missing in every MERL file (and in tabulated models) and are not a data problem.
    """
    values = getattr(brdf, "values", None)
    if values is None or getattr(values, "shape", None) != (3, 90, 90, 180):
        return None

    th, td, pd = merl_sample_angles()
    L, V = halfdiff_to_directions(th[:, None, None], td[None, :, None], pd[None, None, :])
    above = (L[..., 2] > 0) & (V[..., 2] > 0)
    missing = np.any(np.isnan(values), axis=0)
    return int(np.count_nonzero(missing & above))
