"""The view page's size budget (:class:`ViewBudget`) and its rule for the coefficient maps
(:func:`fit_coefficients`): the (rows, P) of least estimated error that fits, by solid-angle area
resampling and bilinear lookups on equal-area directions (``data_specs/view_html.md``), both as
row-banded products in numpy (:class:`_Banded`): gathers of long contiguous runs, the maps of a
chunk held texel-major (:func:`_texel_major`) where texels are gathered.
"""

from __future__ import annotations

import heapq
import math
from collections.abc import Callable, Mapping
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

    def along(self, x: np.ndarray, axis: int) -> np.ndarray:
        """The product along ``axis`` of ``x``: ``x.shape`` with ``rows`` entries on ``axis``, in
        ``dtype`` (only the entries read are converted, each exactly). One gather (``np.take``) and
        one weighted add a band slot, in ``x``'s own layout: fast where ``x``'s entries past
        ``axis`` are long contiguous runs."""
        x = np.asarray(x)
        shape = [1] * x.ndim
        shape[axis] = -1
        out_shape = list(x.shape)
        out_shape[axis] = self.index.shape[0]
        gathered = np.empty(out_shape, x.dtype)
        term = gathered if x.dtype == self.dtype else np.empty(out_shape, self.dtype)
        out: np.ndarray | None = None
        for j in range(self.index.shape[1]):
            on = self.stored[:, j]
            if on.all():
                np.take(x, self.index[:, j], axis=axis, out=gathered, mode="clip")  # "clip": not buffered
                if term is not gathered:
                    np.copyto(term, gathered)  # exact; faster than the product's own cast
                if out is None:
                    out = np.multiply(term, self.weight[:, j].reshape(shape))
                else:
                    term *= self.weight[:, j].reshape(shape)
                    out += term
                continue
            if out is None:
                out = np.zeros(out_shape, self.dtype)
            if on.any():
                sel = np.flatnonzero(on)
                at = (slice(None),) * axis + (sel,)
                out[at] += np.multiply(np.take(x, self.index[sel, j], axis=axis),
                                       self.weight[sel, j].reshape(shape), dtype=self.dtype)
        assert out is not None
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


def _texel_major(block: np.ndarray) -> np.ndarray:
    """(k, h, w, 3) maps → (h·w, 3·k): a texel's values of every map one contiguous row (channel,
    then map), the layout in which gathering texels moves long runs (a 2-D transpose)."""
    k, h, w, _ = block.shape
    return np.ascontiguousarray(np.asarray(block).reshape(k, -1).T).reshape(h * w, 3 * k)


def _map_major(texels: np.ndarray, h: int, w: int) -> np.ndarray:
    """The inverse of :func:`_texel_major`: (h·w, 3·k) → (k, h, w, 3)."""
    k = texels.shape[1] // 3
    return np.ascontiguousarray(texels.reshape(h * w * 3, k).T).reshape(k, h, w, 3)


class _AreaResample:
    """The solid-angle area means of H × W lat-long maps on h × w pixels (:func:`_area_resample`):
    the row and column overlap matrices, built once for every block of maps."""

    def __init__(self, H: int, W: int, h: int, w: int) -> None:
        self.H, self.W, self.h, self.w = H, W, h, w
        # in float32, the maps' type (means of a few texels): half the memory traffic of float64
        self.rows = _overlap(1.0 - row_edges_cos(H), 1.0 - row_edges_cos(h))  # (h, H)
        self.cols = _overlap(np.linspace(0.0, 1.0, W + 1), np.linspace(0.0, 1.0, w + 1))  # (w, W)

    def texels(self, block: np.ndarray) -> np.ndarray:
        """(k, H, W, 3) → (h·w, 3·k) float32 (:func:`_texel_major`): the rows first, whole rows of
        W·3 values gathered from each map; then, texel-major, the columns, runs of 3·k values."""
        k = block.shape[0]
        by_row = self.rows.along(np.asarray(block, np.float32).reshape(k, self.H, self.W * 3), 1)
        by_row = _texel_major(by_row.reshape(k, self.h, self.W, 3)).reshape(self.h, self.W, 3 * k)
        return self.cols.along(by_row, 1).reshape(self.h * self.w, 3 * k)


def _area_resample(maps: np.ndarray, h: int, w: int, chunk: int = 16) -> np.ndarray:
    """(n, H, W, 3) lat-long maps → (n, h, w, 3): each new pixel the solid-angle-weighted mean of
    the old pixels it overlaps (rows weighted in 1 − cos θ, columns in φ)."""
    n, H, W, _ = maps.shape
    resample = _AreaResample(H, W, h, w)
    out = np.empty((n, h, w, 3), np.float32)
    for s in range(0, n, chunk):
        out[s:s + chunk] = _map_major(resample.texels(maps[s:s + chunk]), h, w)
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


def _lookup(texels: np.ndarray, matrix: _Banded, out: np.ndarray | None = None) -> np.ndarray:
    """Bilinear lookups (N, 3·k) float32 of k maps held texel-major (h·w, 3·k)
    (:func:`_texel_major`) by their grid's :func:`_lookup_matrix` (N rows): the products in float64,
    as SciPy's sparse product promoted them, rounded to float32 once (into ``out`` when given: any
    float32 array of N · 3·k values in that order, e.g. a strided view)."""
    looked = matrix.along(texels, 0)
    if out is None:
        return looked.astype(np.float32)
    out[...] = looked.reshape(out.shape)
    return out


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
    SH are orthonormal in V); the least wins, ties to the larger P'. The candidates are P' = P
    down to the first at full resolution (every smaller P' drops more for no gain); each one's
    maps are measured from the first only until its error passes the least found
    (:func:`_least_error`, the same choice and error as measuring each whole), and candidates of
    the same rows share their maps' errors. Nothing is computed beyond a size check when the maps
    fit as they are.

    Raises
    ------
    BadInputError
        When not even one map of ``min_rows`` rows fits, or when the maps must be reduced and
        hold NaN or infinite values.
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
    if not (np.isfinite(np.max(coeffs)) and np.isfinite(np.min(coeffs))):
        # a NaN or inf texel makes every resampled candidate's error NaN: the choice would be the NaN's
        raise BadInputError(None, "the SHRM's coefficient maps hold NaN or infinite values: they cannot be "
                            "fitted to the page budget")
    dirs = _sphere_samples(samples)
    y0, _, x0, _, _, _ = bilinear_corners(dirs, H, W)
    dirs = dirs[np.argsort(y0 * W + x0, kind="stable")]  # the same set, the texels read in memory order
    matrix = _lookup_matrix(dirs, H, W)
    given = np.empty((samples, 3, n), np.float32)  # the given maps' lookups, texel-major as the work's
    for s in range(0, n, _CHUNK):
        block = coeffs[s:s + _CHUNK]
        _lookup(_texel_major(block), matrix, out=given[:, :, s:s + len(block)])
    weight = 4.0 * np.pi / samples
    energy = weight * np.einsum("scn,scn->n", given, given, dtype=np.float64)
    total = float(energy.sum())
    candidates: dict[int, tuple[int, int, float]] = {}  # P' → (rows, maps kept, energy of the maps dropped)
    for p in range(P, -1, -1):
        h = rows_for(p)
        if h < min_rows:
            continue
        candidates[p] = (h, (p + 1) ** 2, float(energy[(p + 1) ** 2:].sum()))
        if h >= H:
            break  # a smaller P' at full resolution only drops more
    if not candidates:
        raise BadInputError(None, f"the SHRM does not fit the page budget: even one {min_rows}-row map "
                            f"needs more than {max_bytes} bytes")
    work = _WorkByRows(coeffs, given, dirs, width)
    p = _least_error(candidates, work, H, weight)
    h, m, dropped = candidates[p]
    if h >= H:
        maps, err = np.asarray(coeffs[:m], np.float32), dropped
    else:
        maps, err = work[h].maps(m), weight * work[h].squared(m) + dropped
    rel = math.sqrt(err / total) if total > 0 else 0.0
    return CoefficientFit(np.ascontiguousarray(maps), p, source, rel)


#: Maps resampled and looked up together: their texel-major rows (3·16 float64 values) long runs,
#: the float64 lookups of a chunk (4096 × 48 × 8 bytes) about one core's L2 cache.
_CHUNK = 16


class _RowsWork:
    """The given maps resampled to h × w (:class:`_AreaResample`) and the squared differences of
    their lookups from the given maps' lookups ``given`` (N, 3, n) at ``dirs``, summed over
    directions and channels: map by map from the first, as far as :meth:`advance` was asked. A
    map's error does not depend on P', so the candidates with h rows share this work."""

    def __init__(self, coeffs: np.ndarray, given: np.ndarray, dirs: np.ndarray, h: int, w: int) -> None:
        self.coeffs, self.given, self.h, self.w = coeffs, given, h, w
        self.resample = _AreaResample(coeffs.shape[1], coeffs.shape[2], h, w)
        self.lookup = _lookup_matrix(dirs, h, w)
        self.done = 0
        self._texels: list[np.ndarray] = []
        self._errors: list[np.ndarray] = []
        self._cumulative = np.zeros(1)

    def advance(self, stop: int) -> None:
        """Resample and measure the maps up to ``stop`` (exclusive), :data:`_CHUNK` at a time."""
        for s in range(self.done, stop, _CHUNK):
            texels = self.resample.texels(self.coeffs[s:min(s + _CHUNK, stop)])
            k = texels.shape[1] // 3
            # the products in float64 from maps converted once (fewer values than the gathered ones)
            looked = _lookup(texels.astype(np.float64), self.lookup).reshape(-1, 3, k)
            diff = looked - self.given[:, :, s:s + k]
            self._errors.append(np.einsum("sck,sck->k", diff, diff, dtype=np.float64))
            self._texels.append(texels)
        self.done = max(self.done, stop)
        # summed in map order: the sum of the first d maps never exceeds that of the first m ≥ d
        self._cumulative = np.concatenate([[0.0], np.cumsum(np.concatenate(self._errors))])

    def squared(self, d: int) -> float:
        """The squared differences of the first ``d`` maps (at most :attr:`done`), summed."""
        return float(self._cumulative[d])

    def maps(self, m: int) -> np.ndarray:
        """The first ``m`` maps resampled (at most :attr:`done`), (m, h, w, 3) float32."""
        return np.concatenate([_map_major(t, self.h, self.w) for t in self._texels])[:m]


class _WorkByRows(dict[int, _RowsWork]):
    """The :class:`_RowsWork` of each number of rows, made when first asked for (a candidate whose
    energy dropped alone loses costs nothing); ``width(h)``: the columns at h rows."""

    def __init__(self, coeffs: np.ndarray, given: np.ndarray, dirs: np.ndarray, width: Callable[[int], int]) -> None:
        super().__init__()
        self.coeffs, self.given, self.dirs, self.width = coeffs, given, dirs, width

    def __missing__(self, h: int) -> _RowsWork:
        self[h] = work = _RowsWork(self.coeffs, self.given, self.dirs, h, self.width(h))
        return work


def _least_error(candidates: dict[int, tuple[int, int, float]], work: Mapping[int, _RowsWork], full_rows: int,
                 weight: float) -> int:
    """The P' of least error ``weight`` · (squared differences of its maps) + (energy dropped), ties
    to the larger P', among ``candidates`` (P' → (rows, maps, energy dropped); candidates of
    ``full_rows`` err by the energy dropped alone). A best-first search: the
    candidate of least lower bound (the error of its first d maps, growing with d; ties to the
    larger P') measures its next maps (d → 2d, at least 4) until the least is one measured whole,
    whose error is then no more than any other's bound, so no more than any other's error: the
    argmin that measuring every candidate whole gives, from a fraction of the maps. An error that is
    not a number (maps holding NaN or inf) orders as +inf: such a candidate never wins over one with
    a number, and when none has one the largest P' wins, as the sequential rule gave."""

    def key(error: float) -> float:
        return math.inf if math.isnan(error) else error

    heap = [(key(dropped), -p, m if h >= full_rows else 0) for p, (h, m, dropped) in candidates.items()]
    heapq.heapify(heap)
    while True:
        _, negative_p, d = heapq.heappop(heap)
        h, m, dropped = candidates[-negative_p]
        if d == m:
            return -negative_p
        rows = work[h]
        if rows.done <= d:
            rows.advance(min(m, max(4, 2 * d)))
        d = min(rows.done, m)  # further when a candidate of the same rows went further
        heapq.heappush(heap, (key(weight * rows.squared(d) + dropped), negative_p, d))
