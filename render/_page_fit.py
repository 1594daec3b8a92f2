"""The view page's size budget (:class:`ViewBudget`) and its rule for the coefficient maps
(:func:`fit_coefficients`): the (rows, P) of least estimated error that fits, by solid-angle area
resampling and bilinear lookups on equal-area directions (``data_specs/view_html.md``), both as
row-banded products in numpy (:class:`_Banded`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..brdf_io.errors import BadInputError
from ..brdf_io.latlong import bilinear_corners, row_edges_cos
from .defaults import DEFAULT_PAGE_BYTES
from .shader import atlas_layout


@dataclass(frozen=True)
class ViewBudget:
    """Size limits of a page (``data_specs/view_html.md``, Size budget).

    Attributes
    ----------
    page_bytes
        The whole HTML page, UTF-8 (default 8 MiB). The coefficient maps get what the rest
        leaves.
    mesh_bytes
        Raw vertex and index data of the mesh (float32 positions and normals, uint16/uint32
        indices; default 1 MiB, about 45 000 triangles); larger meshes are decimated.
    env_rows
        Rows of the background environment (halved until at most this; default 256).
    still_size
        Width and height of the still image in pixels (default 384).
    max_edge
        Largest edge of the coefficient atlas in texels (default 2048, the WebGL2 minimum of
        MAX_TEXTURE_SIZE, so that every WebGL2 implementation can hold it).
    min_rows
        The coefficient maps are never halved below this many rows (default 8).
    brdf_bytes
        The table of a measured BRDF that shades the lights (base64 of half floats; default
        1.5 MiB, at most a quarter of ``page_bytes``): the finest grid within it whose error meets
        the target, or the coarsest (``render.brdf_glsl.choose_table``).
    """

    page_bytes: int = DEFAULT_PAGE_BYTES
    mesh_bytes: int = 1 << 20
    env_rows: int = 256
    still_size: int = 384
    max_edge: int = 2048
    min_rows: int = 8
    brdf_bytes: int = 3 << 19

    def __post_init__(self) -> None:
        for name, lo in (("page_bytes", 64 << 10), ("mesh_bytes", 4096), ("env_rows", 2), ("still_size", 16),
                         ("max_edge", 64), ("min_rows", 2), ("brdf_bytes", 4096)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < lo:
                raise BadInputError(None, f"ViewBudget.{name} must be an integer >= {lo}, got {value!r}")


@dataclass(frozen=True, eq=False)
class CoefficientFit:
    """What :func:`fit_coefficients` kept.

    Attributes
    ----------
    coeffs
        float32 ((P+1)², h, w, 3): the coefficient maps the page stores (before half rounding).
    P
        The view order kept.
    source_shape
        (P, H, W) of the SHRM given.
    added_rel_rms
        Estimated relative RMS error the reduction adds over all (R, V) pairs (0 when nothing
        was reduced): sqrt(error energy / energy) of the maps, the error energy being the
        squared difference between the bilinear lookups of the kept maps and of the given ones,
        integrated over R (equal-area samples), plus the whole energy of the view bands dropped
        (the real SH are orthonormal in V, so these add up over V).
    """

    coeffs: np.ndarray
    P: int
    source_shape: tuple[int, int, int]
    added_rel_rms: float = 0.0

    @property
    def reduced(self) -> bool:
        return (self.P, self.coeffs.shape[1], self.coeffs.shape[2]) != self.source_shape



class _Banded:
    """A matrix with a few entries a row, ``out[i] = Σ_j weight[i, j] · x[index[i, j]]`` over the
    entries of nonzero weight, summed in increasing j from the first product: the arithmetic, in
    that order, of SciPy's CSR product with the row's entries sorted by column (the view page
    imports no SciPy: ~0.3–0.4 s CPU of every report and ``shrm view``). Only the ``stored`` entries
    count, those SciPy's matrix would hold: padding and merged duplicates are skipped, so an
    infinite value they point at does not become 0 · inf = NaN.

    ``index`` (rows, band) int, ``weight`` (rows, band), ``stored`` (rows, band) bool; ``dtype``:
    the products' type."""

    def __init__(self, index: np.ndarray, weight: np.ndarray, stored: np.ndarray,
                 dtype: type = np.float64) -> None:
        self.index: np.ndarray = index
        self.stored: np.ndarray = stored
        self.weight: np.ndarray = weight.astype(dtype)
        self.dtype = dtype

    def __matmul__(self, x: np.ndarray) -> np.ndarray:
        """(rows, ...) product with ``x`` (n, ...), in ``dtype`` (only the rows read are converted)."""
        x = np.asarray(x)
        shape = (-1,) + (1,) * (x.ndim - 1)
        if self.stored[:, 0].all():
            out = np.multiply(x[self.index[:, 0]], self.weight[:, 0].reshape(shape), dtype=self.dtype)
            first = 1
        else:
            out = np.zeros((self.index.shape[0], *x.shape[1:]), dtype=self.dtype)
            first = 0
        term = np.empty_like(out)
        for j in range(first, self.index.shape[1]):
            on = self.stored[:, j]
            if on.all():
                np.multiply(x[self.index[:, j]], self.weight[:, j].reshape(shape), out=term, dtype=self.dtype)
                out += term
            elif on.any():
                out[on] += np.multiply(x[self.index[on, j]], self.weight[on, j].reshape(shape), dtype=self.dtype)
        return out


def _overlap(src: np.ndarray, dst: np.ndarray, dtype: type = np.float32) -> _Banded:
    """(len(dst)−1, len(src)−1) matrix of the fraction of each destination interval covered by
    each source interval; ``src`` and ``dst`` are increasing edges of the same range. Each row's
    entries are one run of columns (the intervals it overlaps)."""
    lo = np.maximum(dst[:-1, None], src[None, :-1])
    hi = np.minimum(dst[1:, None], src[None, 1:])
    m = np.maximum(hi - lo, 0.0) / (dst[1:] - dst[:-1])[:, None]
    nonzero = m > 0.0
    first = np.argmax(nonzero, axis=1)
    count = nonzero.sum(axis=1)
    band = max(1, int(count.max()))
    index = np.minimum(first[:, None] + np.arange(band)[None, :], m.shape[1] - 1)
    inside = np.arange(band)[None, :] < count[:, None]
    rows = np.arange(m.shape[0])[:, None]
    # csr_matrix(m) stores the nonzero entries only
    return _Banded(np.where(inside, index, first[:, None]), np.where(inside, m[rows, index], 0.0), inside, dtype)


def _area_resample(maps: np.ndarray, h: int, w: int, chunk: int = 16) -> np.ndarray:
    """(n, H, W, 3) lat-long maps → (n, h, w, 3): each new pixel the solid-angle-weighted mean of
    the old pixels it overlaps (rows weighted in 1 − cos θ, columns in φ)."""
    n, H, W, _ = maps.shape
    # in float32, the maps' type (means of a few texels): half the memory traffic of float64
    rows = _overlap(1.0 - row_edges_cos(H), 1.0 - row_edges_cos(h))  # (h, H)
    cols = _overlap(np.linspace(0.0, 1.0, W + 1), np.linspace(0.0, 1.0, w + 1))  # (w, W)
    out = np.empty((n, h, w, 3), np.float32)
    for s in range(0, n, chunk):
        block = np.asarray(maps[s:s + chunk], np.float32)
        k = block.shape[0]
        by_row = rows @ np.moveaxis(block, 1, 0).reshape(H, -1)  # (h, k·W·3)
        by_row = np.moveaxis(by_row.reshape(h, k, W, 3), 2, 0).reshape(W, -1)  # (W, h·k·3)
        both = (cols @ by_row).reshape(w, h, k, 3)
        out[s:s + k] = np.transpose(both, (2, 1, 0, 3))
    return out


def _sphere_samples(n: int) -> np.ndarray:
    """n unit vectors of a Fibonacci lattice: equal-area samples of the sphere, (n, 3)."""
    k = np.arange(n) + 0.5
    z = 1.0 - 2.0 * k / n
    phi = np.pi * (3.0 - np.sqrt(5.0)) * k
    r = np.sqrt(np.maximum(1.0 - z * z, 0.0))
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=-1)


def _lookup_matrix(dirs: np.ndarray, height: int, width: int) -> _Banded:
    """(N, H·W) matrix of the bilinear lookup (``brdf_io.latlong.bilinear_lookup``) of an H × W
    lat-long map at unit vectors (N, 3): four weights a row, summing to 1, in float64. Entries of a
    row on the same texel (θ clamped at a pole, or one column wide) are one entry, their weights
    summed in column order, as a sparse matrix built from the four would hold them (a merged
    duplicate's slot keeps weight 0 and is skipped)."""
    y0, y1, x0, x1, fy, fx = bilinear_corners(dirs, height, width)
    cols = np.stack([y0 * width + x0, y0 * width + x1, y1 * width + x0, y1 * width + x1], axis=1)
    weights = np.stack([(1 - fy) * (1 - fx), (1 - fy) * fx, fy * (1 - fx), fy * fx], axis=1)
    order = np.argsort(cols, axis=1, kind="stable")
    cols, weights = np.take_along_axis(cols, order, axis=1), np.take_along_axis(weights, order, axis=1)
    repeat = np.zeros(cols.shape, dtype=bool)
    repeat[:, 1:] = cols[:, 1:] == cols[:, :-1]  # sorted: a texel's entries are neighbours
    head = np.maximum.accumulate(np.where(repeat, 0, np.arange(4)[None, :]), axis=1)  # its first slot
    merged = weights.copy()
    rows = np.arange(len(cols))
    for j in range(1, 4):  # the weights of a texel summed in order into its first slot
        on = repeat[:, j]
        merged[rows[on], head[on, j]] += weights[on, j]
        merged[on, j] = 0.0
    return _Banded(cols, merged, ~repeat)  # a bilinear weight of 0 is stored, as SciPy's COO → CSR keeps it


def _lookup(maps: np.ndarray, dirs: np.ndarray, chunk: int = 16) -> np.ndarray:
    """Bilinear lookups (N, n, 3) float32 of (n, h, w, 3) maps at unit vectors (N, 3): one banded
    product (float64, as SciPy's sparse product promoted it) per chunk of maps laid out (h·w, k·3)."""
    n, h, w, _ = maps.shape
    matrix = _lookup_matrix(dirs, h, w)
    out = np.empty((len(dirs), n, 3), np.float32)
    for s in range(0, n, chunk):
        block = np.ascontiguousarray(np.moveaxis(maps[s:s + chunk], 0, 2)).reshape(h * w, -1)
        out[:, s:s + chunk] = (matrix @ block).reshape(len(dirs), -1, 3)
    return out


def _squared_difference(maps: np.ndarray, dirs: np.ndarray, given: np.ndarray, chunk: int = 2048) -> float:
    """Σ over directions, maps and channels of (lookup of ``maps`` at ``dirs`` − ``given``)², a chunk of
    directions at a time: the (N, n, 3) lookups of the whole set and their difference are not held
    (2 × 18 MB for a P = 18 SHRM at 4096 directions)."""
    total = 0.0
    for s in range(0, len(dirs), chunk):
        diff = _lookup(maps, dirs[s:s + chunk]) - given[s:s + chunk]
        total += float(np.einsum("snc,snc->", diff, diff, dtype=np.float64))
    return total


def _atlas_fits(P: int, h: int, w: int, max_bytes: int, max_edge: int) -> bool:
    cols, rows = atlas_layout((P + 1) ** 2)
    return rows * h * cols * w * 6 <= max_bytes and max(rows * h, cols * w) <= max_edge


def fit_coefficients(
    coeffs: np.ndarray, P: int, max_bytes: int, *, max_edge: int = 2048, min_rows: int = 8, samples: int = 4096
) -> CoefficientFit:
    """The SHRM's coefficient maps at the (rows, P) of least estimated error within ``max_bytes``:
    the page's budget rule (the maps get what the rest of :attr:`ViewBudget.page_bytes` leaves;
    the page states a reduction in a visible note).

    The maps ((P+1)², H, W, 3) are stored as a half-float RGB atlas (6 bytes a texel, tiles as
    (:func:`~shrmkit.render.shader.coefficient_atlas`) whose edges must not exceed ``max_edge``. Candidates:
    for each P' ≤ P, the largest number of rows h ≤ H (at least ``min_rows``, width in the
    same proportion) whose atlas fits, the maps resampled to it by solid-angle-weighted area
    means. Each candidate's error energy (:class:`CoefficientFit`) is estimated on ``samples``
    equal-area directions R (a Fibonacci lattice): the squared difference of the bilinear
    lookups of the resampled and the given maps, plus the energy of the dropped maps (the real
    SH are orthonormal in V); the least wins, ties to the larger P'. Candidates are tried from
    P' = P down and the search stops at the first whose dropped energy alone is no less than the
    best error found (it and every smaller P' lose). Nothing is computed beyond a size check
    when the maps fit as they are.

    Raises
    ------
    BadInputError
        When not even one map of ``min_rows`` rows fits.
    """
    n, H, W, _ = coeffs.shape
    if n != (P + 1) ** 2:
        raise ValueError(f"coeffs must have (P+1)^2 = {(P + 1) ** 2} maps, got {n}")
    source = (P, H, W)

    def width(h: int) -> int:
        return max(1, round(h * W / H))

    def rows_for(p: int) -> int:
        cols, rows = atlas_layout((p + 1) ** 2)
        h = min(H, int(math.sqrt(max_bytes / (6.0 * cols * rows * W / H))) + 1, max_edge // rows)
        while h > 0 and not _atlas_fits(p, h, width(h), max_bytes, max_edge):
            h -= 1
        return h

    if _atlas_fits(P, H, W, max_bytes, max_edge):
        return CoefficientFit(np.asarray(coeffs, np.float32), P, source)
    dirs = _sphere_samples(samples)
    given = _lookup(coeffs, dirs)
    weight = 4.0 * np.pi / samples
    energy = weight * np.einsum("snc,snc->n", given, given, dtype=np.float64)
    total = float(energy.sum())
    best: tuple[float, int, np.ndarray] | None = None
    for p in range(P, -1, -1):
        h = rows_for(p)
        if h < min_rows:
            continue
        m = (p + 1) ** 2
        dropped = float(energy[m:].sum())  # a lower bound of this candidate's error, growing as p falls
        if best is not None and dropped >= best[0]:
            break  # neither this P' nor any smaller one can win (ties go to the larger P')
        if h >= H:
            maps, err = np.asarray(coeffs[:m], np.float32), dropped
        else:
            maps = _area_resample(coeffs[:m], h, width(h))
            err = weight * _squared_difference(maps, dirs, given[:, :m]) + dropped
        if best is None or err < best[0]:
            best = (err, p, maps)
        if h >= H:
            break  # a smaller P' at full resolution only drops more
    if best is None:
        raise BadInputError(None, f"the SHRM does not fit the page budget: even one {min_rows}-row map "
                            f"needs more than {max_bytes} bytes")
    err, p, maps = best
    rel = math.sqrt(err / total) if total > 0 else 0.0
    return CoefficientFit(np.ascontiguousarray(maps), p, source, rel)
