"""shrmkit BRDF table format (``.npz``) input/output.

A table holds rho(θ_i, θ_o, φ_d) in 1/sr on a rectilinear grid of angles; the layout is
specified in ``data_specs/brdf_table.md``. Public objects:

- :class:`TableBRDF` — a tabulated isotropic BRDF, trilinear in angle, excluding missing
  (NaN) samples (the interpolation is shared with the MERL reader:
  :mod:`~shrmkit.brdf_io.masked_grid`);
- :func:`read_table`, :func:`write_table` — the reader/writer pair;
- :func:`tabulate_table` — evaluate any BRDF on a (θ_i, θ_o, φ_d) grid.

The masked-grid machinery (``MaskedTableBRDF``, ``MissingAwareGrid``,
``interpolate_excluding_missing``, ``eval_with_mask``, ``flatten_directions``,
``EVAL_BLOCK``) lives in :mod:`~shrmkit.brdf_io.masked_grid`; import it from there.

References
----------
data_specs/brdf_table.md (format version 1).
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

import numpy as np

from .atomic import atomic_path
from .brdf import BRDF, Kind
from .errors import BadInputError
from .halfdiff import spherical_angles
from .jsonutil import loads_strict
from .masked_grid import MaskedTableBRDF, MissingAwareGrid, eval_with_mask
from .npz_safe import NpzMember, read_npz

__all__ = [
    "MAX_TABLE_RHO",
    "MIN_TABLE_PEAK_RHO",
    "TABLE_FORMAT",
    "TABLE_FORMAT_VERSION",
    "TableBRDF",
    "read_table",
    "tabulate_table",
    "write_table",
]

TABLE_FORMAT = "shrmkit-brdf-table"
TABLE_FORMAT_VERSION = 1
#: Largest value a table (or a MERL file) may hold, rho in 1/sr. Far above any measurement
#: and above any analytic model within its parameter bounds (< 1e33 even at the horizon,
#: data_specs/spec_strings.md), low enough that sums and squares of values stay finite.
MAX_TABLE_RHO = 1e40
#: A table (or MERL file) whose largest measured value is at most this (rho in 1/sr) is refused:
#: 25 orders of magnitude below any measurement (a dark MERL sample is ~1e-5), an all-zero or
#: underflowed table the analysis could only call "zero everywhere" (1e-300 squared is 0).
MIN_TABLE_PEAK_RHO = 1e-30
#: Largest order :meth:`TableBRDF.resolved_order` returns (far above any order cap of the analysis).
MAX_RESOLVED_ORDER = 1_000_000
_MAX_NAME = 1000  # longest metadata name used as the BRDF's name
_REAL = "a real-number array (float, int)"
#: Peak bytes per value while a table is read and set up (measured 33 for float32 and float64
#: RGB tables of 12.6 million values: the member, its float64 copy, the masks, the missing-aware
#: grid); the memory plan (data_specs/limits.md) uses this before the values are inflated.
TABLE_PEAK_BYTES_PER_VALUE = 40
_MEMBERS = {
    "theta_i": NpzMember("fiu", _REAL),
    "theta_o": NpzMember("fiu", _REAL),
    "phi_d": NpzMember("fiu", _REAL),
    "values": NpzMember("fiu", "floating point values", peak_bytes_per_element=TABLE_PEAK_BYTES_PER_VALUE),
    # 0-d unicode string; 2**24 characters is far more than the metadata ever needs
    "metadata": NpzMember("U", "a JSON string", ndim=0, max_bytes=4 * 2**24),
}


# --------------------------------------------------------------------------------------
# validation
# --------------------------------------------------------------------------------------


def _check_axis(source: object, name: str, axis: Any, hi: float) -> np.ndarray:
    try:
        with np.errstate(over="ignore", invalid="ignore"):  # float128 beyond float64: caught as non-finite
            a = np.asarray(axis, dtype=np.float64)
    except (TypeError, ValueError):
        raise BadInputError(source, f"grid {name} is not numeric") from None
    if a.ndim != 1 or a.size < 1:
        raise BadInputError(source, f"grid {name} must be a non-empty 1-D array, got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise BadInputError(source, f"grid {name} has {int(np.sum(~np.isfinite(a)))} non-finite value(s)")
    if np.any(np.diff(a) <= 0):
        k = int(np.argmax(np.diff(a) <= 0))
        raise BadInputError(
            source,
            f"grid {name} is not strictly increasing "
            f"({name}[{k}]={float(a[k])!r}, {name}[{k + 1}]={float(a[k + 1])!r})",
        )
    if a[0] < 0 or a[-1] > hi + 1e-12:
        raise BadInputError(
            source, f"grid {name} spans [{float(a[0])!r}, {float(a[-1])!r}], outside [0, {hi!r}] radians"
        )
    return a


def _check_values(source: object, values: Any, shape: tuple[int, int, int]) -> np.ndarray:
    v = np.asarray(values)
    if v.dtype.kind not in "fiu":
        raise BadInputError(source, f"values have dtype {v.dtype}, expected floating point")
    with np.errstate(over="ignore", invalid="ignore"):  # float128 beyond float64: caught as infinite
        v = v.astype(np.float64)
    if v.shape not in (shape, (*shape, 3)):
        raise BadInputError(
            source, f"values have shape {v.shape}; the grid needs {shape} (scalar) or {(*shape, 3)} (RGB)"
        )
    if np.any(np.isinf(v)):
        raise BadInputError(source, f"values contain {int(np.sum(np.isinf(v)))} infinite value(s)")
    huge = v > MAX_TABLE_RHO
    if np.any(huge):
        raise BadInputError(
            source,
            f"values contain {int(huge.sum())} value(s) above {MAX_TABLE_RHO:g} 1/sr (max {float(v[huge].max())!r})",
        )
    negative = v < 0  # NaN compares false: NaN is allowed (missing)
    if np.any(negative):
        raise BadInputError(
            source,
            f"values contain {int(negative.sum())} negative value(s) (min {float(v[negative].min())!r}); "
            "mark missing samples with NaN",
        )
    return v


# --------------------------------------------------------------------------------------
# the tabulated BRDF
# --------------------------------------------------------------------------------------


class TableBRDF(MaskedTableBRDF):
    """rho(θ_i, θ_o, φ_d) on a rectilinear grid, trilinear in angle (data_specs/brdf_table.md).

    Attributes
    ----------
    theta_i, theta_o, phi_d
        The grid (radians, strictly increasing).
    values
        Shape (n_ti, n_to, n_pd, 3) RGB or (n_ti, n_to, n_pd) scalar, rho in 1/sr, NaN missing.
    n_missing
        Number of grid points with at least one channel missing.
    name, source, metadata
        Name, the file it came from (or ``None``), the metadata dictionary.
    """

    kind: Kind = "tabulated"

    def __init__(
        self,
        theta_i: np.ndarray,
        theta_o: np.ndarray,
        phi_d: np.ndarray,
        values: np.ndarray,
        *,
        name: str = "table",
        source: str | None = None,
        metadata: dict[str, Any] | None = None,
    ) -> None:
        where = source if source is not None else name
        self.theta_i = _check_axis(where, "theta_i", theta_i, np.pi / 2)
        self.theta_o = _check_axis(where, "theta_o", theta_o, np.pi / 2)
        self.phi_d = _check_axis(where, "phi_d", phi_d, np.pi)
        shape = (self.theta_i.size, self.theta_o.size, self.phi_d.size)
        self.values = _check_values(where, values, shape)
        grid = self.values if self.values.ndim == 4 else self.values[..., None]
        self.n_missing = int(np.any(np.isnan(grid), axis=-1).sum())
        self._interpolate = MissingAwareGrid(grid)
        self._ramps = [np.arange(g.size, dtype=np.float64) for g in (self.theta_i, self.theta_o, self.phi_d)]
        self.name = name
        self.source = source
        self.metadata = dict(metadata or {})

    def resolved_order(self) -> int | None:
        """The highest spherical-harmonic order F the table can resolve: ⌈2π / Δ⌉, Δ the finest
        spacing between two *measured* nodes along any axis (θ_i, θ_o, φ_d; the axis's own nodes
        where fewer than two are measured); None for a grid of one node per axis (a constant).
        Beyond it the spectrum is the trilinear interpolation's kinks and edges (a table holding
        one measured sample among 216 nodes sent the order search to F = 356 grids and never
        settled; issue 30). Used as a cap by :func:`~shrmkit.analysis.orders.choose_orders`. At most
        :data:`MAX_RESOLVED_ORDER` (nodes 5·10⁻³²⁴ rad apart made 2π / Δ infinite: an OverflowError)."""
        grid = self.values if self.values.ndim == 4 else self.values[..., None]
        measured = ~np.any(np.isnan(grid), axis=-1)  # (n_ti, n_to, n_pd)
        finest = np.inf
        for axis, nodes in enumerate((self.theta_i, self.theta_o, self.phi_d)):
            present = nodes[np.any(measured, axis=tuple(k for k in range(3) if k != axis))]
            present = present if present.size >= 2 else nodes  # fewer than two measured: the grid's own
            if present.size >= 2:
                finest = min(finest, float(np.min(np.diff(present))))
        if not np.isfinite(finest):
            return None
        with np.errstate(over="ignore", divide="ignore"):  # a subnormal spacing (5e-324 rad) overflows to inf
            order = 2.0 * np.pi / finest
        return int(np.ceil(order - 1e-9)) if order < MAX_RESOLVED_ORDER else MAX_RESOLVED_ORDER

    def index_coordinates(self, L: np.ndarray, V: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Continuous grid indices of (θ_i, θ_o, φ_d) for (N, 3) direction pairs above the surface.

        Piecewise-linear in angle between the grid nodes (``np.interp``), so the
        interpolation is trilinear in angle; φ_d = |φ_o − φ_i| folded into [0, π]
        (bilateral symmetry, data_specs/brdf_table.md).
        """
        theta_i, phi_i = spherical_angles(L)
        theta_o, phi_o = spherical_angles(V)
        phi = np.abs(np.mod(phi_o - phi_i + np.pi, 2.0 * np.pi) - np.pi)
        return (
            np.interp(theta_i, self.theta_i, self._ramps[0]),
            np.interp(theta_o, self.theta_o, self._ramps[1]),
            np.interp(phi, self.phi_d, self._ramps[2]),
        )


# --------------------------------------------------------------------------------------
# reader / writer
# --------------------------------------------------------------------------------------


def tabulate_table(
    brdf: BRDF, *, theta_i: np.ndarray, theta_o: np.ndarray, phi_d: np.ndarray
) -> np.ndarray:
    """rho of ``brdf`` at L = (θ_i, φ = 0), V = (θ_o, φ = φ_d) on the grid, shape (n_ti, n_to, n_pd, 3).

    Points where a tabulated source had no data are NaN (missing).
    """
    ti, to, pd = np.meshgrid(theta_i, theta_o, phi_d, indexing="ij")
    L = np.stack((np.sin(ti), np.zeros_like(ti), np.cos(ti)), axis=-1)
    V = np.stack((np.sin(to) * np.cos(pd), np.sin(to) * np.sin(pd), np.cos(to)), axis=-1)
    rho, has = eval_with_mask(brdf, L, V)
    return np.where(has[..., None], rho, np.nan)


def write_table(
    path: str | os.PathLike[str],
    brdf_or_values: BRDF | np.ndarray,
    *,
    theta_i: np.ndarray | None = None,
    theta_o: np.ndarray | None = None,
    phi_d: np.ndarray | None = None,
    provenance: str | None = None,
    name: str | None = None,
) -> Path:
    """Write a BRDF table (data_specs/brdf_table.md), atomically.

    Parameters
    ----------
    path
        Output ``.npz`` file.
    brdf_or_values
        A BRDF to tabulate on the grid (any kind that evaluates), or a values array of
        shape (n_ti, n_to, n_pd[, 3]) in 1/sr with NaN for missing samples. A
        :class:`TableBRDF` given without a grid is written on its own grid.
    theta_i, theta_o, phi_d
        The grid in radians, strictly increasing; θ in [0, π/2], φ_d in [0, π].
    provenance, name
        Free text stored in the metadata (defaults: the BRDF's name / the file stem).

    Raises
    ------
    BadInputError
        Missing or invalid grid, wrong shapes, negative or infinite values.
    """
    path = Path(path)
    grids = (theta_i, theta_o, phi_d)
    if isinstance(brdf_or_values, TableBRDF) and all(g is None for g in grids):
        # a table on its own grid: copy its samples (missing ones included) unchanged
        table = brdf_or_values
        theta_i, theta_o, phi_d = table.theta_i, table.theta_o, table.phi_d
        grids = (theta_i, theta_o, phi_d)
        name = name or table.name
        if provenance is None:
            provenance = table.metadata.get("provenance", f"copied from {table.source or table.name}")
        brdf_or_values = table.values
    if any(g is None for g in grids):
        raise BadInputError(path, "write_table needs the grid: theta_i, theta_o and phi_d (radians)")
    theta_i = _check_axis(path, "theta_i", theta_i, np.pi / 2)
    theta_o = _check_axis(path, "theta_o", theta_o, np.pi / 2)
    phi_d = _check_axis(path, "phi_d", phi_d, np.pi)
    if isinstance(brdf_or_values, BRDF):
        source_name = brdf_or_values.name
        values = tabulate_table(brdf_or_values, theta_i=theta_i, theta_o=theta_o, phi_d=phi_d)
    else:
        source_name = None
        values = brdf_or_values
    values = _check_values(path, values, (theta_i.size, theta_o.size, phi_d.size))
    metadata = {
        "format": TABLE_FORMAT,
        "format_version": TABLE_FORMAT_VERSION,
        "units": "1/sr",
        "quantity": "rho, the BRDF without the cosine factor",
        "grid": "rho(theta_i, theta_o, phi_d), radians; phi_d = |phi_o - phi_i| folded into [0, pi]",
        "channels": "rgb" if values.ndim == 4 else "scalar",
        "name": name or source_name or path.stem,
        "provenance": provenance if provenance is not None else (
            f"tabulated from {source_name}" if source_name else "values written by shrmkit"
        ),
    }

    with atomic_path(path) as tmp, tmp.open("wb") as f:
        np.savez_compressed(
            f, theta_i=theta_i, theta_o=theta_o, phi_d=phi_d, values=values,
            metadata=np.array(json.dumps(metadata)),
        )
    return path


def read_table(path: str | os.PathLike[str]) -> TableBRDF:
    """Read a BRDF table written by :func:`write_table` (data_specs/brdf_table.md).

    The archive is read through :func:`~shrmkit.brdf_io.npz_safe.read_npz`: each member's
    declared dtype, shape and size are checked against the limits
    (:mod:`~shrmkit.brdf_io.limits`) and the archive before anything is decompressed.

    Returns
    -------
    TableBRDF
        The grid (radians), the values (n_ti, n_to, n_pd[, 3]) in 1/sr with NaN missing,
        the metadata dictionary; ``name`` from the metadata (default: the file stem).

    Raises
    ------
    BadInputError
        Not a regular file, not a readable archive, missing keys, a member of the wrong
        dtype or a declared size over the limits or unlike the archive's, metadata that is
        not strict JSON or not of this format and version, an invalid grid, values that
        are negative, infinite or above :data:`MAX_TABLE_RHO`, no measured (non-NaN) sample
        at all or none above :data:`MIN_TABLE_PEAK_RHO`; a values member whose planned peak
        (:data:`TABLE_PEAK_BYTES_PER_VALUE` per value) is over ``SHRM_MAX_MEMORY_BYTES``
        (refused from its ``.npy`` header, before it is inflated).
    """
    path = Path(path)
    arrays = read_npz(path, _MEMBERS, what="a BRDF table")
    metadata = loads_strict(str(arrays["metadata"][()]), path, "metadata JSON")
    if not isinstance(metadata, dict) or metadata.get("format") != TABLE_FORMAT:
        raise BadInputError(path, f"metadata does not say format {TABLE_FORMAT!r}")
    version = metadata.get("format_version")
    if type(version) is not int or version != TABLE_FORMAT_VERSION:
        raise BadInputError(
            path, f"format_version {version!r} is not supported (this reader reads {TABLE_FORMAT_VERSION})"
        )
    if metadata.get("units") != "1/sr":
        raise BadInputError(path, f"units {metadata.get('units')!r}; expected '1/sr'")
    name = metadata.get("name")
    if not (isinstance(name, str) and 0 < len(name) <= _MAX_NAME and name.isprintable()):
        name = path.stem
    table = TableBRDF(
        arrays["theta_i"], arrays["theta_o"], arrays["phi_d"], arrays["values"],
        name=name,
        source=str(path),
        metadata=metadata,
    )
    nodes = table.theta_i.size * table.theta_o.size * table.phi_d.size
    if table.n_missing == nodes:  # it would evaluate to 0 everywhere, as if measured black
        raise BadInputError(path, f"all {nodes:,} grid points are missing (NaN): no measured sample to analyse")
    largest = float(np.nanmax(table.values))
    if not largest > MIN_TABLE_PEAK_RHO:
        raise BadInputError(
            path, f"the largest value is {largest!r} 1/sr, at most {MIN_TABLE_PEAK_RHO:g}: nothing a measurement "
            "can hold (an all-zero or underflowed table)",
        )
    return table
