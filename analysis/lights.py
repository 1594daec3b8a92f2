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
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..brdf_io.brdf import BRDF
from ..brdf_io.envmap import EnvironmentMap
from ..brdf_io.errors import BadInputError
from ..brdf_io.exr import luminance_weights
from ..brdf_io.latlong import row_solid_angles
from .components import grid_labels
from .defaults import (  # numpy-free home: the CLI's parsers check --lights without numpy
    DEFAULT_LIGHTS,
    LIGHT_CONTRAST,
    LIGHT_MODES,
    MAX_LIGHT_RADIUS_DEG,
    MAX_LIGHTS,
    check_lights,
)
from .pairs import sample_pairs_focused
from .reference import local_frames

__all__ = [
    "LightSet", "Light", "extract_lights", "check_lights", "LIGHT_MODES", "DEFAULT_LIGHTS", "LIGHT_CONTRAST",
    "MAX_LIGHT_RADIUS_DEG", "MAX_LIGHTS", "MAX_SAMPLES_PER_LIGHT", "light_radiance", "Extraction",
    "merge_error_by_band", "MERGE_PAIRS_PER_BAND", "MERGE_ERROR_PAIRS_PER_BAND",
]

#: Samples per light: one per pixel up to this count, median-cut groups beyond.
MAX_SAMPLES_PER_LIGHT = 16


@dataclass(frozen=True)
class Light:
    """One extracted light (what ``--json`` and reports list).

    Attributes
    ----------
    direction
        Flux-weighted centre, unit (3,) in the z-up frame, and its ``elevation_deg``/``azimuth_deg``.
    power
        RGB Σ E_k (radiance × solid angle, the map's radiance units × sr).
    radius_deg
        Angular radius of its pixels about the centre; ``solid_angle`` their total (sr).
    share
        Share of the map's flux (luminance) it took out.
    pixels, samples
        Pixels it covers; samples it is shaded with.
    merge_deg
        Largest angle between a pixel and the sample it was merged into (0 when one per pixel).
    """

    direction: tuple[float, float, float]
    elevation_deg: float
    azimuth_deg: float
    power: tuple[float, float, float]
    radius_deg: float
    solid_angle: float
    share: float
    pixels: int
    samples: int
    merge_deg: float

    def to_dict(self) -> dict[str, Any]:
        return {
            "direction": list(self.direction), "elevation_deg": self.elevation_deg, "azimuth_deg": self.azimuth_deg,
            "power": list(self.power), "radius_deg": self.radius_deg, "solid_angle_sr": self.solid_angle,
            "flux_share": self.share, "pixels": self.pixels, "samples": self.samples, "merge_deg": self.merge_deg,
        }


@dataclass(frozen=True, eq=False)
class LightSet:
    """The explicit lights of a scene: samples (ω_k, E_k) shaded exactly.

    Attributes
    ----------
    directions
        float64 (n, 3): unit sample directions, z-up frame (DESIGN §2).
    power
        float64 (n, 3): RGB E_k = excess radiance × solid angle of each sample.
    light
        int (n,): the light each sample belongs to.
    lights
        The lights (:class:`Light`), brightest first.
    """

    directions: np.ndarray
    power: np.ndarray
    light: np.ndarray
    lights: tuple[Light, ...] = field(default=())

    def __post_init__(self) -> None:
        d = np.asarray(self.directions, dtype=np.float64).reshape(-1, 3)
        e = np.asarray(self.power, dtype=np.float64).reshape(-1, 3)
        k = np.asarray(self.light, dtype=np.int64).reshape(-1)
        if not (d.shape[0] == e.shape[0] == k.shape[0]):
            raise ValueError(f"light samples disagree: {d.shape}, {e.shape}, {k.shape}")
        if not (np.all(np.isfinite(d)) and np.all(np.isfinite(e)) and np.all(e >= 0.0)):
            raise BadInputError(None, "light samples must be finite, with non-negative power")
        norms = np.linalg.norm(d, axis=1) if d.size else np.ones(0)
        if np.any(norms == 0.0):
            raise BadInputError(None, "light sample directions must not be zero")
        d = d / norms[:, None] if d.size else d
        for name, value in (("directions", d), ("power", e), ("light", k)):
            value.setflags(write=False)
            object.__setattr__(self, name, value)

    @classmethod
    def empty(cls) -> LightSet:
        return cls(np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0, dtype=np.int64))

    def __len__(self) -> int:
        return int(self.directions.shape[0])

    @property
    def total_power(self) -> np.ndarray:
        """Σ_k E_k per channel (3,)."""
        return self.power.sum(axis=0)

    def rotated(self, rotation: np.ndarray) -> LightSet:
        """The lights of the environment rotated by the (3, 3) rotation Q (``brdf_io.env_rotation``):
        sample directions Q ω_k, powers unchanged; the per-light summaries (:class:`Light`) are kept as
        extracted (they describe the map as loaded)."""
        q = np.asarray(rotation, dtype=np.float64)
        return LightSet(self.directions @ q.T, self.power, self.light, self.lights)

    def radiance(self, brdf: BRDF, R: np.ndarray, V: np.ndarray) -> np.ndarray:
        """Σ_k ρ̂(ω_k; V, N) E_k at unit (n, 3) R and V, N = normalize(R + V): (n, 3).

        :func:`light_radiance` of these samples."""
        return light_radiance(brdf, self.directions, self.power, R, V)


def light_radiance(brdf: BRDF, directions: np.ndarray, power: np.ndarray, R: np.ndarray, V: np.ndarray,
                   *, chunk: int = 1 << 15) -> np.ndarray:
    """Reflected radiance of point lights: Σ_k ρ̂(ω_k; V, N) E_k, (n, 3), with ρ̂ evaluated in the
    frame of N = normalize(R + V) exactly as the angular reference (``analysis.reference``) does
    for each pixel: the model's own ρ̂ (RH02 eq. 2), or ρ · max(N·ω, 0) for measured data."""
    R = np.atleast_2d(np.asarray(R, dtype=np.float64))
    V = np.atleast_2d(np.asarray(V, dtype=np.float64))
    out = np.zeros((R.shape[0], 3))
    if len(directions) == 0:
        return out
    for start in range(0, R.shape[0], chunk):
        stop = start + chunk
        frames = local_frames(R[start:stop] + V[start:stop])  # (k, 3, 3) rows t, b, n
        L_loc = np.einsum("kij,nj->kni", frames, directions)
        V_loc = np.broadcast_to(np.einsum("kij,kj->ki", frames, V[start:stop])[:, None, :], L_loc.shape)
        if brdf.kind == "analytic":
            rho_hat = brdf.rho_hat(L_loc, V_loc)
        else:
            rho, _ = brdf.eval_counted(L_loc, V_loc)
            rho_hat = rho * np.maximum(L_loc[..., 2], 0.0)[..., None]
        out[start:stop] = np.einsum("knc,nc->kc", rho_hat, power)
    return out


@dataclass(frozen=True, eq=False)
class Extraction:
    """What :func:`extract_lights` gives: the lights, the residual map and the rule's numbers."""

    lights: LightSet
    residual: EnvironmentMap
    threshold: float
    reference_luminance: float
    skipped: int  # bright regions left in the map (too large, or beyond the count)
    flux_share: float  # share of the map's flux (luminance) the lights took
    exact: LightSet | None = None  # one sample per pixel, when some light was merged

    @property
    def merged(self) -> bool:
        return self.exact is not None


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


#: (R, V) pairs per view band on which :func:`merge_error_by_band` measures the signal (the SHRM part).
MERGE_PAIRS_PER_BAND = 48
#: Pairs per view band for the merge error itself (the lights alone: cheap per pair).
MERGE_ERROR_PAIRS_PER_BAND = 128


def merge_error_by_band(
    extraction: Extraction, brdf: BRDF, shrm_part: Any, edges_deg: Any, *, whole: Any = None,
    per_band: int = MERGE_PAIRS_PER_BAND, error_per_band: int = MERGE_ERROR_PAIRS_PER_BAND, seed: int = 0,
) -> tuple[np.ndarray, np.ndarray]:
    """Per band of θ_v: the energy of the merged samples' error (against one sample per pixel) over
    the energy of ``shrm_part`` (the SHRM's reflection of the residual map) and of ``whole`` (that
    plus the lights; callables (R, V) -> (n, 3)): two (n_bands,) arrays, zeros when nothing was
    merged. The same relative measures as the per-band statements they are added to.

    Both energies are uniform-R means over each band, estimated with importance weights on (R, V)
    pairs focused on lights (:func:`~shrmkit.analysis.pairs.sample_pairs_focused`): the error on
    ``error_per_band`` pairs per band about the merged lights (only their samples and pixels are
    evaluated there, the others cancel exactly: cheap per pair), the signal on ``per_band`` other
    pairs about every light (an SHRM evaluation each). Under a sharp lobe the error lives in a small part of
    (R, V) space: with the error on the signal's 48 pairs a band (issue 23's matrix, three lamps at
    128 rows) the stated error was 10⁻²¹ at 60–70° for Phong s = 512 and 0.06–0.5 × a 72 000-pair
    measurement at 70–90° for microfacet σ = 0.05 and GGX α = 0.1 (``tests/analysis/test_lights_matrix.py``)."""
    n_bands = len(edges_deg) - 1
    if not extraction.merged:
        return np.zeros(n_bands), np.zeros(n_bands)
    merged, exact = extraction.lights, extraction.exact
    assert exact is not None  # extraction.merged: the one-sample-per-pixel lights are kept
    which = [k for k, light in enumerate(merged.lights) if light.merge_deg > 0.0]
    edges = np.radians(np.asarray(edges_deg, dtype=np.float64))

    def pairs(count: int, seed_: int, lights: list[int]) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        centres = np.array([merged.lights[k].direction for k in lights])
        weights = np.array([max(float(np.sum(merged.lights[k].power)), 1e-300) for k in lights])
        R, V, theta_v, w = sample_pairs_focused(count, edges_deg, centre=centres, centre_weights=weights, seed=seed_)
        return R, V, w, np.clip(np.searchsorted(edges, theta_v, side="right") - 1, 0, n_bands - 1)

    def mean_by_band(values: np.ndarray, w: np.ndarray, band: np.ndarray) -> np.ndarray:
        return np.bincount(band, weights=w * values, minlength=n_bands) / np.maximum(
            np.bincount(band, minlength=n_bands), 1)

    R, V, w, band = pairs(error_per_band, seed + 1, which)  # where the merge moved flux
    mine_m, mine_e = np.isin(merged.light, which), np.isin(exact.light, which)
    diff = light_radiance(brdf, merged.directions[mine_m], merged.power[mine_m], R, V) - \
        light_radiance(brdf, exact.directions[mine_e], exact.power[mine_e], R, V)
    num = mean_by_band((diff**2).sum(axis=1), w, band)
    R, V, w, band = pairs(per_band, seed, list(range(len(merged.lights))))  # where the signal is

    def ratio(signal_of: Any) -> np.ndarray:
        den = mean_by_band((np.asarray(signal_of(R, V), dtype=np.float64) ** 2).sum(axis=1), w, band)
        return np.where(den > 0, num / np.where(den > 0, den, 1.0), np.where(num > 0, np.inf, 0.0))

    return ratio(shrm_part), ratio(whole if whole is not None else shrm_part)


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
