"""Lat-long (equirectangular) grids in the project convention (DESIGN §2).

Pixel (i, j) of an H × W map has its centre at θ = (i + ½)π/H, φ = 2π(j + ½)/W, direction
ω = (sin θ cos φ, sin θ sin φ, cos θ) in the z-up frame.
"""

from __future__ import annotations

import numpy as np

__all__ = ["pixel_angles", "pixel_directions", "row_solid_angles", "direction_angles", "bilinear_lookup"]


def pixel_angles(height: int, width: int) -> tuple[np.ndarray, np.ndarray]:
    """θ of the row centres (H,) and φ of the column centres (W,)."""
    theta = (np.arange(height) + 0.5) * np.pi / height
    phi = 2.0 * np.pi * (np.arange(width) + 0.5) / width
    return theta, phi


def pixel_directions(height: int, width: int) -> np.ndarray:
    """Unit vectors of the pixel centres, shape (H, W, 3)."""
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


def row_solid_angles(height: int, width: int) -> np.ndarray:
    """Exact solid angle of one pixel in each row: (2π/W)(cos θ_top − cos θ_bottom), shape (H,)."""
    edges = np.cos(np.arange(height + 1) * np.pi / height)
    return (2.0 * np.pi / width) * (edges[:-1] - edges[1:])


def direction_angles(dirs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(θ, φ) of unit vectors, φ in [0, 2π)."""
    dirs = np.asarray(dirs, dtype=np.float64)
    theta = np.arccos(np.clip(dirs[..., 2], -1.0, 1.0))
    phi = np.mod(np.arctan2(dirs[..., 1], dirs[..., 0]), 2.0 * np.pi)
    return theta, phi


def bilinear_lookup(image: np.ndarray, dirs: np.ndarray) -> np.ndarray:
    """Bilinear interpolation of a lat-long ``image`` (H, W, ...) at unit vectors ``dirs`` (..., 3).

    φ wraps around; θ is clamped to the first and last row centres (no pole artefacts
    beyond half a pixel). Returns ``dirs.shape[:-1] + image.shape[2:]``.
    """
    height, width = image.shape[:2]
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
    trailing = (1,) * (image.ndim - 2)
    fy = fy.reshape(fy.shape + trailing)
    fx = fx.reshape(fx.shape + trailing)
    top = image[y0, x0] * (1.0 - fx) + image[y0, x1] * fx
    bottom = image[y1, x0] * (1.0 - fx) + image[y1, x1] * fx
    return top * (1.0 - fy) + bottom * fy
