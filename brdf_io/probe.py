"""Debevec angular light probes: pixel geometry and conservative resampling to lat-long.

Angular probes ([DebevecProbes], angular map format): a square
D × D image, u = 2(c + ½)/D − 1 to the right, v = 1 − 2(r + ½)/D upwards; the direction
(Dx, Dy, Dz) in the probe frame (y up) appears at (u, v) = (Dx, Dy)·acos(Dz)/(π sqrt(Dx² + Dy²)),
so the image centre looks along +z and the rim along −z. The probe frame maps into the
project frame (DESIGN §2, z up) by the rotation :data:`PROBE_TO_PROJECT`.

Resampling (:func:`probe_to_latlong`) gathers s × s equal-area sub-samples per lat-long
pixel (:func:`~shrmkit.brdf_io.latlong.gather_to_latlong`), takes the probe pixel
containing each and averages: an estimate of the pixel's mean radiance
∫_pixel L dω / Ω_pixel. A constant map stays exactly constant, and ∫ L dω is preserved up
to the sub-sampling error (measured on cube maps, which share the gather: < 2e-4 for a
smooth closed form; 1e-4 to 5e-3 on the real 1999 cube maps; the flux of one isolated
texel is kept only to about ±20 %: raise ``samples`` for such maps).

The lat-long geometry lives in :mod:`~shrmkit.brdf_io.latlong`, cube maps in
:mod:`~shrmkit.brdf_io.cubemap`.

Public objects: :data:`PROBE_TO_PROJECT`, :func:`probe_pixel_directions`,
:func:`probe_to_latlong`.
"""

from __future__ import annotations

import numpy as np

from .cubemap import face_coordinates
from .latlong import default_gather_samples, gather_to_latlong

__all__ = ["PROBE_TO_PROJECT", "probe_pixel_directions", "probe_to_latlong"]

# project = PROBE_TO_PROJECT @ probe: X = x_p, Y = -z_p, Z = y_p (a rotation, det = +1):
# the probe's up axis y_p becomes the zenith.
PROBE_TO_PROJECT = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])


def probe_pixel_directions(size: int) -> tuple[np.ndarray, np.ndarray]:
    """Directions (probe frame) and solid angles of the pixels of a D × D angular map.

    Returns
    -------
    dirs
        ``(D, D, 3)`` unit vectors (undefined, but finite, outside the disc).
    solid_angles
        ``(D, D)``: π sin(πρ)/ρ · (2/D)² inside the unit disc (ρ = pixel-centre radius,
        the Jacobian of the angular map), 0 outside.
    """
    c = face_coordinates(size)  # the pixel-centre coordinates, as on a cube face
    u = c[None, :]
    v = -c[:, None]
    rho = np.hypot(u, v)
    alpha = np.pi * np.minimum(rho, 1.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        s = np.where(rho > 0, np.sin(alpha) / rho, np.pi)
        jac = np.where(rho > 0, np.pi * np.sin(alpha) / rho, np.pi * np.pi)
    dirs = np.stack(np.broadcast_arrays(u * s, v * s, np.cos(alpha)), axis=-1)
    solid = np.where(rho <= 1.0, jac * (2.0 / size) ** 2, 0.0)
    return dirs, solid


def _probe_pixel_index(x: np.ndarray, y: np.ndarray, z: np.ndarray, size: int) -> np.ndarray:
    """Flat index row·D + col of the angular-map pixel that shows each probe-frame direction."""
    r_xy = np.hypot(x, y)
    alpha = np.arccos(np.clip(z, -1.0, 1.0))
    with np.errstate(invalid="ignore", divide="ignore"):
        scale = np.where(r_xy > 1e-300, alpha / (np.pi * r_xy), 0.0)
    u = x * scale
    v = y * scale
    col = np.clip(((u + 1.0) * 0.5 * size).astype(np.int64), 0, size - 1)
    row = np.clip(((1.0 - v) * 0.5 * size).astype(np.int64), 0, size - 1)
    return row * size + col


def probe_to_latlong(image: np.ndarray, height: int, samples: int | None = None) -> np.ndarray:
    """Resample a Debevec angular-map probe (D × D × 3) to a lat-long map in the project frame.

    Pixels outside the unit disc are never sampled. See
    :func:`~shrmkit.brdf_io.cubemap.cube_to_latlong` for the parameters (default samples
    clip(ceil(max(2D, 256)/H), 2, 16)); D/2 rows keep the probe's resolution at its centre.
    """
    size = image.shape[0]
    values = np.asarray(image, dtype=np.float64).reshape(-1, 3)
    s = samples or default_gather_samples(height, size)
    return gather_to_latlong(values, lambda x, y, z: _probe_pixel_index(x, y, z, size), PROBE_TO_PROJECT.T, height, s)
