"""Checks of an RGL file's fields and tables: dtype, axes, finite values, grid sizes, shapes, densities.

Each check raises :class:`BadInputError` naming the file and the field; :mod:`.rgl` (the reader
and ``RGLBRDF``) and :mod:`._rgl_anisotropy` (the refusal of anisotropic files) share them. The
rules are in ``data_specs/rgl_bsdf.md``, "Fields".
"""

from __future__ import annotations

import numpy as np

from .errors import BadInputError


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


def _checked_tables(
    where: object, theta_i: object, ndf: object, sigma: object, vndf: object, rgb: object
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The tables of :class:`RGLBRDF` as float64, checked: finite, θ_i strictly increasing in
    [0, π/2], 2-D grids of at least 2 x 2, shapes that agree, densities ≥ 0 and σ > 0."""
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
    return theta_i, ndf, sigma, vndf, rgb


def _expect(source: object, fields: dict[str, np.ndarray], name: str, dtype: str, ndim: int) -> np.ndarray:
    a = fields[name]
    if a.dtype != np.dtype(dtype):
        raise BadInputError(source, f"field {name!r} has dtype {a.dtype.name}, expected {np.dtype(dtype).name}")
    if a.ndim != ndim:
        raise BadInputError(source, f"field {name!r} has shape {a.shape}, expected {ndim} axes")
    return a
