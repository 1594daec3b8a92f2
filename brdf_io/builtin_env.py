"""Procedural environment maps, named by spec strings ``builtin:NAME[,key=value...]``.

Grammar (data_specs/environment_maps.md)::

    spec  := "builtin:" name ("," key "=" value)*
    value := number | number "/" number "/" number   (r/g/b) | axis word (spot ``dir``)

Every built-in is a lat-long map of ``height`` rows (default 256) and 2·height columns
in the project frame (z up, DESIGN §2), float64, with a closed-form integral:

- ``constant``: uniform ``value`` (default 1); ∫ L dω = 4π·value.
- ``sky``: a sky brightening linearly in cos θ from ``horizon`` to ``zenith``, a uniform
  ``ground`` below the horizon, plus a sun disc of angular radius ``sun_radius`` whose
  radiance is ``sun_ratio`` (default 1e4) times the zenith sky, at ``sun_elevation``,
  ``sun_azimuth``. ∫ L dω = 2π(horizon + (zenith − horizon)/2) + 2π·ground
  + sun_ratio·zenith·2π(1 − cos sun_radius).
- ``studio``: three soft Gaussian area lights (key, fill, rim) on a dim ``background``.
- ``spot``: a disc of radiance ``value`` and radius ``radius`` at ``dir`` (x, -x, y, -y,
  z, -z) or at ``elevation``/``azimuth``, on ``background``.
- ``sun``: the one pixel containing (``elevation``, ``azimuth``) at ``ratio`` (1e5) times a
  uniform dim ``sky`` (DESIGN §7 hard case).

Angles are in degrees; elevation is 90° − θ, azimuth is φ (from +x toward +y). Discs are
rasterized by 8 × 8 equal-area sub-samples per pixel and then scaled so that their flux is
exactly value · 2π(1 − cos radius).

Public objects: :func:`builtin_radiance`, :data:`BUILTIN_NAMES`, :data:`BUILTIN_PARAMS`.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from .errors import BadInputError
from .latlong import (
    pixel_directions,
    pixel_index,
    row_edges_cos,
    row_solid_angles,
    subsample_cos_theta,
    subsample_phi,
)
from .spec_params import SpecParams, parse_params

__all__ = ["builtin_radiance", "BUILTIN_NAMES", "BUILTIN_PARAMS", "BUILTIN_PREFIX"]

BUILTIN_PREFIX = "builtin:"
_AXES = {
    "x": (1.0, 0.0, 0.0), "+x": (1.0, 0.0, 0.0), "-x": (-1.0, 0.0, 0.0),
    "y": (0.0, 1.0, 0.0), "+y": (0.0, 1.0, 0.0), "-y": (0.0, -1.0, 0.0),
    "z": (0.0, 0.0, 1.0), "+z": (0.0, 0.0, 1.0), "-z": (0.0, 0.0, -1.0),
}  # fmt: skip


def _unit(elevation_deg: float, azimuth_deg: float) -> np.ndarray:
    el, az = np.radians(elevation_deg), np.radians(azimuth_deg)
    return np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])


def _pixel_of(direction: np.ndarray, height: int) -> tuple[int, int]:
    """Row and column of the pixel of the height × 2·height map containing a unit direction."""
    row, col = pixel_index(direction, height, 2 * height)
    return int(row), int(col)


def _disc_coverage(height: int, centre: np.ndarray, radius: float, sub: int = 8) -> np.ndarray:
    """Fraction of each pixel inside a spherical cap, scaled so Σ coverage·Ω = 2π(1 − cos r).

    Sub-sample (a, b) of pixel (i, j) is at cos θ = cos θ_i⁻ − (a + ½)/sub·Δcos θ_i,
    φ = 2π(j + (b + ½)/sub)/W: equal-area within the pixel. Only rows that can meet the
    cap are sub-sampled.
    """
    width = 2 * height
    cap_cos = np.cos(radius)
    theta_c = np.arccos(np.clip(centre[2], -1.0, 1.0))
    rows = np.flatnonzero(
        (np.arange(height + 1)[1:] * np.pi / height >= theta_c - radius)
        & (np.arange(height) * np.pi / height <= theta_c + radius)
    )
    phi = subsample_phi(width, sub)
    azimuthal = centre[0] * np.cos(phi) + centre[1] * np.sin(phi)  # (W, sub)
    coverage = np.zeros((height, width))
    block = max(1, 2_000_000 // (sub * sub * width))
    for k in range(0, rows.size, block):
        r = rows[k : k + block]
        cos_t = subsample_cos_theta(height, sub, r)
        sin_t = np.sqrt(np.maximum(0.0, 1.0 - cos_t * cos_t))
        # dot(sample, centre) for samples indexed (row, a, col, b)
        dot = sin_t[:, :, None, None] * azimuthal[None, None] + cos_t[:, :, None, None] * centre[2]
        coverage[r] = (dot >= cap_cos).mean(axis=(1, 3))
    omega = row_solid_angles(height, width)
    target = 2.0 * np.pi * (1.0 - cap_cos)
    flux = float((coverage * omega[:, None]).sum())
    if flux == 0.0:  # cap smaller than the sub-sample spacing: all of it in one pixel
        row, col = _pixel_of(centre, height)
        coverage[row, col] = 1.0
        flux = omega[row]
    return coverage * (target / flux)


def _row_mean_sky(height: int, zenith: np.ndarray, horizon: np.ndarray, ground: np.ndarray) -> np.ndarray:
    """Exact solid-angle mean per row of L(μ) = horizon + (zenith − horizon)μ (μ > 0), ground (μ < 0)."""
    edges = row_edges_cos(height)
    top, bottom = edges[:-1], edges[1:]  # μ decreases down the rows
    up_hi, up_lo = np.maximum(top, 0.0), np.maximum(bottom, 0.0)  # sky part of [bottom, top]
    # ∫ (h + (z − h)μ) dμ over [up_lo, up_hi]
    sky = horizon[None] * (up_hi - up_lo)[:, None] + (zenith - horizon)[None] * (
        0.5 * (up_hi**2 - up_lo**2)
    )[:, None]
    down = (np.minimum(top, 0.0) - np.minimum(bottom, 0.0))[:, None] * ground[None]
    return (sky + down) / (top - bottom)[:, None]


def _sky(p: SpecParams, height: int) -> np.ndarray:
    zenith = p.color("zenith", (0.3, 0.5, 1.0), 0.0)
    horizon = p.color("horizon", (0.8, 0.85, 0.9), 0.0)
    ground = p.color("ground", (0.1, 0.09, 0.08), 0.0)
    ratio = p.scalar("sun_ratio", 1e4, 0.0)
    radius = np.radians(p.scalar("sun_radius", 1.0, 0.0, 20.0, lo_open=True))
    sun_dir = _unit(p.scalar("sun_elevation", 45.0, -90.0, 90.0), p.scalar("sun_azimuth", 0.0))
    rows = _row_mean_sky(height, zenith, horizon, ground)
    image = np.repeat(rows[:, None, :], 2 * height, axis=1)
    image += _disc_coverage(height, sun_dir, radius)[..., None] * (ratio * zenith)[None, None]
    return image


def _studio(p: SpecParams, height: int) -> np.ndarray:
    background = p.color("background", 0.02, 0.0)
    scale = p.scalar("intensity", 1.0, 0.0)
    dirs = pixel_directions(height, 2 * height)
    image = np.broadcast_to(background, dirs.shape).copy()
    # (elevation, azimuth, angular width (deg), RGB radiance): key, fill, rim
    lights = ((40.0, 30.0, 12.0, (10.0, 9.5, 9.0)), (15.0, 140.0, 25.0, (2.0, 2.2, 2.5)),
              (20.0, 250.0, 8.0, (6.0, 6.0, 6.0)))  # fmt: skip
    for elevation, azimuth, width_deg, color in lights:
        cos_angle = np.clip(dirs @ _unit(elevation, azimuth), -1.0, 1.0)
        lobe = np.exp(-((np.arccos(cos_angle) / np.radians(width_deg)) ** 2))
        image += scale * lobe[..., None] * np.asarray(color)[None, None]
    return image


def _constant(p: SpecParams, height: int) -> np.ndarray:
    return np.broadcast_to(p.color("value", 1.0, 0.0), (height, 2 * height, 3)).copy()


def _spot(p: SpecParams, height: int) -> np.ndarray:
    if p.has("dir"):
        if p.has("elevation") or p.has("azimuth"):
            raise BadInputError(p.spec, "give either dir= or elevation=/azimuth=, not both")
        centre = np.asarray(_AXES[p.choice("dir", None, tuple(_AXES), fold_case=True)])
    else:
        centre = _unit(p.scalar("elevation", 90.0, -90.0, 90.0), p.scalar("azimuth", 0.0))
    radius = np.radians(p.scalar("radius", 5.0, 0.0, 90.0, lo_open=True))
    value = p.color("value", 100.0, 0.0)
    background = p.color("background", 0.0, 0.0)
    coverage = _disc_coverage(height, centre, radius)
    return background[None, None] + coverage[..., None] * value[None, None]


def _sun(p: SpecParams, height: int) -> np.ndarray:
    sky = p.color("sky", 0.01, 0.0)
    ratio = p.scalar("ratio", 1e5, 0.0)
    row, col = _pixel_of(_unit(p.scalar("elevation", 45.0, -90.0, 90.0), p.scalar("azimuth", 0.0)), height)
    image = np.broadcast_to(sky, (height, 2 * height, 3)).copy()
    image[row, col] = ratio * sky
    return image


# name -> (builder, accepted keys besides height)
_BUILTINS: dict[str, tuple[Callable[[SpecParams, int], np.ndarray], tuple[str, ...]]] = {
    "sky": (_sky, ("zenith", "horizon", "ground", "sun_ratio", "sun_radius", "sun_elevation", "sun_azimuth")),
    "studio": (_studio, ("background", "intensity")),
    "constant": (_constant, ("value",)),
    "spot": (_spot, ("dir", "elevation", "azimuth", "radius", "value", "background")),
    "sun": (_sun, ("sky", "ratio", "elevation", "azimuth")),
}
BUILTIN_NAMES = tuple(_BUILTINS)
BUILTIN_PARAMS = {name: ("height", *keys) for name, (_, keys) in _BUILTINS.items()}


def builtin_radiance(spec: str) -> tuple[str, np.ndarray]:
    """Build a procedural environment from ``builtin:NAME[,key=value...]``.

    Returns
    -------
    name
        The built-in's name.
    radiance
        ``(height, 2·height, 3)`` float64 lat-long radiance in the project frame.

    Raises
    ------
    BadInputError
        Unknown name (the valid ones are listed), unknown or repeated parameter (the
        valid ones are listed), or a value out of range.
    """
    body = spec.strip()
    if not body.startswith(BUILTIN_PREFIX):
        raise BadInputError(spec, f"a built-in environment spec starts with {BUILTIN_PREFIX!r}")
    name, *items = [s.strip() for s in body[len(BUILTIN_PREFIX) :].split(",")]
    if name not in _BUILTINS:
        raise BadInputError(spec, f"unknown built-in environment {name!r}; valid: {', '.join(BUILTIN_NAMES)}")
    raw = parse_params(spec, items, allowed=BUILTIN_PARAMS[name], owner=f"builtin:{name}")
    params = SpecParams(spec, raw, owner=f"builtin:{name}")
    builder = _BUILTINS[name][0]
    return name, builder(params, params.integer("height", 256, 1, 8192))
