"""OpenEXR's own environment-map conventions (the ``envmap`` attribute, ImfEnvmap): resampled to project lat-long.

A file whose header carries ``envmap`` = latlong or cube states its orientation: OpenEXR's
environment frame is y-up, mapped into the project frame by :data:`OPENEXR_TO_PROJECT`; each
lat-long output pixel is the mean of the nearest file pixels at equal-area sub-samples
(:func:`openexr_envmap_to_latlong`). :mod:`.envmap` re-exports the public names; the rules are in
data_specs/environment_maps.md.

Reference: OpenEXR ``src/lib/OpenEXR/ImfEnvmap.h`` and ``ImfEnvmap.cpp``.
"""

from __future__ import annotations

import numpy as np

from .latlong import default_gather_samples, gather_to_latlong

#: OpenEXR environment frame (x_e, y_e, z_e; y up) → project frame: X = x_e, Y = −z_e,
#: Z = y_e. A rotation (det +1) by +90° about x; the same map as ``up="y"`` lat-long files.
OPENEXR_TO_PROJECT = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])

# OpenEXR cube faces in file order (ImfEnvmap.h CubeMapFace): +X, −X, +Y, −Y, +Z, −Z
OPENEXR_CUBE_FACES = ("+X", "-X", "+Y", "-Y", "+Z", "-Z")


def _openexr_latlong_texel(h: int, w: int):
    """texel_of(x, y, z) for an OpenEXR lat-long data window of h × w: the nearest pixel to
    ImfEnvmap ``LatLongMap::pixelPosition``: x = (lon/(−2π) + ½)(w − 1), y = (lat/(−π) + ½)(h − 1),
    lat = asin(y_e), lon = atan2(x_e, z_e) (pixel centres on the poles and on the ±π seam)."""

    def texel_of(x: np.ndarray, y: np.ndarray, z: np.ndarray) -> np.ndarray:
        lat = np.arcsin(np.clip(y, -1.0, 1.0))
        lon = np.arctan2(x, z)
        col = np.clip(np.rint((lon / (-2.0 * np.pi) + 0.5) * (w - 1)), 0, w - 1).astype(np.int64)
        row = np.clip(np.rint((lat / -np.pi + 0.5) * (h - 1)), 0, h - 1).astype(np.int64)
        return row * w + col

    return texel_of


def _openexr_cube_texel(n: int):
    """texel_of(x, y, z) for an OpenEXR cube of six n × n faces stacked vertically (+X, −X,
    +Y, −Y, +Z, −Z): the face of the largest |component| (ties: x, then y), the in-face
    position of ImfEnvmap ``CubeMap::faceAndPixelPosition`` (p = (d_a/|d_major| + 1)/2 · (n − 1),
    a = y, z for ±X; x, z for ±Y; x, y for ±Z) and the file pixel of ``CubeMap::pixelPosition``,
    rounded to the nearest pixel. Flat index (face·n + row)·n + column."""
    last = n - 1

    def texel_of(x: np.ndarray, y: np.ndarray, z: np.ndarray) -> np.ndarray:
        ax, ay, az = np.abs(x), np.abs(y), np.abs(z)
        on_x = (ax >= ay) & (ax >= az)
        on_y = ~on_x & (ay >= az)
        major = np.maximum(np.where(on_x, ax, np.where(on_y, ay, az)), 1e-300)
        first = np.where(on_x, y, x) / major  # pif.x
        second = np.where(on_x | on_y, z, y) / major  # pif.y
        px = (first + 1.0) * 0.5 * last
        py = (second + 1.0) * 0.5 * last
        negative = np.where(on_x, x < 0, np.where(on_y, y < 0, z < 0))
        face = np.where(on_x, 0, np.where(on_y, 2, 4)) + negative
        # CubeMap::pixelPosition, relative to the face's top-left pixel: (column, row)
        col = np.select(
            [face == 0, face == 1, face == 4], [py, last - py, last - px], default=px
        )
        row = np.select([face == 3], [py], default=last - np.where(face <= 1, px, py))
        col = np.clip(np.rint(col), 0, last).astype(np.int64)
        row = np.clip(np.rint(row), 0, last).astype(np.int64)
        return (face * n + row) * n + col

    return texel_of


def openexr_envmap_to_latlong(image: np.ndarray, kind: str, height: int, samples: int | None = None) -> np.ndarray:
    """Resample an OpenEXR environment map (its data window) to a project-frame lat-long map.

    Parameters
    ----------
    image
        ``(h, w, 3)`` data-window pixels: ``kind="latlong"`` (ImfEnvmap LatLongMap: top row
        latitude +π/2, bottom −π/2, left column longitude +π, right −π, direction
        (sin lon cos lat, sin lat, cos lon cos lat)), or ``kind="cube"`` (h = 6w: faces +X,
        −X, +Y, −Y, +Z, −Z from the top, ImfEnvmap CubeMap).
    height
        Output rows H (width 2H).
    samples
        Equal-area sub-samples per pixel and axis; default
        :func:`~shrmkit.brdf_io.latlong.default_gather_samples` with h (lat-long) or 2w (cube)
        source rows.

    Returns
    -------
    numpy.ndarray
        ``(H, 2H, 3)`` float64: each pixel the mean over its equal-area sub-samples of the
        nearest file pixel (OpenEXR's pixel-centre positions), directions mapped by
        :data:`OPENEXR_TO_PROJECT`. Source: OpenEXR ``ImfEnvmap.cpp``.
    """
    h, w = image.shape[:2]
    values = np.asarray(image, dtype=np.float64).reshape(-1, 3)
    if kind == "latlong":
        texel_of, rows = _openexr_latlong_texel(h, w), h
    elif kind == "cube":
        texel_of, rows = _openexr_cube_texel(w), 2 * w
    else:
        raise ValueError(f"unknown OpenEXR envmap kind {kind!r}")
    s = samples or default_gather_samples(height, rows)
    return gather_to_latlong(values, texel_of, OPENEXR_TO_PROJECT.T, height, s)
