"""The [DJ18] tables' interpolants: bilinear tables and the inverse VNDF warp (Mitsuba ``Marginal2D``).

An RGL material stores its tables on unit squares, one slice per measured incident elevation:
:class:`_Bilinear` interpolates such a table (bilinear in the square, linear between slices,
clamped outside them) and :class:`_InverseWarp` inverts the continuous marginal/conditional
sampling map of a bilinear density, which takes a half vector's unit coordinates to the warped
square the RGB table lives on. A patch's quantities (its corners' values, the warp's sums) are
kept together in one row of a table (array of structures), so that one gather per parameter
slice fetches them all from one or two cache lines; the arithmetic keeps the order of operations
of the formulas below, so the values do not depend on the layout (bit for bit). :mod:`.rgl`
evaluates the material with them; the formulas are in ``data_specs/rgl_bsdf.md``, "The VNDF
warp" and "Evaluation".

Reference: [DJ18]; [Mitsuba3] ``include/mitsuba/core/distr_2d.h`` (``Marginal2D``, continuous
variant). Citation keys: ``data_specs/bibliography.md``.
"""

from __future__ import annotations

import numpy as np


def _theta_to_u(theta: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """Elevation θ ∈ [0, π/2] -> unit coordinate sqrt(θ / (π/2)) (denser near the pole);
    written into ``out`` (which may be ``theta``) when given."""
    if out is None:
        return np.sqrt(np.maximum(theta, 0.0) * (2.0 / np.pi))
    np.maximum(theta, 0.0, out=out)
    out *= 2.0 / np.pi
    return np.sqrt(out, out=out)


def _phi_to_u(phi: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """Azimuth φ -> unit coordinate (φ + π)/2π, wrapped into [0, 1); written into ``out``
    (which may be ``phi``) when given."""
    if out is None:
        u = (phi + np.pi) * (0.5 / np.pi)
        return u - np.floor(u)
    np.add(phi, np.pi, out=out)
    out *= 0.5 / np.pi
    out -= np.floor(out)
    return out


def _clip01(x: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """``x`` clipped to [0, 1], into ``out`` (default: in place); the ufuncs themselves, without
    ``np.clip``'s Python layers (several µs a call, and a block makes a dozen calls)."""
    out = x if out is None else out
    np.maximum(x, 0.0, out=out)
    return np.minimum(out, 1.0, out=out)


def _param_weights(grid: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Lower/upper grid index and the weight of the upper one for linear interpolation in
    a sorted 1-D parameter grid; clamped (constant) outside the grid."""
    n = grid.size
    if n == 1:
        zero = np.zeros(x.shape, dtype=np.intp)
        return zero, zero, np.zeros(x.shape)
    lo = np.searchsorted(grid, x, side="right")
    lo -= 1
    np.maximum(lo, 0, out=lo)
    np.minimum(lo, n - 2, out=lo)
    w = np.subtract(x, np.take(grid, lo))
    w /= np.take(grid[1:] - grid[:-1], lo)
    _clip01(w)
    return lo, lo + 1, w


def _cells(u: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Patch index (0..n−2) and fraction of unit coordinates u on an axis of n vertices
    spanning [0, 1]; u is clamped to [0, 1]."""
    t = _clip01(u, np.empty(u.shape))
    t *= n - 1
    i = t.astype(np.intp)
    np.minimum(i, n - 2, out=i)
    t -= i
    return i, t


def _patch_rows(cols: list[np.ndarray]) -> np.ndarray:
    """(n_patches, n_cols) contiguous float64: one row per patch holding its per-patch quantities
    (array of structures: one gather of whole rows fetches a patch's quantities from one or two
    cache lines, 2-3x faster than a gather per quantity from separate columns)."""
    return np.ascontiguousarray(np.stack([np.ravel(c) for c in cols], axis=-1), dtype=np.float64)


def _gather(rows: np.ndarray, slice_size: int, cell: np.ndarray,
            param: tuple[np.ndarray, np.ndarray, np.ndarray] | None) -> np.ndarray:
    """The per-patch quantities (rows of ``rows``, :func:`_patch_rows`) at the patches ``cell`` (N,):
    (N, n_cols), linear between the parameter slices ``lo`` and ``hi`` of ``param`` with weight
    ``w`` of ``hi``, (1 − w)·v_lo + w·v_hi; ``param=None``: a table of one slice."""
    if param is None:
        return np.take(rows, cell, axis=0)
    lo, hi, w = param
    at = lo * slice_size
    at += cell
    out = np.take(rows, at, axis=0)
    if (w > 0).any():
        np.multiply(hi, slice_size, out=at)
        at += cell
        upper = np.take(rows, at, axis=0)
        upper *= w[:, None]
        out *= (1.0 - w)[:, None]
        out += upper
    return out


class _Bilinear:
    """Bilinear interpolation of vertex values on [0, 1]², linear between parameter slices.

    ``values`` has shape (T, H, W, C): T parameter slices, H rows (the y coordinate), W
    columns (x, fastest), C channels; vertex (j, i) sits at (x, y) = (i/(W−1), j/(H−1)).
    A table whose rows are all equal (``ndf`` and ``sigma`` of an isotropic file) is interpolated
    in x only: the bilinear formula's y term (top − bottom)·fy is then exactly 0, so the values are
    the same, for half the work.
    """

    def __init__(self, values: np.ndarray) -> None:
        T, H, W, C = values.shape
        self.shape = (H, W)
        self._channels = C
        self._constant_in_y = bool(np.all(values == values[:, :1]))
        if self._constant_in_y:
            values = values[:, :2]
        # per patch: the C values of its corners (0,0), (1,0), (0,1), (1,1) (x, y), corner-major;
        # (0,0), (1,0) only when constant in y
        corners = [values[:, :-1, :-1], values[:, :-1, 1:], values[:, 1:, :-1], values[:, 1:, 1:]]
        del corners[2 if self._constant_in_y else 4:]
        self._rows = _patch_rows([corner[..., c] for corner in corners for c in range(C)])
        self._slice = self._rows.shape[0] // T

    def __call__(
        self, x: np.ndarray, y: np.ndarray, param: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
    ) -> np.ndarray:
        """Values (N, C) at points (x, y) (N,) of the unit square; ``param``: the slices and the weight
        of the upper one (:func:`_param_weights`), ``None`` for a table of one slice."""
        return np.stack(self.columns(x, y, param), axis=-1)

    def columns(
        self, x: np.ndarray, y: np.ndarray, param: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
    ) -> list[np.ndarray]:
        """As ``__call__``, one contiguous (N,) array per channel."""
        H, W = self.shape
        cell, fx = _cells(x, W)
        if not self._constant_in_y:
            j, fy = _cells(y, H)
            cell += j * (W - 1)
        v = _gather(self._rows, self._slice, cell, param)
        C = self._channels
        out = []
        for c in range(C):  # strided columns of v, one channel at a time (faster than (N, C) blocks)
            v00, v10 = v[:, c], v[:, C + c]
            bottom = v10 - v00  # v00 + (v10 − v00)·fx
            bottom *= fx
            bottom += v00
            if not self._constant_in_y:
                v01, v11 = v[:, 2 * C + c], v[:, 3 * C + c]
                top = v11 - v01  # v01 + (v11 − v01)·fx
                top *= fx
                top += v01
                top -= bottom  # bottom + (top − bottom)·fy
                top *= fy
                bottom += top
            out.append(bottom)
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
        self._rows = _patch_rows(cols)
        self._slice = (H - 1) * (W - 1)

    def __call__(
        self, x: np.ndarray, y: np.ndarray, param: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """The warped sample (s_x, s_y), each (N,) in [0, 1], of points (x, y) (N,) of the unit
        square; ``param`` as for :class:`_Bilinear`."""
        H, W = self.shape
        i, fx = _cells(x, W)
        j, fy = _cells(y, H)
        j *= W - 1
        j += i
        v = _gather(self._rows, self._slice, j, param)
        v00, v10, v01, v11, c0, c1, r0, r1, m0 = (v[:, k] for k in range(9))
        # density along the patch's left and right edges at y: left = v00 + (v01 − v00)·fy, right alike
        left = v01 - v00
        left *= fy
        left += v00
        right = v11 - v10
        right *= fy
        right += v10
        # ∫_0^fx of the density along the row at y, in patch widths: fx·(left + (right − left)·fx/2)/(W − 1)
        half = 0.5 * fx
        partial = right
        partial -= left
        partial *= half
        partial += left
        partial *= fx
        partial /= W - 1
        dr = r1 - r0
        row = dr * fy  # the row total at y: r0 + (r1 − r0)·fy
        row += r0
        has_mass = row > 0
        sx = c1 - c0  # (c0 + (c1 − c0)·fy + partial) / row
        sx *= fy
        sx += c0
        sx += partial
        sx /= np.where(has_mass, row, 1.0)
        sx = np.where(has_mass, sx, x)  # a row without mass: the identity (no data to warp by)
        sy = dr  # m0 + fy·(r0 + (r1 − r0)·fy/2)/(H − 1)
        sy *= np.multiply(0.5, fy, out=half)
        sy += r0
        sy *= fy
        sy /= H - 1
        sy += m0
        return _clip01(sx), _clip01(sy)


def _normalized(x: np.ndarray, y: np.ndarray, z: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The vectors with components x, y, z (each (N,), no zero vector) scaled to unit length, as
    three new contiguous arrays. Scaled to O(1) by the largest component first (no underflow);
    the squares are summed as (x² + z²) + y², the order numpy's ``einsum("ij,ij->i")`` uses for
    (N, 3) rows, so the result is bit-identical to that form."""
    m = np.maximum(np.abs(x), np.abs(y))
    np.maximum(m, np.abs(z), out=m)
    x, y, z = x / m, y / m, z / m
    norm = np.multiply(x, x, out=m)
    norm += z * z
    norm += y * y
    np.sqrt(norm, out=norm)
    x /= norm
    y /= norm
    z /= norm
    return x, y, z


def _unit(*ws: np.ndarray) -> tuple[np.ndarray, ...]:
    """The (N, 3) arrays (no zero rows) scaled to unit length (:func:`_normalized`)."""
    out = []
    for w in ws:
        w = np.asarray(w, dtype=np.float64).reshape(-1, 3)
        out.append(np.stack(_normalized(w[:, 0], w[:, 1], w[:, 2]), axis=-1))
    return tuple(out)
