"""The explicit lights as data and their exact shading: one light's summary (:class:`Light`), the
samples (ω_k, E_k) of a scene (:class:`LightSet`), Σ_k ρ̂(ω_k; V, N) E_k (:func:`light_radiance`)
and what an extraction gives (:class:`Extraction`). Public through :mod:`shrmkit.analysis.lights`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..brdf_io.brdf import BRDF
from ..brdf_io.envmap import EnvironmentMap
from ..brdf_io.errors import BadInputError
from .reference import local_frames


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
    """What :func:`~shrmkit.analysis.lights.extract_lights` gives: the lights, the residual map and the
    rule's numbers."""

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
