"""The [DJ18] tables' interpolants: bilinear tables and the inverse VNDF warp (Mitsuba ``Marginal2D``).

An RGL material stores its tables on unit squares, one slice per measured incident elevation:
:class:`_Bilinear` interpolates such a table (bilinear in the square, linear between slices,
clamped outside them) and :class:`_InverseWarp` inverts the continuous marginal/conditional
sampling map of a bilinear density, which takes a half vector's unit coordinates to the warped
square the RGB table lives on. Per-patch quantities are kept as contiguous columns (structure of
arrays) so that a gather per quantity is cheap. :mod:`.rgl` evaluates the material with them;
the formulas are in ``data_specs/rgl_bsdf.md``, "The VNDF warp" and "Evaluation".

Reference: [DJ18]; [Mitsuba3] ``include/mitsuba/core/distr_2d.h`` (``Marginal2D``, continuous
variant). Citation keys: ``data_specs/bibliography.md``.
"""

from __future__ import annotations

import numpy as np


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


def _unit(*ws: np.ndarray) -> tuple[np.ndarray, ...]:
    """The (N, 3) arrays (no zero rows) scaled to unit length."""
    out = []
    for w in ws:
        w = np.asarray(w, dtype=np.float64).reshape(-1, 3)
        a = np.abs(w)
        w = w / np.maximum(np.maximum(a[:, 0], a[:, 1]), a[:, 2])[:, None]  # to O(1) first: no underflow
        out.append(w / np.sqrt(np.einsum("ij,ij->i", w, w))[:, None])
    return tuple(out)
