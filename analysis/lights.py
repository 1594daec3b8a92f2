"""Bright lights as lights: compact bright regions of an environment map taken out as explicit
lights, the smooth rest left for the SHRM [RH02] (DESIGN §5a).

A truncated SH expansion of a map holding a sun, lamps or windows beside a smooth rest needs
orders in the hundreds and rings (Gibbs). :func:`extract_lights` splits the map once, before
prefiltering, into light samples and a residual, L(ω) = L_res(ω) + Σ_k E_k δ(ω − ω_k), conserving
the flux; the reflected radiance is then B = B_SHRM[L_res](R, V) + Σ_k ρ̂(ω_k; V, N) E_k with
N = normalize(R + V): the residual through the SHRM, the lights exactly (:meth:`LightSet.radiance`).
Large lights are cut into samples by median cut [Debevec05]. Rules: ``data_specs/lights.md``.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..brdf_io.envmap import EnvironmentMap
from ..brdf_io.exr import luminance_weights
from ..brdf_io.latlong import row_solid_angles
from ._light_error import MERGE_ERROR_PAIRS_PER_BAND, MERGE_PAIRS_PER_BAND, merge_error_by_band
from ._light_regions import _centre, _components, _directions, _label_indices, _median_cut, _median_luminance, _ring
from ._light_set import Extraction, Light, LightSet, light_radiance
from .defaults import (  # numpy-free home: the CLI's parsers check --lights without numpy
    DEFAULT_LIGHTS,
    LIGHT_CONTRAST,
    LIGHT_MODES,
    MAX_LIGHT_RADIUS_DEG,
    MAX_LIGHTS,
    check_lights,
)

__all__ = [
    "LightSet", "Light", "extract_lights", "check_lights", "LIGHT_MODES", "DEFAULT_LIGHTS", "LIGHT_CONTRAST",
    "MAX_LIGHT_RADIUS_DEG", "MAX_LIGHTS", "MAX_SAMPLES_PER_LIGHT", "light_radiance", "Extraction",
    "merge_error_by_band", "MERGE_PAIRS_PER_BAND", "MERGE_ERROR_PAIRS_PER_BAND",
]

#: Samples per light: one per pixel up to this count, median-cut groups beyond.
MAX_SAMPLES_PER_LIGHT = 16


def extract_lights(env: EnvironmentMap, mode: str | int = DEFAULT_LIGHTS) -> Extraction:
    """Split ``env`` into explicit lights and a residual map.

    L(ω) = L_res(ω) + Σ_k E_k δ(ω − ω_k), where the samples (ω_k, E_k) of the lights are the excess
    radiance of the bright pixels over their surroundings times each pixel's exact solid angle, at
    the pixel centres — exactly how the angular reference (``analysis.reference``) reads a pixel —
    and the residual L_res holds, in each light's pixels, the mean radiance of the ring of pixels
    around it (never more than the pixel held). Per pixel light + residual = original, so the flux ∫
    L dω is conserved to rounding. The reflected radiance is then B = B_SHRM[L_res](R, V) + Σ_k
    ρ̂(ω_k; V, N) E_k with N = normalize(R + V): the residual through the SHRM, the lights exactly
    (:meth:`LightSet.radiance`).

    **Which regions** (``lights="auto"``, documented in ``data_specs/lights.md``): pixels whose
    luminance (Rec. 709) exceeds :data:`LIGHT_CONTRAST` × the solid-angle-weighted median luminance
    of the map (at least 10⁻³ × its maximum) form connected regions (8-neighbours, across the
    φ seam and around the poles); a region is a light when it fits in a cap of
    :data:`MAX_LIGHT_RADIUS_DEG` about its flux-weighted centre — larger bright regions are smooth
    enough for the SHRM and stay in the map. At most :data:`MAX_LIGHTS` lights, the brightest
    (by flux) first; ``lights=N`` takes at most N of them, ``"none"`` none. What that saves: the
    one-pixel sun of ``builtin:sun`` holds all of the map's high-order energy (a flat spectrum up to
    any order); taken out, the residual is a smooth sky whose SHRM needs low orders and no window.

    **Samples.** A light of up to :data:`MAX_SAMPLES_PER_LIGHT` pixels is one sample per pixel
    (exact, as the reference); a larger one is cut into that many groups by median cut (split the
    group of largest angular extent at its flux median along its longest axis, [Debevec05]), each group one
    sample at its flux-weighted direction carrying its total RGB power. The merge moves flux by at
    most the group's angular radius, stated per light (``merge_deg``) and counted in the error
    statements of :func:`~shrmkit.analysis.shrm.prefilter`.

    Parameters
    ----------
    env
        The environment (lat-long, z-up).
    mode
        ``"auto"``, ``"none"`` or N (at most N lights): :func:`check_lights`.

    Returns
    -------
    Extraction
        ``lights`` (possibly empty) and ``residual`` (``env`` itself when nothing was taken), such
        that residual + lights = ``env`` per pixel.
    """
    mode = check_lights(mode)
    height, width = env.radiance.shape[:2]
    if mode == "none" or height < 2:
        return Extraction(LightSet.empty(), env, np.inf, 0.0, 0, 0.0)
    limit = MAX_LIGHTS if mode == "auto" else int(mode)
    weights = luminance_weights()
    Y = env.radiance @ weights.astype(env.radiance.dtype)  # the map's own type: 2 Mpixel maps stay light
    row_omega = row_solid_angles(height, width)
    y_max = float(Y.max())
    if not y_max > 0.0:
        return Extraction(LightSet.empty(), env, np.inf, 0.0, 0, 0.0)
    reference = _median_luminance(Y, row_omega)
    threshold = max(LIGHT_CONTRAST * reference, 1e-3 * y_max)
    labels, n = _components(Y > threshold)
    if n == 0:
        return Extraction(LightSet.empty(), env, threshold, reference, 0, 0.0)
    kept, skipped = _compact_regions(Y, row_omega, labels, n, limit)
    if not kept:
        return Extraction(LightSet.empty(), env, threshold, reference, skipped, 0.0)
    residual, floor = _residual_start(env, kept)
    samples_d, samples_e, samples_k, lights = [], [], [], []
    pixels_d, pixels_e, pixels_k = [], [], []
    total_flux = float(Y.astype(np.float64).sum(axis=1) @ row_omega)
    bright = labels > 0
    for k, (rows, cols, pix_dirs, centre) in enumerate(kept):
        excess = _take_region(env, residual, rows, cols, bright, row_omega, floor)
        d, e, merge = _median_cut(pix_dirs, excess, MAX_SAMPLES_PER_LIGHT)
        pixels_d.append(pix_dirs)
        pixels_e.append(excess)
        pixels_k.append(np.full(len(pix_dirs), k))
        samples_d.append(d)
        samples_e.append(e)
        samples_k.append(np.full(len(d), k))
        lights.append(_light_record(rows, pix_dirs, centre, excess, row_omega, weights, total_flux, len(d), merge))
    light_set = LightSet(np.concatenate(samples_d), np.concatenate(samples_e), np.concatenate(samples_k),
                         tuple(lights))
    residual_env = EnvironmentMap.derived(residual, name=env.name,
                                          source=f"{env.source or env.name} without {len(lights)} light(s)")
    share = float(sum(light.share for light in lights))
    exact = None
    if any(light.merge_deg > 0.0 for light in lights):
        exact = LightSet(np.concatenate(pixels_d), np.concatenate(pixels_e), np.concatenate(pixels_k), tuple(lights))
    return Extraction(light_set, residual_env, threshold, reference, skipped, share, exact)


def _compact_regions(Y: np.ndarray, row_omega: np.ndarray, labels: np.ndarray, n: int, limit: int
                     ) -> tuple[list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]], int]:
    """The bright regions that are lights, brightest (by flux) first: those within a cap of
    :data:`MAX_LIGHT_RADIUS_DEG` about their flux-weighted centre, at most ``limit`` of them, each
    (rows, cols, pixel directions (m, 3), centre (3,)); and how many regions were left in the map."""
    height, width = labels.shape
    # every region as its pixel indices (work in proportion to the bright pixels, not the map)
    regions = [np.nonzero(labels == label) for label in range(1, n + 1)] if n <= 4 else \
        [tuple(np.unravel_index(idx, labels.shape)) for idx in _label_indices(labels, n)]
    flux = np.array([float(Y[r, c].astype(np.float64) @ row_omega[r]) for r, c in regions])
    cos_max = np.cos(np.radians(MAX_LIGHT_RADIUS_DEG))
    kept: list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]] = []
    skipped = 0
    for j in np.argsort(flux)[::-1]:
        rows, cols = regions[j]
        d = _directions(rows, cols, height, width)
        centre = _centre(d, Y[rows, cols].astype(np.float64) * row_omega[rows])
        if float((d @ centre).min()) < cos_max or len(kept) >= limit:
            skipped += 1
            continue
        kept.append((rows, cols, d, centre))
    return kept, skipped


def _residual_start(env: EnvironmentMap, kept: Sequence[tuple[np.ndarray, ...]]) -> tuple[np.ndarray, float]:
    """A copy of the map (its own type: residual + lights = map to its rounding) and the floor of
    the residual: 0, or the smallest normal float32 outside the lights when they are all there is."""
    residual = env.radiance.copy()
    lit = np.zeros(residual.shape[:2], dtype=bool)
    for rows, cols, _, _ in kept:
        lit[rows, cols] = True
    floor = 0.0
    if not np.any(residual[~lit] > 0.0):
        # the lights are all there is: keep the residual a map (the smallest normal float32, so the
        # SHT has something to expand) rather than a black one, which analyses refuse
        floor = float(np.finfo(np.float32).tiny)
        residual[~lit] = floor
    return residual, floor


def _take_region(env: EnvironmentMap, residual: np.ndarray, rows: np.ndarray, cols: np.ndarray, bright: np.ndarray,
                 row_omega: np.ndarray, floor: float) -> np.ndarray:
    """Fill a light's pixels of ``residual`` (in place) with the solid-angle-weighted mean of the ring
    of non-bright pixels around it (never above what the pixel held); the excess radiance times each
    pixel's solid angle, (m, 3) ≥ 0, is the light's power per pixel."""
    height, width = residual.shape[:2]
    ring_r, ring_c = _ring(rows, cols, height, width)
    outside = ~bright[ring_r, ring_c]
    ring_r, ring_c = ring_r[outside], ring_c[outside]
    ring_w = row_omega[ring_r]
    fill = (residual[ring_r, ring_c].astype(np.float64) * ring_w[:, None]).sum(axis=0) / ring_w.sum() \
        if ring_r.size else np.zeros(3)
    original = np.asarray(env.radiance[rows, cols], dtype=np.float64)
    # rounded to the map's own type first, so that residual + lights = map holds to float64 rounding
    residual[rows, cols] = np.minimum(original, np.maximum(fill, floor)[None, :])
    return (original - residual[rows, cols].astype(np.float64)) * row_omega[rows][:, None]  # (m, 3) ≥ 0


def _light_record(rows: np.ndarray, pix_dirs: np.ndarray, centre: np.ndarray, excess: np.ndarray,
                  row_omega: np.ndarray, weights: np.ndarray, total_flux: float, n_samples: int, merge: float
                  ) -> Light:
    """The :class:`Light` of one region: centre (flux-weighted over the excess), elevation and azimuth
    in degrees, RGB power, angular radius, solid angle, share of the map's flux, pixels and samples."""
    lum = excess @ weights
    centre = _centre(pix_dirs, lum) if lum.sum() > 0 else centre
    el = float(np.degrees(np.arcsin(np.clip(centre[2], -1.0, 1.0))))
    az = float(np.degrees(np.arctan2(centre[1], centre[0])) % 360.0) % 360.0
    radius = float(np.degrees(np.arccos(np.clip((pix_dirs @ centre).min(), -1.0, 1.0))))
    flux_rgb = excess.sum(axis=0)  # (3,) RGB
    return Light(
        direction=(float(centre[0]), float(centre[1]), float(centre[2])), elevation_deg=el, azimuth_deg=az,
        power=(float(flux_rgb[0]), float(flux_rgb[1]), float(flux_rgb[2])), radius_deg=radius,
        solid_angle=float(row_omega[rows].sum()), share=float(lum.sum() / total_flux) if total_flux > 0 else 0.0,
        pixels=int(rows.size), samples=n_samples, merge_deg=merge,
    )
