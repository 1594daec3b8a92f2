"""Lighting coefficients L_lm of an environment and their accuracy ε_L(F) ([RH02] §5.1).

    L_lm = ∫ L(ω) Y*_lm(ω) dω,      1 − ε_L(F) = Σ_{l<=F} Σ_m |L_lm|² / ∫ L² dω.

The integral is the exact integral of the piecewise-constant lat-long image: a sum over
pixel centres weighted by each pixel's exact solid angle, evaluated by ducc0's fast
adjoint SHT (F1 geometry = pixel-centred rings, phi0 = π/W). The angular-domain
reference integrates the same pixels, so the two agree as F grows. Maps with many more
rows than the order needs are first area-averaged down (integer factor, at least 4F
rows) — the integral ∫L dω is preserved exactly.

Coefficients are stored in the ducc0/healpy layout (m >= 0 only; index
m(2 lmax + 1 − m)/2 + l), one row per RGB channel.

Reference: [RH02] (``data_specs/bibliography.md``).
"""

from __future__ import annotations

from dataclasses import dataclass

import ducc0
import numpy as np

from ..brdf_io.errors import BadInputError
from ..brdf_io.latlong import row_solid_angles

__all__ = [
    "LightingCoefficients", "lighting_coefficients", "alm_index", "area_downsample", "eps_lighting",
    "point_band_energy",
]


def alm_index(l: int | np.ndarray, m: int | np.ndarray, lmax: int) -> np.ndarray:
    """ducc0 index m(2 lmax + 1 − m)/2 + l of (l, m >= 0)."""
    return np.asarray(m) * (2 * lmax + 1 - np.asarray(m)) // 2 + np.asarray(l)


@dataclass(frozen=True, eq=False)
class LightingCoefficients:
    """L_lm of an RGB environment.

    Attributes
    ----------
    alm
        complex128 (3, n_alm), ducc0 layout, l <= lmax.
    lmax
        Largest degree stored.
    energy
        ∫ L² dω per channel, by the pixel sum (shape (3,)).
    rows, source_rows
        Rows of the map the SHT ran on (after area averaging) and of the map given
        (0: unknown).
    beyond
        Optional (n, 3): a_l = Σ_m |L_lm|² for l = lmax+1 … lmax+n of the pixels taken as
        point lights (the angular reference's reading of the map;
        :func:`point_band_energy`) — beyond what the map resolves, for error statements.
    """

    alm: np.ndarray
    lmax: int
    energy: np.ndarray
    name: str = ""
    rows: int = 0
    source_rows: int = 0
    beyond: np.ndarray | None = None

    def band_energy(self) -> np.ndarray:
        """Σ_m |L_lm|² for each l (both signs of m), shape (lmax+1, 3)."""
        out = np.zeros((self.lmax + 1, 3))
        for m in range(self.lmax + 1):
            idx = alm_index(np.arange(m, self.lmax + 1), m, self.lmax)
            power = np.abs(self.alm[:, idx]) ** 2
            out[m:] += (1.0 if m == 0 else 2.0) * power.T
        return out

    def band_energy_all(self) -> np.ndarray:
        """:meth:`band_energy` followed by ``beyond`` when present: (lmax+1+n, 3)."""
        own = self.band_energy()
        return own if self.beyond is None else np.concatenate([own, self.beyond])

    def eps(self) -> np.ndarray:
        """ε_L(F) for F = 0..lmax, worst channel (RH02 §5.1)."""
        return eps_lighting(self.band_energy(), self.energy)


def eps_lighting(band_energy: np.ndarray, energy: np.ndarray) -> np.ndarray:
    """1 − cumulative band energy / total, worst channel with energy."""
    if not np.any(energy > 0):
        raise BadInputError(None, "the environment map is black (zero everywhere): nothing to analyse")
    live = energy > 1e-12 * energy.max()
    return (1.0 - np.cumsum(band_energy[:, live], axis=0) / energy[live]).max(axis=1)


def area_downsample(radiance: np.ndarray, factor: int) -> np.ndarray:
    """Area-weighted average of ``factor``×``factor`` pixel blocks (preserves ∫L dω).

    Rows are weighted by their exact solid angle, so the block value times the block's
    solid angle equals the sum of the fine pixels' radiance times solid angle.
    """
    if factor == 1:
        return radiance
    height, width = radiance.shape[:2]
    if height % factor or width % factor:
        raise ValueError(f"factor {factor} does not divide the map size {height}x{width}")
    weights = row_solid_angles(height, width)
    weighted = (radiance * weights[:, None, None]).reshape(height // factor, factor, width // factor, factor, -1)
    block_weight = weights.reshape(height // factor, factor).sum(axis=1)[:, None, None] * factor
    return weighted.sum(axis=(1, 3)) / block_weight


def _downsample_factor(height: int, width: int, lmax: int) -> int:
    factor = 1
    while height % (2 * factor) == 0 and width % (2 * factor) == 0 and height // (2 * factor) >= 4 * (lmax + 1):
        factor *= 2
    return factor


def lighting_coefficients(
    radiance: np.ndarray, lmax: int, *, name: str = "", nthreads: int = 1
) -> LightingCoefficients:
    """L_lm for l <= lmax of a lat-long map (H, W, 3) by a fast adjoint SHT.

    Parameters
    ----------
    radiance
        Linear radiance, lat-long, z-up, pixel centres as in DESIGN §2.
    lmax
        Largest degree; at most H − 1 (the rings' Nyquist limit).
    """
    radiance = np.asarray(radiance, dtype=np.float64)
    height, width = radiance.shape[:2]
    if lmax < 0 or lmax > height - 1:
        raise BadInputError(name or None, f"lighting order {lmax} outside [0, {height - 1}] for a {height}-row map")
    if width < 2 * lmax + 1:
        raise BadInputError(name or None, f"map width {width} too small for order {lmax}")
    omega = row_solid_angles(height, width)
    energy = np.einsum("h,hwc->c", omega, radiance**2)
    factor = _downsample_factor(height, width, lmax)
    small = area_downsample(radiance, factor)
    h2, w2 = small.shape[:2]
    weighted = small * row_solid_angles(h2, w2)[:, None, None]
    alm = np.empty((3, (lmax + 1) * (lmax + 2) // 2), dtype=np.complex128)
    for c in range(3):
        alm[c] = ducc0.sht.experimental.adjoint_synthesis_2d(
            map=np.ascontiguousarray(weighted[None, :, :, c]),
            spin=0,
            lmax=lmax,
            geometry="F1",
            phi0=np.pi / w2,
            nthreads=nthreads,
        )[0]
    return LightingCoefficients(alm=alm, lmax=lmax, energy=energy, name=name, rows=h2, source_rows=height)


def point_band_energy(radiance: np.ndarray, l_from: int, l_to: int, *, nthreads: int = 1) -> np.ndarray:
    """a_l = Σ_m |L_lm|² for l_from <= l <= l_to of the pixels of a lat-long map taken as point
    lights of flux L·Ω at their centres — exactly what the angular reference integrates — at
    any degree (beyond the rows' Nyquist limit too), by ducc0's adjoint general synthesis
    (agrees with :func:`lighting_coefficients` to 1e-13 where both apply). Shape
    (l_to − l_from + 1, 3)."""
    radiance = np.asarray(radiance, dtype=np.float64)
    height, width = radiance.shape[:2]
    if l_to < l_from:
        return np.zeros((0, 3))
    theta = (np.arange(height) + 0.5) * np.pi / height
    phi = 2.0 * np.pi * (np.arange(width) + 0.5) / width
    loc = np.stack(np.meshgrid(theta, phi, indexing="ij"), axis=-1).reshape(-1, 2)
    flux = (radiance * row_solid_angles(height, width)[:, None, None]).reshape(-1, 3)
    lit = np.any(flux != 0.0, axis=1)
    out = np.zeros((l_to + 1, 3))
    for c in range(3) if lit.any() else ():
        alm = ducc0.sht.experimental.adjoint_synthesis_general(
            map=np.ascontiguousarray(flux[lit, c][None]), spin=0, lmax=l_to, loc=np.ascontiguousarray(loc[lit]),
            epsilon=1e-10, nthreads=nthreads,
        )[0]
        for m in range(l_to + 1):
            idx = alm_index(np.arange(m, l_to + 1), m, l_to)
            out[m:, c] += (1.0 if m == 0 else 2.0) * np.abs(alm[idx]) ** 2
    return out[l_from:]
