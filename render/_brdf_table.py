"""A measured (or any) BRDF as a table texture on half/difference angles [Rus98] at MERL's spacing
[MERL03]: the grid (:func:`table_grid_for`), the tabulation (:func:`tabulate_brdf`), the texture's
lookup on the CPU (:func:`table_lookup`), its error on the lights' reflection (:func:`table_error`),
the coarsest grid within the target (:func:`choose_table`) and the θ_d rows a render's views can
read (:func:`theta_d_ranges`, :func:`theta_d_rows`). The shaders that read it: ``render.brdf_glsl``.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..analysis.lights import LightSet, light_radiance
from ..analysis.pairs import sample_pairs_focused
from ..analysis.reference import local_frames
from ..brdf_io.brdf import BRDF
from ..brdf_io.errors import BadInputError
from ..brdf_io.halfdiff import directions_to_halfdiff, halfdiff_to_directions
from ..brdf_io.merl import MerlBRDF

__all__ = [
    "TABLE_GRID",
    "BrdfTable",
    "table_angles",
    "table_grid_for",
    "tabulate_brdf",
    "table_lookup",
    "TABLE_COS_FLOOR",
    "TABLE_TARGET_REL_RMS",
    "TABLE_FACTORS",
    "scaled_grid",
    "atlas_texels",
    "choose_table",
    "table_light_radiance",
    "table_error",
    "THETA_D_MARGIN_ROWS",
    "theta_d_ranges",
    "theta_d_rows",
    "table_covers",
]



#: Default table grid (θ_h, θ_d, φ_d samples): MERL's spacing (90 θ_h steps on the square-root
#: scale, 1° in θ_d and φ_d) with both ends of every axis, so MERL's samples are texels.
TABLE_GRID = (91, 91, 181)


@dataclass(frozen=True, eq=False)
class BrdfTable:
    """ρ of a BRDF on a half/difference grid, as the texture ``brdf_table.glsl`` reads.

    Attributes
    ----------
    values
        float32 (NH, ND, NP, 3): ρ cos θ_L cos θ_V (1/sr) at θ_h = (i/(NH−1))² π/2,
        θ_d = j/(ND−1) π/2 and φ_d = k/(NP−1) π — or, ``periodic``, φ_d = k π/NP. Samples where L
        or V is below the surface hold the nearest sample above it along θ_d (the shader returns 0
        there; this only keeps interpolation near the horizon from blending in zeros). The cosines
        make the interpolated quantity bounded: an RGL material's ρ grows like 1/cos θ of one
        direction toward the horizon, and interpolating ρ itself spread a node's ρ at cos θ_L ≈ 0.001
        over its cell (lights near the horizon came out up to 24× too bright); a lookup divides by
        the actual cos θ_V (:func:`table_lookup`, ``brdf_table.glsl``).
    periodic
        φ_d folded into [0, π) by reciprocity, periodic (MERL's convention, ρ(φ_d) = ρ(φ_d + π):
        for MERL files, whose reader folds so); else into [0, π] by the mirror symmetry of an
        isotropic BRDF, |φ_d|, clamped.
    scale
        The texture holds ``values × scale`` (1 for float32 textures; a power of two for the
        page's half floats).
    missing
        Grid samples the BRDF had no data for (``eval_counted``) or gave NaN (set to 0); of a table
        tabulated in part (``rows``, ``tabulate_brdf(only=)``), among the samples evaluated only.
    seconds
        Time to tabulate.
    rows
        None: every texel tabulated. Else the table holds only what its views can read
        (:func:`choose_table`'s ``theta_d``): these θ_d rows, as inclusive (first, last) index runs,
        whole in θ_h and φ_d, and the texels its error pairs read; every other texel is 0 and no
        lookup from those views reads it.
    tabulated
        Texels tabulated (NH·ND·NP for a whole table).
    """

    values: np.ndarray
    scale: float = 1.0
    missing: int = 0
    seconds: float = 0.0
    periodic: bool = False
    rows: tuple[tuple[int, int], ...] | None = None
    tabulated: int = -1  # -1: every texel (set in __post_init__)

    def __post_init__(self) -> None:
        if self.tabulated < 0:
            object.__setattr__(self, "tabulated", int(np.prod(self.values.shape[:3])))

    @property
    def shape(self) -> tuple[int, int, int]:
        return tuple(int(n) for n in self.values.shape[:3])  # type: ignore[return-value]

    @property
    def cols(self) -> int:
        """Tiles (θ_h slices) per row of the atlas: the atlas as square as it gets."""
        nh, nd, npd = self.shape
        return max(1, min(nh, round(math.sqrt(nh * nd / npd))))  # as atlas_texels

    def atlas(self) -> np.ndarray:
        """float32 (rows·ND, cols·NP, 3): tile i (θ_h) at column (i mod cols)·NP, row (i div cols)·ND,
        φ_d along x and θ_d along y; values × scale."""
        nh, nd, npd = self.shape
        cols = self.cols
        rows = -(-nh // cols)
        out = np.zeros((rows * nd, cols * npd, 3), np.float32)
        for i in range(nh):
            r, c = divmod(i, cols)
            out[r * nd:(r + 1) * nd, c * npd:(c + 1) * npd] = self.values[i] * np.float32(self.scale)
        return out

    def with_values(self, values: np.ndarray, scale: float) -> BrdfTable:
        return dataclasses.replace(self, values=np.asarray(values, np.float32), scale=float(scale))


def table_angles(shape: tuple[int, int, int], periodic: bool = False) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(θ_h, θ_d, φ_d) of the table's samples, 1-D arrays (radians)."""
    nh, nd, npd = shape
    phi = np.arange(npd) * (np.pi / npd) if periodic else np.arange(npd) / max(npd - 1, 1) * np.pi
    return (np.arange(nh) / max(nh - 1, 1)) ** 2 * (np.pi / 2), np.arange(nd) / max(nd - 1, 1) * (np.pi / 2), phi


def table_grid_for(brdf: BRDF) -> tuple[tuple[int, int, int], bool]:
    """The default grid and φ_d fold of ``brdf``'s table: MERL's own samples for a MERL file
    (91 × 91 × 180, periodic: every sample of the file is a texel and the reader's trilinear
    interpolation is reproduced), :data:`TABLE_GRID` with the mirror fold otherwise."""
    if isinstance(brdf, MerlBRDF):
        return (TABLE_GRID[0], TABLE_GRID[1], TABLE_GRID[2] - 1), True
    return TABLE_GRID, False


def _source_rows(above: np.ndarray) -> np.ndarray:
    """For each sample (j, k) of a θ_h slice, the θ_d row whose value it holds (:class:`BrdfTable`):
    its own, or, past the last sample above the surface along θ_d in its φ_d column of ``above``
    (ND, NP), that last one."""
    nd, _ = above.shape
    has = np.asarray(above.any(axis=0))
    last = nd - 1 - np.argmax(above[::-1], axis=0)
    rows = np.arange(nd)[:, None]
    return np.where(has[None, :] & (rows > last[None, :]), last[None, :], rows)


def _rho_cos_cos(brdf: BRDF, L: np.ndarray, V: np.ndarray) -> tuple[np.ndarray, int]:
    """ρ cos θ_L cos θ_V (float64 (n, 3), what the table holds) at (n, 3) L, V, 0 where the BRDF has
    no data or gives NaN, and the count of those samples."""
    rho, none = brdf.eval_counted(L, V)
    rho = np.asarray(rho, dtype=np.float64).reshape(len(L), 3)
    bad = ~np.isfinite(rho)
    rho[bad] = 0.0
    rho *= (np.maximum(L[:, 2], 0.0) * np.maximum(V[:, 2], 0.0))[:, None]
    return rho, int(none) + int(np.any(bad, axis=-1).sum())


#: Samples evaluated per call by ``tabulate_brdf(only=)`` (at most about this many, 48 bytes each in L and V).
_EVAL_BATCH = 1 << 16


def tabulate_brdf(brdf: BRDF, shape: Sequence[int] | None = None, periodic: bool | None = None,
                  *, only: np.ndarray | None = None) -> BrdfTable:
    """ρ of ``brdf`` (its own ``eval``) on a half/difference grid (:class:`BrdfTable`); ``shape`` and
    ``periodic`` default to :func:`table_grid_for`.

    The texture holds ρ cos θ_L cos θ_V on Rusinkiewicz's half/difference angles [Rus98], θ_h on
    MERL's square-root scale [MERL03], φ_d folded by the mirror symmetry of an isotropic BRDF
    (ρ(φ_d) = ρ(−φ_d)); ``brdf_table.glsl`` interpolates it trilinearly in the indices and divides
    by cos θ_V (:func:`table_lookup`). The default grid (:data:`TABLE_GRID`) puts texels on MERL's
    own samples (a MERL file's values at its nodes).

    ``only``: a boolean (NH, ND, NP) mask of the samples wanted; the others are left 0 and the
    BRDF is evaluated only where the wanted ones read (a candidate grid's error needs the few
    samples its lookups touch, :func:`choose_table`); ``missing`` then counts those evaluations and
    ``tabulated`` the wanted samples.
    """
    default_shape, default_periodic = table_grid_for(brdf)
    shape = default_shape if shape is None else shape
    periodic = default_periodic if periodic is None else bool(periodic)
    nh, nd, npd = (int(n) for n in shape)
    if min(nh, nd, npd) < 2:
        raise BadInputError(getattr(brdf, "name", None), f"a BRDF table needs at least 2 samples an axis, got {shape}")
    t0 = time.perf_counter()
    th, td, pd = table_angles((nh, nd, npd), periodic)
    values = np.zeros((nh, nd, npd, 3), np.float32)
    missing = 0
    # only=: the samples of several slices evaluated in one call (a call costs ~ms in an RGL reader
    # whatever its size): (i, j, k, position of each wanted sample among the slice's evaluated, L, V)
    pending: list[tuple[int, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]] = []

    def evaluate() -> None:
        nonlocal missing
        rho, none = _rho_cos_cos(brdf, np.concatenate([p[4] for p in pending]), np.concatenate([p[5] for p in pending]))
        missing += none
        start = 0
        for i, j, k, position, Lp, _ in pending:
            values[i, j, k] = rho[start + position]
            start += len(Lp)
        pending.clear()

    for i in range(nh):  # one θ_h slice at a time: (ND·NP) evaluations
        if only is not None and not only[i].any():
            continue
        L, V = halfdiff_to_directions(th[i], td[:, None], pd[None, :])
        above = (L[..., 2] > 0.0) & (V[..., 2] > 0.0)
        if only is None:
            rho, none = _rho_cos_cos(brdf, L.reshape(-1, 3), V.reshape(-1, 3))
            missing += none
            rho = rho.reshape(nd, npd, 3)
            # below the surface: the nearest sample above it along θ_d (θ_d rises toward the horizon)
            values[i] = rho[_source_rows(above), np.arange(npd)]
            continue
        j, k = np.nonzero(only[i])
        source = _source_rows(above)[j, k] * npd + k  # flat index of the sample each wanted one holds
        evaluated = np.zeros(nd * npd, bool)
        evaluated[source] = True
        flat = np.flatnonzero(evaluated)  # each sample once (a fill row's source may be wanted too)
        position = np.zeros(nd * npd, np.intp)
        position[flat] = np.arange(flat.size)
        pending.append((i, j, k, position[source], L.reshape(-1, 3)[flat], V.reshape(-1, 3)[flat]))
        if sum(len(p[4]) for p in pending) >= _EVAL_BATCH:
            evaluate()
    if pending:
        evaluate()
    tabulated = -1 if only is None else int(np.count_nonzero(only))
    return BrdfTable(values, 1.0, missing, time.perf_counter() - t0, periodic, tabulated=tabulated)


def _lookup_corners(shape: tuple[int, int, int], periodic: bool, L: np.ndarray, V: np.ndarray):
    """The eight samples and weights of ``brdf_table.glsl``'s trilinear lookup at local (…, 3)
    directions: ((i0, i1), (j0, j1), (k0, k1)) index arrays and the fractions (fu, fv, fw)."""
    nh, nd, npd = shape
    th, td, pd = directions_to_halfdiff(L, V)

    def axis(x: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        x = np.clip(x, 0.0, n - 1)
        i0 = np.minimum(np.floor(x), max(n - 2, 0)).astype(np.intp)
        return i0, np.minimum(i0 + 1, n - 1), x - i0

    i0, i1, fu = axis((nh - 1) * np.sqrt(np.clip(th / (np.pi / 2), 0.0, 1.0)), nh)
    j0, j1, fv = axis((nd - 1) * td / (np.pi / 2), nd)
    if periodic:
        w = np.mod(pd, np.pi) * (npd / np.pi)
        k0 = np.minimum(np.floor(w).astype(np.intp), npd - 1)
        k1, fw = (k0 + 1) % npd, w - k0
    else:
        k0, k1, fw = axis((npd - 1) * np.abs(pd) / np.pi, npd)
    return (i0, i1), (j0, j1), (k0, k1), (fu, fv, fw)


def _lookup_mask(shape: tuple[int, int, int], periodic: bool, L: np.ndarray, V: np.ndarray) -> np.ndarray:
    """Boolean (NH, ND, NP) mask of the samples the lookups at (L, V) read."""
    (i0, i1), (j0, j1), (k0, k1), _ = _lookup_corners(shape, periodic, L, V)
    mask = np.zeros(shape, bool)
    for i in (i0, i1):
        for j in (j0, j1):
            for k in (k0, k1):
                mask[i, j, k] = True
    return mask


def table_lookup(table: BrdfTable, L: np.ndarray, V: np.ndarray) -> np.ndarray:
    """ρ̂ = ρ cos θ_L at local directions (..., 3) as ``brdf_table.glsl`` computes it: the table's
    ρ cos θ_L cos θ_V trilinear in the indices (φ_d folded as the table says) over max(V_z,
    :data:`TABLE_COS_FLOOR`); 0 unless L_z > 0 and V_z > 0; float64."""
    L, V = np.broadcast_arrays(np.asarray(L, np.float64), np.asarray(V, np.float64))
    vals = np.asarray(table.values, np.float64)
    (i0, i1), (j0, j1), (k0, k1), (fu, fv, fw) = _lookup_corners(table.shape, table.periodic, L, V)
    fu, fv, fw = fu[..., None], fv[..., None], fw[..., None]

    def lerp(a: np.ndarray, b: np.ndarray, t: np.ndarray) -> np.ndarray:
        return a * (1.0 - t) + b * t

    c00 = lerp(vals[i0, j0, k0], vals[i0, j0, k1], fw)
    c01 = lerp(vals[i0, j1, k0], vals[i0, j1, k1], fw)
    c10 = lerp(vals[i1, j0, k0], vals[i1, j0, k1], fw)
    c11 = lerp(vals[i1, j1, k0], vals[i1, j1, k1], fw)
    rho = lerp(lerp(c00, c01, fv), lerp(c10, c11, fv), fu)
    above = (L[..., 2] > 0.0) & (V[..., 2] > 0.0)
    return np.where(above[..., None], rho / np.maximum(V[..., 2], TABLE_COS_FLOOR)[..., None], 0.0)


#: Smallest cos θ_V a table lookup divides by (``brdf_table.glsl`` the same).
TABLE_COS_FLOOR = 1e-6


#: The table's resolution is chosen by its error: the coarsest of the grids :data:`TABLE_FACTORS` ×
#: the default whose error on the lights' reflection (:func:`table_error`) is at most this in every
#: view band; the finest when none is.
TABLE_TARGET_REL_RMS = 0.01
#: Fractions of the default grid's spacing tried, coarse to fine (1: :func:`table_grid_for`).
TABLE_FACTORS = (1.0 / 3.0, 0.5, 2.0 / 3.0, 1.0)


def scaled_grid(shape: tuple[int, int, int], factor: float, periodic: bool) -> tuple[int, int, int]:
    """``shape`` with ``factor`` × the samples per axis (both ends kept; a periodic φ_d axis scales
    its count)."""
    nh, nd, npd = shape
    clamp = [max(2, round((n - 1) * factor) + 1) for n in (nh, nd)]
    last = max(2, round(npd * factor)) if periodic else max(2, round((npd - 1) * factor) + 1)
    return clamp[0], clamp[1], last


def atlas_texels(shape: tuple[int, int, int]) -> int:
    """Texels of the 2-D atlas of a table of ``shape`` (:meth:`BrdfTable.atlas`, tiles padded)."""
    nh, nd, npd = shape
    cols = max(1, min(nh, round(math.sqrt(nh * nd / npd))))
    return -(-nh // cols) * nd * cols * npd


#: θ_d rows tabulated beyond those a view can read, on each side (:func:`theta_d_rows`): the shader
#: computes θ_d in float32 from an interpolated surface point, a hair off the exact value; one row
#: (1° at the default grid) is ~10⁴ times that.
THETA_D_MARGIN_ROWS = 1


def theta_d_ranges(directions: np.ndarray, cones: Sequence[tuple[np.ndarray, float]]) -> np.ndarray:
    """The θ_d a render can look up: float64 (n_lights · n_cones, 2) [lo, hi] in radians.

    θ_d = ½ ∠(L, V) [Rus98] does not depend on the surface normal. For a light direction L
    ((n_lights, 3) ``directions``, the frame the lookups are made in) and views V within the cone
    of half-angle a about the unit axis A (``cones``: (A, a), a in radians, e.g.
    ``Camera.view_cone``), the triangle inequality on the sphere gives, with γ = ∠(L, A),
    ∠(L, V) ∈ [max(γ − a, 0), min(γ + a, π)]; row c·n_lights + k is light k in cone c.
    """
    L = np.asarray(directions, np.float64).reshape(-1, 3)
    L = L / np.linalg.norm(L, axis=1, keepdims=True)
    out = []
    for axis, half_angle in cones:
        a = np.asarray(axis, np.float64).reshape(3)
        gamma = np.arccos(np.clip(L @ (a / np.linalg.norm(a)), -1.0, 1.0))
        out.append(np.stack([0.5 * np.maximum(gamma - half_angle, 0.0),
                             0.5 * np.minimum(gamma + half_angle, np.pi)], axis=1))
    return np.concatenate(out) if out else np.zeros((0, 2))


def theta_d_rows(ranges: np.ndarray, nd: int, margin: int = THETA_D_MARGIN_ROWS) -> np.ndarray:
    """Boolean (``nd``,): the θ_d rows of an ``nd``-row table that lookups at θ_d within ``ranges``
    ((n, 2) [lo, hi] radians, :func:`theta_d_ranges`) read, ``margin`` more on each side.

    A lookup at v = (ND − 1) θ_d / (π/2) reads rows j0 = min(⌊v⌋, ND − 2) and j0 + 1
    (``brdf_table.glsl``, :func:`table_lookup`): over [v_lo, v_hi], rows min(⌊v_lo⌋, ND − 2) to
    ⌊v_hi⌋ + 1, clipped to the table.
    """
    rows = np.zeros(int(nd), bool)
    v = np.asarray(ranges, np.float64).reshape(-1, 2) * ((nd - 1) / (np.pi / 2))
    for lo, hi in v:
        first = min(math.floor(lo), nd - 2) - margin
        last = math.floor(hi) + 1 + margin
        rows[max(first, 0):max(min(last, nd - 1) + 1, 0)] = True
    return rows


def _runs(mask: np.ndarray) -> tuple[tuple[int, int], ...]:
    """The inclusive (first, last) index runs of the True entries of a 1-D boolean mask."""
    edges = np.flatnonzero(np.diff(np.concatenate([[0], mask.astype(np.int8), [0]])))
    return tuple((int(a), int(b) - 1) for a, b in zip(edges[::2], edges[1::2], strict=True))


def table_covers(table: BrdfTable, theta_d: np.ndarray | None) -> bool:
    """Whether ``table`` holds every texel lookups at θ_d within ``theta_d`` ((n, 2) radians,
    :func:`theta_d_ranges`; None: any θ_d) read, :data:`THETA_D_MARGIN_ROWS` included: a whole
    table always, one tabulated for some views (``rows``) when those rows include them."""
    if table.rows is None:
        return True
    if theta_d is None:
        return False
    have = np.zeros(table.shape[1], bool)
    for first, last in table.rows:
        have[first:last + 1] = True
    return bool(np.all(have[theta_d_rows(theta_d, table.shape[1])]))


def choose_table(brdf: BRDF, lights: LightSet, *, max_view_deg: float = 80.0, max_texels: int | None = None,
                 target: float = TABLE_TARGET_REL_RMS, shape: tuple[int, int, int] | None = None,
                 store: Callable[[BrdfTable], BrdfTable] | None = None,
                 theta_d: np.ndarray | None = None) -> tuple[BrdfTable, dict[str, Any]]:
    """The table of ``brdf`` for ``lights`` and its measured error (:func:`table_error`).

    Grids :data:`TABLE_FACTORS` × the default (:func:`table_grid_for`) are tried coarse to fine,
    those whose atlas has over ``max_texels`` texels left out (if none fits, a coarser grid that
    does), and the first whose
    worst view band is within ``target`` is taken, else the finest tried; ``shape`` forces one grid.
    ``store`` maps a table to what the texture will hold (e.g. half-float rounding) before its
    error is measured. The error dict adds ``target`` and ``grids_tried``.

    A candidate's error is measured on the samples its lookups read, evaluated alone
    (``tabulate_brdf(only=)``): only the grid taken is tabulated whole, and its error is measured
    again on the whole table as stored.

    ``theta_d``: None (default), the whole table; else (n, 2) [lo, hi] radians, the θ_d the renders
    can look up (:func:`theta_d_ranges` of their lights and views): the grid taken holds only those
    rows (:func:`theta_d_rows`, margin included) and the texels the error pairs read, the rest 0
    (``BrdfTable.rows``, ``tabulated``), so that the error is the whole table's, to the bit; ``missing``
    counts the samples evaluated. Not with ``store`` (whose rounding may depend on every texel).

    Raises
    ------
    ValueError
        ``theta_d`` and ``store`` both given.
    """
    if theta_d is not None and store is not None:
        raise ValueError("choose_table: theta_d (a table for some views) and store (a page's texture) together")
    base, periodic = table_grid_for(brdf)
    grids: list[tuple[int, int, int]] = [shape] if shape is not None else list(dict.fromkeys(
        scaled_grid(base, f, periodic) for f in TABLE_FACTORS))
    if max_texels is not None and shape is None:
        fitting = [g for g in grids if atlas_texels(g) <= max_texels]
        factor = TABLE_FACTORS[0]
        while not fitting and factor > 1e-3:  # coarser still, until the atlas fits
            factor *= 0.9
            grid = scaled_grid(base, factor, periodic)
            fitting = [grid] if atlas_texels(grid) <= max_texels or min(grid) <= 2 else []
        grids = fitting
    pairs = _ErrorPairs(brdf, lights, max_view_deg=max_view_deg)
    tried = []
    for n, grid in enumerate(grids):
        tried.append(list(grid))
        if n < len(grids) - 1:  # a candidate that may not be taken: only the samples its error reads
            sparse = tabulate_brdf(brdf, grid, periodic, only=_lookup_mask(grid, periodic, *pairs.local))
            if pairs.error(store(sparse) if store is not None else sparse)["worst_band_rel_rms"] > target:
                continue
        break
    taken: tuple[int, int, int] = (tried[-1][0], tried[-1][1], tried[-1][2])
    rows = None if theta_d is None else theta_d_rows(theta_d, taken[1])
    if rows is None or rows.all():
        table = tabulate_brdf(brdf, taken, periodic)
    else:  # the rows the views read, and the texels of the error pairs (its error the whole table's)
        wanted = _lookup_mask(taken, periodic, *pairs.local)
        wanted[:, rows, :] = True
        table = dataclasses.replace(tabulate_brdf(brdf, taken, periodic, only=wanted), rows=_runs(rows))
    if store is not None:
        table = store(table)
    return table, {**pairs.error(table), "target": float(target), "grids_tried": tried}


def table_light_radiance(table: BrdfTable, lights: LightSet, R: np.ndarray, V: np.ndarray) -> np.ndarray:
    """Σ_k ρ̂_table(ω_k; V, N) E_k at (n, 3) R and V, N = normalize(R + V): the lights' reflection as
    the table texture gives it (:func:`table_lookup` in the frame of N, as ``light_radiance``)."""
    L_loc, V_loc = _local_light_directions(lights, R, V)
    return np.einsum("knc,nc->kc", table_lookup(table, L_loc, V_loc), lights.power)


def _local_light_directions(lights: LightSet, R: np.ndarray, V: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The lights' directions and V in the frame of N = normalize(R + V), each (n_pairs, n_lights, 3)."""
    frames = local_frames(R + V)
    L_loc = np.einsum("kij,nj->kni", frames, lights.directions)
    V_loc = np.broadcast_to(np.einsum("kij,kj->ki", frames, V)[:, None, :], L_loc.shape)
    return L_loc, V_loc


class _ErrorPairs:
    """The (R, V) pairs of :func:`table_error`, with the exact reflection of the lights on them
    (computed once for every table measured on them)."""

    def __init__(self, brdf: BRDF, lights: LightSet, *, max_view_deg: float = 80.0, per_band: int = 64,
                 seed: int = 0) -> None:
        self.lights, self.max_view_deg = lights, float(max_view_deg)
        self.edges = np.linspace(0.0, float(max_view_deg), max(2, int(math.ceil(max_view_deg / 10.0)) + 1))
        centres = np.array([light.direction for light in lights.lights]) if lights.lights else lights.directions
        R, V, theta_v, self.w = sample_pairs_focused(per_band, self.edges, centre=centres, seed=seed)
        self.exact = light_radiance(brdf, lights.directions, lights.power, R, V)
        self.local = _local_light_directions(lights, R, V)
        self.band = np.clip(np.searchsorted(np.radians(self.edges), theta_v, side="right") - 1, 0,
                            len(self.edges) - 2)

    def error(self, table: BrdfTable) -> dict[str, float]:
        got = np.einsum("knc,nc->kc", table_lookup(table, *self.local), self.lights.power)
        err = self.w * ((got - self.exact) ** 2).sum(axis=1)
        sig = self.w * (self.exact**2).sum(axis=1)
        per = [math.sqrt(err[self.band == b].sum() / sig[self.band == b].sum()) if sig[self.band == b].sum() > 0
               else 0.0 for b in range(len(self.edges) - 1)]
        total = math.sqrt(err.sum() / sig.sum()) if sig.sum() > 0 else 0.0
        return {"rel_rms": total, "worst_band_rel_rms": max(per), "pairs": int(len(self.w)),
                "max_view_deg": self.max_view_deg}


def table_error(table: BrdfTable, brdf: BRDF, lights: LightSet, *, max_view_deg: float = 80.0,
                per_band: int = 64, seed: int = 0) -> dict[str, float]:
    """The table's own error on the lights' reflection, against the BRDF's ``eval``.

    On (R, V) pairs focused on the lights (``analysis.pairs.sample_pairs_focused``: R in caps
    about the lights, θ_v uniform in angle in 10° bands up to ``max_view_deg``, importance
    weights), the relative RMS of Σ_k ρ̂_table E_k − Σ_k ρ̂ E_k (``analysis.lights.light_radiance``)
    over the RMS of the latter: ``rel_rms`` over all pairs and ``worst_band_rel_rms``, the
    largest per band; ``pairs`` counts them.
    """
    return _ErrorPairs(brdf, lights, max_view_deg=max_view_deg, per_band=per_band, seed=seed).error(table)
