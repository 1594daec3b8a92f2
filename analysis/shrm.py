"""The Spherical Harmonic Reflection Map (RH02 §4, eqs. 8, 12) and its prefiltering.

An :class:`SHRM` stores the *global* SHRM B̃_pq(α, β): for each reflection direction
(α, β) on a lat-long grid, the real-basis coefficients of the reflected radiance as a
function of the global view direction V,

    B(R, V) = Σ_{p≤P, |q|≤p} B̃_pq(R) Y^r_pq(V)                (RH02 eq. 8)

with the real basis of ``analysis.sh`` at flat index p² + p + q.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .latlong import bilinear_lookup
from .sh import real_sph_harm

__all__ = ["SHRM"]


@dataclass(frozen=True, eq=False)
class SHRM:
    """A global SHRM on a lat-long grid.

    Attributes
    ----------
    F, P
        Orders in the reflection direction and in the view direction.
    coeffs
        float32 array ((P+1)², H, W, 3): B̃_pq(α, β) at the pixel centres
        α = (i+½)π/H, β = 2π(j+½)/W (z-up frame), real basis index p² + p + q.
    tolerance
        The requested ε; ``eps`` holds the achieved error estimates.
    eps
        Dict of achieved error estimates (``"brdf"``, ``"lighting"``, ``"bound"``).
    meta
        Provenance: BRDF and environment names, timings, tool version.
    """

    F: int
    P: int
    coeffs: np.ndarray
    tolerance: float = float("nan")
    eps: dict[str, float] = field(default_factory=dict)
    meta: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        n = (self.P + 1) ** 2
        if self.coeffs.ndim != 4 or self.coeffs.shape[0] != n or self.coeffs.shape[3] != 3:
            raise ValueError(f"coeffs must have shape ({n}, H, W, 3), got {self.coeffs.shape}")

    @property
    def height(self) -> int:
        return int(self.coeffs.shape[1])

    @property
    def width(self) -> int:
        return int(self.coeffs.shape[2])

    def radiance(self, R: np.ndarray, V: np.ndarray) -> np.ndarray:
        """Predicted reflected radiance B(R, V), shape (n, 3) (RH02 eq. 8).

        Parameters
        ----------
        R, V
            Unit reflection and view directions (n, 3) in the global z-up frame; the
            surface normal is normalize(R + V).
        """
        R = np.atleast_2d(np.asarray(R, dtype=np.float64))
        V = np.atleast_2d(np.asarray(V, dtype=np.float64))
        maps = np.moveaxis(self.coeffs, 0, 2)  # (H, W, n_coef, 3)
        at_r = bilinear_lookup(maps, R)  # (n, n_coef, 3)
        basis = real_sph_harm(self.P, V)  # (n, n_coef)
        return np.einsum("nc,nck->nk", basis, at_r)

    def view_map(self, view: np.ndarray) -> np.ndarray:
        """Distant-viewer map Σ B̃_pq(α, β) Y^r_pq(V) for one view direction (RH02 eq. 12).

        Returns float32 (H, W, 3).
        """
        basis = real_sph_harm(self.P, np.asarray(view, dtype=np.float64).reshape(3)).astype(np.float32)
        return np.tensordot(basis, self.coeffs, axes=(0, 0))
