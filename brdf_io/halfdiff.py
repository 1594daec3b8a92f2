"""Rusinkiewicz half/difference coordinates of a pair of directions, both ways.

For a light direction L and a view direction V (unit vectors in the local frame, normal
+z, both pointing away from the surface) the half vector is H = normalize(L + V), with
spherical angles (θ_h, φ_h). The *difference* vector D is L expressed in a frame where H
is the pole: D = Ry(−θ_h) Rz(−φ_h) L (rotate by −φ_h about z, then by −θ_h about y), and
(θ_d, φ_d) are its spherical angles ([Rus98] §3 and Fig. 2). In that frame V
is the mirror image of D about the pole, V' = (−D_x, −D_y, D_z), so swapping L and V
keeps θ_h, θ_d and maps φ_d to φ_d + π (mod 2π): reciprocity is a half turn in φ_d.

Conventions: θ_h ∈ [0, π], θ_d ∈ [0, π/2], φ_h and φ_d ∈ (−π, π] (``arctan2``). D is
built from L (the incident direction), as MERL's ``BRDFRead.cpp`` builds it from its
``theta_in, fi_in`` pair.
"""

from __future__ import annotations

import numpy as np

__all__ = ["directions_to_halfdiff", "halfdiff_to_directions", "spherical_angles"]


def spherical_angles(w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(θ, φ) of unit vectors ``w`` (..., 3), DESIGN §2: w = (sin θ cos φ, sin θ sin φ, cos θ).

    θ is computed with ``arctan2`` so it stays accurate near the poles; φ ∈ (−π, π].
    """
    w = np.asarray(w, dtype=np.float64)
    rho = np.hypot(w[..., 0], w[..., 1])
    return np.arctan2(rho, w[..., 2]), np.arctan2(w[..., 1], w[..., 0])


def directions_to_halfdiff(
    L: np.ndarray, V: np.ndarray, *, return_phi_h: bool = False
) -> tuple[np.ndarray, ...]:
    """Half/difference angles of direction pairs (Rusinkiewicz 1998, §3).

    Parameters
    ----------
    L, V
        Unit vectors (..., 3), broadcast against each other. L + V must not vanish.
    return_phi_h
        Also return the azimuth φ_h of the half vector (last element).

    Returns
    -------
    theta_h, theta_d, phi_d (, phi_h)
        Arrays of the broadcast shape; φ_d ∈ (−π, π].
    """
    L = np.asarray(L, dtype=np.float64)
    V = np.asarray(V, dtype=np.float64)
    L, V = np.broadcast_arrays(L, V)
    H = L + V
    norm = np.sqrt(np.einsum("...i,...i->...", H, H))
    norm = np.where(norm > 0, norm, 1.0)
    hx, hy, hz = H[..., 0] / norm, H[..., 1] / norm, H[..., 2] / norm
    # sin θ_h, cos θ_h and cos φ_h, sin φ_h straight from H (φ_h = 0 on the pole)
    st = np.hypot(hx, hy)
    ct = hz
    on_pole = st == 0
    safe = np.where(on_pole, 1.0, st)
    cp = np.where(on_pole, 1.0, hx / safe)
    sp = np.where(on_pole, 0.0, hy / safe)
    theta_h = np.arctan2(st, ct)
    # D = Ry(−θ_h) Rz(−φ_h) L, written out (R_axis(a) is the right-handed rotation by a)
    x1 = cp * L[..., 0] + sp * L[..., 1]
    y1 = -sp * L[..., 0] + cp * L[..., 1]
    z1 = L[..., 2]
    dx = ct * x1 - st * z1
    dz = st * x1 + ct * z1
    theta_d = np.arctan2(np.hypot(dx, y1), dz)
    phi_d = np.arctan2(y1, dx)
    if return_phi_h:
        return theta_h, theta_d, phi_d, np.arctan2(hy, hx)
    return theta_h, theta_d, phi_d


def halfdiff_to_directions(
    theta_h: np.ndarray, theta_d: np.ndarray, phi_d: np.ndarray | float, phi_h: np.ndarray | float = 0.0
) -> tuple[np.ndarray, np.ndarray]:
    """Directions (L, V) from half/difference angles, the inverse of ``directions_to_halfdiff``.

    L = Rz(φ_h) Ry(θ_h) D and V = Rz(φ_h) Ry(θ_h) D', with D = (sin θ_d cos φ_d,
    sin θ_d sin φ_d, cos θ_d) and D' = (−D_x, −D_y, D_z) its mirror about the half vector.
    The default φ_h = 0 is enough for isotropic BRDFs.

    Returns
    -------
    L, V
        Arrays of shape (..., 3) (the broadcast shape of the angles).
    """
    theta_h, theta_d, phi_d, phi_h = (np.asarray(a, dtype=np.float64) for a in (theta_h, theta_d, phi_d, phi_h))
    shape = np.broadcast_shapes(theta_h.shape, theta_d.shape, phi_d.shape, phi_h.shape)
    # the sines and cosines on each angle's own (often much smaller) shape; only products are full size
    sd = np.sin(theta_d)
    dx, dy, dz = sd * np.cos(phi_d), sd * np.sin(phi_d), np.cos(theta_d)
    ct, st = np.cos(theta_h), np.sin(theta_h)
    cp, sp = np.cos(phi_h), np.sin(phi_h)

    def to_local(x: np.ndarray, y: np.ndarray, z: np.ndarray) -> np.ndarray:
        # Ry(θ_h) then Rz(φ_h)
        x1 = ct * x + st * z
        out = np.empty((*shape, 3))
        out[..., 2] = -st * x + ct * z
        out[..., 0] = cp * x1 - sp * y
        out[..., 1] = sp * x1 + cp * y
        return out

    return to_local(dx, dy, dz), to_local(-dx, -dy, dz)
