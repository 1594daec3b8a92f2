"""Tabulated BRDFs with missing samples: the interpolation and evaluation that the MERL
reader (:mod:`~shrmkit.brdf_io.merl`) and the ``.npz`` table reader
(:mod:`~shrmkit.brdf_io.table`) share.

A tabulated BRDF stores rho on a regular *index* grid of three coordinates (half/difference
angles for MERL, (θ_i, θ_o, φ_d) for the table format) with NaN where a sample is missing.
It evaluates in three steps, the first of which is the only one that differs between
formats:

1. map each query (L, V) with both directions above the surface to continuous index
   coordinates (:meth:`MaskedTableBRDF.index_coordinates`);
2. interpolate trilinearly over the present corners of the enclosing cell, renormalizing
   the weights (:class:`MissingAwareGrid`);
3. return rho and the mask of the queries that had data (:meth:`MaskedTableBRDF.eval_masked`);
   below-surface queries give 0 and count as having data.

Public objects: :class:`MaskedTableBRDF`, :class:`MissingAwareGrid`,
:func:`interpolate_excluding_missing`, :func:`eval_with_mask`, :func:`flatten_directions`,
:data:`EVAL_BLOCK`.

References
----------
data_specs/merl_binary.md and data_specs/brdf_table.md (sections "Interpolation" and
"Evaluation").
"""

from __future__ import annotations

import numpy as np

from .brdf import BRDF, as_directions

__all__ = [
    "EVAL_BLOCK",
    "MaskedTableBRDF",
    "MissingAwareGrid",
    "eval_with_mask",
    "flatten_directions",
    "interpolate_excluding_missing",
]

EVAL_BLOCK = 1 << 15  # query points per block: the temporaries stay in cache


def _axis_corners(t: np.ndarray, n: int, periodic: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Lower/upper sample index and the fraction towards the upper one, for continuous
    index coordinates ``t`` on an axis of ``n`` samples (clamped, or wrapped if periodic)."""
    if periodic:
        t = np.mod(t, n)
        i0 = np.minimum(np.floor(t).astype(np.intp), n - 1)  # mod can round up to n
        return i0, (i0 + 1) % n, t - i0
    t = np.clip(t, 0.0, n - 1)
    i0 = np.minimum(np.floor(t).astype(np.intp), max(n - 2, 0))
    return i0, np.minimum(i0 + 1, n - 1), t - i0


class MissingAwareGrid:
    """Trilinear interpolation on an index grid that ignores missing (NaN) samples.

    The value at continuous index coordinates (t0, t1, t2) is
    Σ_c w_c v_c / Σ_c w_c over the 8 corners c of the enclosing cell whose sample is
    present (w_c the trilinear weight), separately per channel; with all corners present
    this is plain trilinear interpolation. Coordinates outside [0, n−1] are clamped to the
    edge, or wrapped modulo n on a periodic axis (there sample n−1 neighbours sample 0).

    Parameters
    ----------
    grid
        Samples, shape (n0, n1, n2, C), NaN where missing.
    periodic
        Which axes wrap around.
    """

    def __init__(self, grid: np.ndarray, periodic: tuple[bool, bool, bool] = (False, False, False)) -> None:
        grid = np.asarray(grid, dtype=np.float64)
        if grid.ndim != 4:
            raise ValueError(f"grid must have shape (n0, n1, n2, C), got {grid.shape}")
        self.shape = grid.shape[:3]
        self.n_channels = grid.shape[3]
        self.periodic = tuple(bool(p) for p in periodic)
        n2 = self.shape[2]
        k = np.arange(n2)
        upper = (k + 1) % n2 if self.periodic[2] else np.minimum(k + 1, n2 - 1)
        # one row per sample: its C values and those of its upper neighbour on the last
        # axis (the neighbour _axis_corners pairs it with), so that one gather fetches both
        # corners of a cell edge; NaN marks a missing sample
        self._pairs = np.concatenate((grid, grid[:, :, upper]), axis=-1).reshape(-1, 2 * self.n_channels)

    def __call__(self, coords: tuple[np.ndarray, np.ndarray, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
        """Interpolate at continuous index coordinates (three finite arrays of shape (N,)).

        Returns
        -------
        values, no_data
            ``values`` (N, C), 0 where a channel had no present corner of positive weight;
            ``no_data`` (N,) bool, true where some channel had none.
        """
        flat = [np.asarray(t, dtype=np.float64).ravel() for t in coords]
        count = flat[0].shape[0]
        values = np.empty((count, self.n_channels))
        no_data = np.empty(count, dtype=bool)
        # blocks small enough for the temporaries to stay in cache
        for start in range(0, count, EVAL_BLOCK):
            block = slice(start, start + EVAL_BLOCK)
            values[block], no_data[block] = self._interpolate_block([t[block] for t in flat])
        return values, no_data

    def _interpolate_block(self, coords: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
        n0, n1, n2 = self.shape
        axes = [_axis_corners(t, n, p) for t, n, p in zip(coords, self.shape, self.periodic, strict=True)]
        (lo0, hi0, f0), (lo1, hi1, f1), (lo2, _, f2) = axes
        rows0 = (lo0 * n1, hi0 * n1)
        w0 = (1.0 - f0, f0)
        w1 = (1.0 - f1, f1)
        n_ch = self.n_channels
        count = f0.shape[0]
        total = np.zeros((count, 2 * n_ch))
        weight_sum = np.zeros((count, 2 * n_ch))
        weight = np.empty((count, 2 * n_ch))
        for a in (0, 1):
            for b in (0, 1):
                # columns: the C channels at lo2, then the C channels at its upper neighbour
                pair = np.take(self._pairs, (rows0[a] + (lo1, hi1)[b]) * n2 + lo2, axis=0)
                wab = w0[a] * w1[b]
                weight[:, :n_ch] = (wab * (1.0 - f2))[:, None]
                weight[:, n_ch:] = (wab * f2)[:, None]
                missing = np.isnan(pair)
                np.copyto(weight, 0.0, where=missing)
                np.copyto(pair, 0.0, where=missing)
                weight_sum += weight
                pair *= weight
                total += pair
        total = total[:, :n_ch] + total[:, n_ch:]
        weight_sum = weight_sum[:, :n_ch] + weight_sum[:, n_ch:]
        has = weight_sum > 0
        values = np.where(has, total / np.where(has, weight_sum, 1.0), 0.0)
        return values, ~np.all(has, axis=1)


def interpolate_excluding_missing(
    grid: np.ndarray,
    coords: tuple[np.ndarray, np.ndarray, np.ndarray],
    periodic: tuple[bool, bool, bool] = (False, False, False),
) -> tuple[np.ndarray, np.ndarray]:
    """One-shot :class:`MissingAwareGrid` ``(grid, periodic)(coords)``."""
    return MissingAwareGrid(grid, periodic)(coords)


def eval_with_mask(brdf: BRDF, L: np.ndarray, V: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """rho(L, V) and a bool mask of the points that had data (all true for models)."""
    if hasattr(brdf, "eval_masked"):
        return brdf.eval_masked(L, V)
    rho = np.asarray(brdf.eval(L, V), dtype=np.float64)
    return rho, np.ones(rho.shape[:-1], dtype=bool)


def flatten_directions(L: np.ndarray, V: np.ndarray) -> tuple[np.ndarray, np.ndarray, tuple[int, ...]]:
    """Broadcast direction arrays and flatten them to (N, 3); also return the batch shape."""
    L, V = as_directions(L, V)
    shape = L.shape[:-1]
    L, V = L.reshape(-1, 3), V.reshape(-1, 3)
    if not (np.all(np.isfinite(L)) and np.all(np.isfinite(V))):
        raise ValueError("directions must be finite")
    return L, V, shape


class MaskedTableBRDF(BRDF):
    """A tabulated BRDF on a :class:`MissingAwareGrid` that says where it had data.

    A subclass sets ``self._interpolate`` (a :class:`MissingAwareGrid` of shape
    (n0, n1, n2, C), C = 3 or 1: a scalar table broadcasts to the three channels) and
    implements :meth:`index_coordinates`; ``eval_masked``, ``eval_counted`` and ``eval``
    derive from them.
    """

    _interpolate: MissingAwareGrid

    def index_coordinates(self, L: np.ndarray, V: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Continuous grid index coordinates (three (N,) arrays) of N direction pairs
        (N, 3) with both directions above the surface."""
        raise NotImplementedError

    def eval_masked(self, L: np.ndarray, V: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(rho (..., 3), has_data (...)); rho is 0 below the surface and without data.

        Below-surface points are 0 and count as having data (rho is 0 there by definition).
        """
        L, V, shape = flatten_directions(L, V)
        out = np.zeros((L.shape[0], 3))
        has = np.ones(L.shape[0], dtype=bool)
        above = np.flatnonzero((L[:, 2] > 0) & (V[:, 2] > 0))
        for start in range(0, above.size, EVAL_BLOCK):
            sel = above[start : start + EVAL_BLOCK]
            values, no_data = self._interpolate(self.index_coordinates(L[sel], V[sel]))
            out[sel] = values
            has[sel] = ~no_data
        return out.reshape(*shape, 3), has.reshape(shape)

    def eval_counted(self, L: np.ndarray, V: np.ndarray) -> tuple[np.ndarray, int]:
        """rho and the number of above-surface query points with no present sample near."""
        rho, has = self.eval_masked(L, V)
        return rho, int(np.sum(~has))

    def eval(self, L: np.ndarray, V: np.ndarray) -> np.ndarray:
        """rho(L, V) in 1/sr, (..., 3); 0 below the surface and where no sample is present."""
        return self.eval_masked(L, V)[0]
