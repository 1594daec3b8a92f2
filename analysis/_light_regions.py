"""The bright regions of a lat-long map, pixel by pixel: their labelling (8-neighbours, across the
φ seam and around the poles), pixel directions and rings, the map's median luminance, and the
median cut of a region into samples [Debevec05]. Used by :func:`shrmkit.analysis.lights.extract_lights`.
"""

from __future__ import annotations

import numpy as np

from ..brdf_io.exr import luminance_weights
from .components import grid_labels


def _median_luminance(Y: np.ndarray, row_omega: np.ndarray) -> float:
    """The solid-angle-weighted median of the luminance, on the map area-averaged to at most 256
    rows (a robust level of the sky or the room; sorting a 2-Mpixel map for it is not needed)."""
    factor = 1
    while Y.shape[0] % (2 * factor) == 0 and Y.shape[1] % (2 * factor) == 0 and Y.shape[0] // factor > 256:
        factor *= 2
    h, w = Y.shape[0] // factor, Y.shape[1] // factor
    weighted = (Y.astype(np.float64) * row_omega[:, None]).reshape(h, factor, w, factor).sum(axis=(1, 3))
    omega = row_omega.reshape(h, factor).sum(axis=1) * factor
    values = weighted / omega[:, None]
    order = np.argsort(values, axis=None)
    cumulative = np.cumsum(np.repeat(omega, w)[order])
    return float(values.ravel()[order][np.searchsorted(cumulative, 0.5 * cumulative[-1])])


def _label_indices(labels: np.ndarray, n: int) -> list[np.ndarray]:
    """Flat pixel indices of each label 1..n, in one pass."""
    flat = labels.ravel()
    nonzero = np.flatnonzero(flat)
    order = nonzero[np.argsort(flat[nonzero], kind="stable")]
    bounds = np.searchsorted(flat[order], np.arange(1, n + 2))
    return [order[bounds[k] : bounds[k + 1]] for k in range(n)]


def _directions(rows: np.ndarray, cols: np.ndarray, height: int, width: int) -> np.ndarray:
    """Unit pixel-centre directions (DESIGN §2) of the pixels (rows, cols), (m, 3)."""
    theta = (rows + 0.5) * np.pi / height
    phi = 2.0 * np.pi * (cols + 0.5) / width
    s = np.sin(theta)
    return np.stack([s * np.cos(phi), s * np.sin(phi), np.cos(theta)], axis=-1)


def _ring(rows: np.ndarray, cols: np.ndarray, height: int, width: int) -> tuple[np.ndarray, np.ndarray]:
    """The 8-neighbours of the pixels (rows, cols) that are not among them (periodic in φ)."""
    dr, dc = np.meshgrid([-1, 0, 1], [-1, 0, 1], indexing="ij")
    r = (rows[:, None] + dr.ravel()[None, :]).ravel()
    c = ((cols[:, None] + dc.ravel()[None, :]) % width).ravel()
    ok = (r >= 0) & (r < height)
    key = np.unique(r[ok].astype(np.int64) * width + c[ok])
    own = rows.astype(np.int64) * width + cols
    key = key[~np.isin(key, own)]
    return key // width, key % width


def _components(mask: np.ndarray) -> tuple[np.ndarray, int]:
    """Connected regions of a lat-long mask, 8-neighbours, joined across the φ seam and, for regions
    touching the first or last row, around the pole. Labels 1..n."""
    labels, n = grid_labels(mask)
    if n == 0:
        return labels, 0
    parent = np.arange(n + 1)

    def find(a: int) -> int:
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    def union(a: int, b: int) -> None:
        if a and b:
            ra, rb = find(a), find(b)
            if ra != rb:
                parent[max(ra, rb)] = min(ra, rb)

    height = mask.shape[0]
    for i in range(height):  # the seam: column W−1 neighbours column 0 in rows i−1..i+1
        for di in (-1, 0, 1):
            if 0 <= i + di < height:
                union(int(labels[i, -1]), int(labels[i + di, 0]))
    for row in (0, height - 1):  # a pole: every pixel of the first (last) row touches it
        touching = np.unique(labels[row][labels[row] > 0])
        for a in touching[1:]:
            union(int(touching[0]), int(a))
    roots = np.array([find(a) for a in range(n + 1)])
    unique = np.unique(roots[1:])
    relabel = np.zeros(n + 1, dtype=labels.dtype)
    relabel[1:] = np.searchsorted(unique, roots[1:]) + 1
    return relabel[labels], int(unique.size)


def _centre(dirs: np.ndarray, weight: np.ndarray) -> np.ndarray:
    c = (dirs * weight[:, None]).sum(axis=0)
    norm = np.linalg.norm(c)
    return c / norm if norm > 0 else dirs.mean(axis=0) / max(np.linalg.norm(dirs.mean(axis=0)), 1e-300)


def _median_cut(dirs: np.ndarray, power: np.ndarray, count: int) -> tuple[np.ndarray, np.ndarray, float]:
    """(sample directions, sample powers, largest merge angle in degrees): one sample per pixel up
    to ``count`` pixels, else ``count`` flux-median-cut groups."""
    if len(dirs) <= count:
        return dirs.copy(), power.copy(), 0.0
    weight = power @ luminance_weights()
    weight = np.where(weight > 0, weight, 1e-300)
    groups = [np.arange(len(dirs))]
    while len(groups) < count:
        spans = [np.ptp(dirs[g], axis=0).max() if len(g) > 1 else -1.0 for g in groups]
        j = int(np.argmax(spans))
        if spans[j] <= 0.0:
            break
        g = groups.pop(j)
        axis = int(np.argmax(np.ptp(dirs[g], axis=0)))
        order = g[np.argsort(dirs[g, axis], kind="stable")]
        cumulative = np.cumsum(weight[order])
        cut = int(np.clip(np.searchsorted(cumulative, 0.5 * cumulative[-1]) + 1, 1, len(order) - 1))
        groups += [order[:cut], order[cut:]]
    out_d = np.array([_centre(dirs[g], weight[g]) for g in groups])
    out_e = np.array([power[g].sum(axis=0) for g in groups])
    merge = max(float(np.degrees(np.arccos(np.clip((dirs[g] @ c).min(), -1.0, 1.0)))) for g, c in zip(groups, out_d,
                                                                                                       strict=True))
    return out_d, out_e, merge
