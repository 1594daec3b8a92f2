"""Lat-long (equirectangular) grids in the project convention (DESIGN §2): the one home of
this geometry in shrmkit.

Pixel (i, j) of an H × W map has its centre at θ = (i + ½)π/H, φ = 2π(j + ½)/W, direction
ω = (sin θ cos φ, sin θ sin φ, cos θ) in the z-up frame. Row i spans θ ∈ [iπ/H, (i + 1)π/H]
and column j spans φ ∈ [2πj/W, 2π(j + 1)/W], so the exact solid angle of a pixel of row i is
Ω_i = (2π/W)(cos(iπ/H) − cos((i + 1)π/H)); the H·W pixels sum to 4π.

Public objects:

- :func:`pixel_angles`, :func:`pixel_directions`, :func:`row_edges_cos`,
  :func:`row_solid_angles`: the grid;
- :func:`direction_angles`, :func:`pixel_index`: from directions back to (θ, φ) and to
  the pixel that contains them;
- :func:`bilinear_lookup`: interpolation between pixel centres;
- :func:`subsample_cos_theta`, :func:`subsample_phi`, :func:`gather_to_latlong`,
  :func:`default_gather_samples`: equal-area sub-samples of the pixels, and the
  conservative resampling of a piecewise-constant source (cube map, angular probe) onto
  the grid.

Users: :mod:`~shrmkit.brdf_io.envmap` (the environment map container),
:mod:`~shrmkit.brdf_io.builtin_env` (procedural maps), :mod:`~shrmkit.brdf_io.cubemap` and
:mod:`~shrmkit.brdf_io.probe` (resampling), and the analysis and render layers.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

__all__ = [
    "pixel_angles",
    "pixel_directions",
    "row_edges_cos",
    "row_solid_angles",
    "direction_angles",
    "pixel_index",
    "bilinear_lookup",
    "subsample_cos_theta",
    "subsample_phi",
    "gather_to_latlong",
    "default_gather_samples",
]


def pixel_angles(height: int, width: int) -> tuple[np.ndarray, np.ndarray]:
    """θ of the row centres (H,) and φ of the column centres (W,)."""
    theta = (np.arange(height) + 0.5) * np.pi / height
    phi = 2.0 * np.pi * (np.arange(width) + 0.5) / width
    return theta, phi


def pixel_directions(height: int, width: int) -> np.ndarray:
    """Unit vectors of the pixel centres, shape (H, W, 3) float64."""
    theta, phi = pixel_angles(height, width)
    st = np.sin(theta)[:, None]
    return np.stack(
        [
            st * np.cos(phi)[None, :],
            st * np.sin(phi)[None, :],
            np.broadcast_to(np.cos(theta)[:, None], (height, width)),
        ],
        axis=-1,
    )


def row_edges_cos(height: int) -> np.ndarray:
    """cos θ at the H + 1 row edges θ = iπ/H, shape (H + 1,), from 1 (zenith) down to −1."""
    return np.cos(np.arange(height + 1) * np.pi / height)


def row_solid_angles(height: int, width: int) -> np.ndarray:
    """Exact solid angle of one pixel in each row: (2π/W)(cos θ_top − cos θ_bottom), shape (H,)."""
    edges = row_edges_cos(height)
    return (2.0 * np.pi / width) * (edges[:-1] - edges[1:])


def direction_angles(dirs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(θ, φ) of unit vectors, φ in [0, 2π)."""
    dirs = np.asarray(dirs, dtype=np.float64)
    theta = np.arccos(np.clip(dirs[..., 2], -1.0, 1.0))
    phi = np.mod(np.arctan2(dirs[..., 1], dirs[..., 0]), 2.0 * np.pi)
    return theta, phi


def pixel_index(dirs: np.ndarray, height: int, width: int) -> tuple[np.ndarray, np.ndarray]:
    """Row and column (int64 arrays of shape ``dirs.shape[:-1]``) of the pixel containing
    each unit vector: row ⌊θH/π⌋, column ⌊φW/2π⌋, clamped to the last row and column."""
    theta, phi = direction_angles(dirs)
    row = np.minimum(np.floor(theta * height / np.pi).astype(np.int64), height - 1)
    col = np.minimum(np.floor(phi * width / (2.0 * np.pi)).astype(np.int64), width - 1)
    return row, col


def bilinear_corners(
    dirs: np.ndarray, height: int, width: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The rule of :func:`bilinear_lookup` for an H × W lat-long map at unit vectors ``dirs``
    (..., 3): rows (y0, y1), columns (x0, x1) (int64, φ wrapped) and fractions (fy, fx) in
    [0, 1], each of shape ``dirs.shape[:-1]``; the value is
    (1−fy)((1−fx) I[y0,x0] + fx I[y0,x1]) + fy((1−fx) I[y1,x0] + fx I[y1,x1])."""
    theta, phi = direction_angles(dirs)
    y = np.clip(theta * height / np.pi - 0.5, 0.0, height - 1.0)
    x = phi * width / (2.0 * np.pi) - 0.5
    y0 = np.clip(np.floor(y).astype(np.int64), 0, max(height - 2, 0))
    y1 = np.minimum(y0 + 1, height - 1)
    fy = y - y0
    x0f = np.floor(x)
    fx = x - x0f
    x0 = np.mod(x0f.astype(np.int64), width)
    x1 = np.mod(x0 + 1, width)
    return y0, y1, x0, x1, fy, fx


def bilinear_lookup(image: np.ndarray, dirs: np.ndarray) -> np.ndarray:
    """Bilinear interpolation of a lat-long ``image`` (H, W, ...) at unit vectors ``dirs`` (..., 3).

    φ wraps around; θ is clamped to the first and last row centres (no pole artefacts
    beyond half a pixel). Returns ``dirs.shape[:-1] + image.shape[2:]``.
    """
    y0, y1, x0, x1, fy, fx = bilinear_corners(dirs, *image.shape[:2])
    trailing = (1,) * (image.ndim - 2)
    fy = fy.reshape(fy.shape + trailing)
    fx = fx.reshape(fx.shape + trailing)
    top = image[y0, x0] * (1.0 - fx) + image[y0, x1] * fx
    bottom = image[y1, x0] * (1.0 - fx) + image[y1, x1] * fx
    return top * (1.0 - fy) + bottom * fy


# --------------------------------------------------------------------------------------
# equal-area sub-samples and conservative resampling
# --------------------------------------------------------------------------------------
def subsample_cos_theta(height: int, samples: int, rows: np.ndarray | None = None) -> np.ndarray:
    """cos θ of ``samples`` equal-area sub-sample rows per pixel row, shape (len(rows), s).

    Sub-sample a of row i sits at cos θ = cos θ_i⁻ − (a + ½)/s · (cos θ_i⁻ − cos θ_i⁺)
    (θ_i⁻, θ_i⁺ the row's upper and lower edge): uniform in cos θ, so each of the s × s
    sub-samples of a pixel (with :func:`subsample_phi`) carries Ω_i/s². ``rows`` selects
    rows (default all H).
    """
    edges = row_edges_cos(height)
    r = np.arange(height) if rows is None else np.asarray(rows)
    frac = (np.arange(samples) + 0.5) / samples
    return edges[r, None] - frac[None, :] * (edges[r] - edges[r + 1])[:, None]


def subsample_phi(width: int, samples: int) -> np.ndarray:
    """φ = 2π(j + (b + ½)/s)/W of the s sub-sample columns of each pixel column j, shape (W, s)."""
    frac = (np.arange(samples) + 0.5) / samples
    return 2.0 * np.pi * (np.arange(width)[:, None] + frac[None, :]) / width


def default_gather_samples(height: int, source_rows: int) -> int:
    """Sub-samples per axis for :func:`gather_to_latlong`: clip(ceil(max(2·source_rows, 256)/H), 2, 16),
    about two per source texel along θ and at least 256 sample rows."""
    return int(np.clip(np.ceil(max(2 * source_rows, 256) / height), 2, 16))


def gather_to_latlong(
    values: np.ndarray,
    texel_of: Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray],
    to_source: np.ndarray,
    height: int,
    samples: int,
) -> np.ndarray:
    """Resample flat source texels ``values`` (T, C) to a (height, 2·height, C) lat-long map.

    ``texel_of(x, y, z)`` maps source-frame direction components to flat texel indices;
    ``to_source`` (3 × 3) maps project-frame vectors to the source frame. Every pixel
    takes ``samples`` × ``samples`` equal-area sub-samples (:func:`subsample_cos_theta`,
    :func:`subsample_phi`), each carrying Ω_pixel/s², so the pixel value is the plain mean
    of the texels under them: an estimate of ∫_pixel L dω / Ω_pixel for the
    piecewise-constant source. A constant source stays exactly constant.
    """
    width = 2 * height
    s = samples
    cos_t = subsample_cos_theta(height, s).reshape(-1)
    sin_t = np.sqrt(np.maximum(0.0, 1.0 - cos_t * cos_t))
    phi = subsample_phi(width, s).reshape(-1)
    cp, sp = np.cos(phi), np.sin(phi)
    texel = np.empty((height * s, width * s), dtype=np.int64)
    block = max(1, 1_000_000 // (width * s))
    for r0 in range(0, height * s, block):
        st, ct = sin_t[r0 : r0 + block, None], cos_t[r0 : r0 + block, None]
        big_x, big_y = st * cp, st * sp
        big_z = np.broadcast_to(ct, big_x.shape)
        # source-frame components: row k of to_source dotted with (X, Y, Z)
        comps = [m[0] * big_x + m[1] * big_y + m[2] * big_z for m in to_source]
        texel[r0 : r0 + block] = texel_of(*comps)
    # sample (i·s + a, j·s + b) -> pixel (i, j): mean over a and b
    picked = values[texel.reshape(height, s, width, s)]
    return picked.mean(axis=(1, 3))
