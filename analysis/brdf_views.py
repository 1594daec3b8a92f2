"""BRDF Explorer's views of a BRDF [Burley12]: the half/difference slice, the plane of incidence,
the lit sphere.

- **Half/difference slice**: ρ on a θ_h × θ_d grid (cell centres every :data:`SLICE_STEP_DEG`) at
  φ_d = :data:`SLICE_PHI_D_DEG`, the directions from the half/difference angles ([Rus98],
  ``brdf_io.halfdiff.halfdiff_to_directions``, φ_h = 0). A cell is *missing* where the table has no
  present sample in its interpolation cell (``eval_masked``), *below the surface* where L or V is.
- **Plane of incidence**: L = (−sin θ_i, 0, cos θ_i), V = (sin θ_o, 0, cos θ_o) with signed θ_o
  (the mirror direction at θ_o = +θ_i); of scattered measurements, the samples within
  :data:`PLANE_TOLERANCE_DEG` of the plane.
- **Lit sphere**: a unit sphere seen orthographically along −z (V = +z at every pixel) under one
  distant light of irradiance π at normal incidence, radiance ρ(L, V)·max(N·L, 0)·π in each pixel's
  tangent frame (a white Lambertian surface facing the light has radiance 1).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from ..brdf_io.brdf import BRDF
from ..brdf_io.halfdiff import halfdiff_to_directions
from ..brdf_io.masked_grid import eval_with_mask
from ..brdf_io.notebook import lit_sphere_radiance

__all__ = ["SLICE_PHI_D_DEG", "SLICE_STEP_DEG", "SPHERE_SIZE", "SPHERE_LIGHT", "PLANE_TOLERANCE_DEG",
           "plane_directions", "plane_samples",
           "halfdiff_slice", "lit_sphere"]

#: φ_d of the half/difference slice (BRDF Explorer's default: no cell below the surface).
SLICE_PHI_D_DEG = 90.0
#: Cell size of the θ_h × θ_d slice: 45 × 45 cells, centres at 1°, 3°, …, 89°.
SLICE_STEP_DEG = 2.0
#: Scattered samples this close to the plane of incidence (azimuth) count as in the plane.
PLANE_TOLERANCE_DEG = 3.0
#: Lit-sphere image size (pixels) and light direction (45° from the view, from the upper left).
SPHERE_SIZE = 128
SPHERE_LIGHT = (-0.5, 0.5, math.sqrt(0.5))


def plane_directions(theta_i_deg: float, theta_o_deg: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(L, V) in the plane of incidence: L = (−sin θ_i, 0, cos θ_i), V = (sin θ_o, 0, cos θ_o)."""
    ti = math.radians(theta_i_deg)
    to = np.radians(np.asarray(theta_o_deg, dtype=np.float64))
    V = np.stack([np.sin(to), np.zeros_like(to), np.cos(to)], axis=-1)
    L = np.broadcast_to(np.array([-math.sin(ti), 0.0, math.cos(ti)]), V.shape)
    return L, V


def plane_samples(brdf: Any, tolerance_deg: float = PLANE_TOLERANCE_DEG
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(θ_i°, signed θ_o°, rgb) of the scattered measurements (``brdf.L``, ``brdf.V``, ``brdf.rgb``)
    within ``tolerance_deg`` of the plane of incidence (signed θ_o > 0 on the side of the mirror
    direction)."""
    L, V, rgb = np.asarray(brdf.L, float), np.asarray(brdf.V, float), np.asarray(brdf.rgb, float)
    dphi = np.arctan2(V[:, 1], V[:, 0]) - np.arctan2(L[:, 1], L[:, 0])
    theta_i = np.degrees(np.arccos(np.clip(L[:, 2], -1.0, 1.0)))
    theta_o = np.degrees(np.arccos(np.clip(V[:, 2], -1.0, 1.0)))
    # in the plane: Δφ near 0 (back towards the light) or near π (forward); at θ_o ≈ 0 the
    # azimuth does not matter
    in_plane = (np.abs(np.sin(dphi)) < math.sin(math.radians(tolerance_deg))) | (theta_o < 0.5)
    signed = np.where(np.cos(dphi) < 0, theta_o, -theta_o)
    return theta_i[in_plane], signed[in_plane], rgb[in_plane]


def _cell_centres(step: float) -> np.ndarray:
    n = int(round(90.0 / step))
    return (np.arange(n) + 0.5) * (90.0 / n)


def halfdiff_slice(brdf: BRDF, phi_d_deg: float = SLICE_PHI_D_DEG, step_deg: float = SLICE_STEP_DEG
                   ) -> dict[str, Any]:
    """ρ on the θ_h × θ_d grid at φ_d: ``theta_h_deg``, ``theta_d_deg`` (cell centres),
    ``rgb`` (n_h, n_d, 3), ``missing`` and ``below_surface`` (bool (n_h, n_d))."""
    th = _cell_centres(step_deg)
    td = _cell_centres(step_deg)
    L, V = halfdiff_to_directions(np.radians(th)[:, None], np.radians(td)[None, :], math.radians(phi_d_deg))
    rgb, has = eval_with_mask(brdf, L, V)
    below = (L[..., 2] <= 0) | (V[..., 2] <= 0)
    return {"theta_h_deg": th, "theta_d_deg": td, "rgb": np.asarray(rgb, dtype=np.float64),
            "missing": ~has & ~below, "below_surface": below}


def lit_sphere(brdf: BRDF, size: int = SPHERE_SIZE, light: Sequence[float] = SPHERE_LIGHT
               ) -> tuple[np.ndarray, np.ndarray]:
    """Linear radiance (size, size, 3) of the unit sphere under one distant light, and the
    hit mask: orthographic view along −z (V = +z), pixel centres x = (2j+1)/size − 1,
    y = 1 − (2i+1)/size, N = (x, y, √(1 − x² − y²)); radiance = ρ(L, V)·max(N·L, 0)·π with
    L and V in the tangent frame (T = the part of V across N, B = N × T, N): the lower layer's
    ``brdf_io.notebook.lit_sphere_radiance`` (NaN of ρ kept)."""
    return lit_sphere_radiance(brdf, size, light, nan_to_zero=False)
