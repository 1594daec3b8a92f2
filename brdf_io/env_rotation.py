"""Rotation of the environment: one definition for every part of shrmkit (DESIGN §2, §5a).

An environment rotated by the rotation matrix Q has the radiance

    L_Q(ω) = L(Qᵀ ω)                      (a feature at direction μ moves to Q μ)

so the radiance reflected under it, for any representation B(R, V) of the unrotated scene
(an SHRM, Gaussian lobes, twelve RSIBR maps, explicit lights, the angular reference), is

    B_Q(R, V) = B(Qᵀ R, Qᵀ V)

(and the lights' directions ω_k move to Q ω_k): a rotation is a change of the lookup
directions at view time, and nothing is prefiltered again ([RH02] §1, §8; for an isotropic
BRDF the identity is exact, every error statement of the scene holds unchanged).

Euler angles (degrees) in the z-up frame of DESIGN §2, applied roll first:

    Q = R_z(AZ) · R_y(−EL) · R_x(ROLL)

- AZ turns the map about the up axis +z, counterclockwise seen from above: a feature at
  azimuth φ moves to φ + AZ, the sense of ``load_env(azimuth=)`` and ``--env-azimuth``
  (:meth:`~shrmkit.brdf_io.envmap.EnvironmentMap.rotated_z`), so ``env_rotation_matrix(70)``
  renders what a map loaded with ``azimuth=70`` renders;
- EL raises the horizon point at azimuth 0 (+x) toward the zenith (+z) by EL;
- ROLL turns the map about +x (right-handed: +y toward +z) before the other two.

The horizon point at azimuth 0 ends at elevation EL, azimuth AZ.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from .errors import BadInputError

__all__ = ["env_rotation_matrix", "check_env_rotation", "to_map_frame", "rotation_about_z", "ORTHONORMAL_TOL"]

#: A given 3 × 3 matrix is accepted as a rotation when ‖QᵀQ − I‖_max and |det Q − 1| are at most this.
ORTHONORMAL_TOL = 1e-6


def rotation_about_z(angle_deg: float) -> np.ndarray:
    """R_z(angle) (3, 3) float64: counterclockwise about +z seen from above, angle in degrees."""
    a = np.radians(float(angle_deg))
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def env_rotation_matrix(az: float, el: float = 0.0, roll: float = 0.0) -> np.ndarray:
    """The rotation Q = R_z(AZ) R_y(−EL) R_x(ROLL) of the environment (module docstring), (3, 3) float64.

    Parameters
    ----------
    az, el, roll
        Degrees: azimuth about +z (the sense of ``--env-azimuth``), elevation of the horizon
        point at azimuth 0, roll about +x (applied first).

    Raises
    ------
    BadInputError
        A non-finite angle.

    Examples
    --------
    >>> Q = env_rotation_matrix(90.0)              # +x moves to +y
    >>> (Q @ [1.0, 0.0, 0.0]).round(12) + 0.0
    array([0., 1., 0.])
    >>> (env_rotation_matrix(0.0, 90.0) @ [1.0, 0.0, 0.0]).round(12) + 0.0   # +x up to the zenith
    array([0., 0., 1.])
    """
    angles = np.array([az, el, roll], dtype=np.float64)
    if not np.all(np.isfinite(angles)):
        raise BadInputError(None, f"environment rotation angles must be finite, got az={az!r}, el={el!r}, "
                            f"roll={roll!r}")
    e, r = np.radians(angles[1:])
    ry = np.array([[np.cos(e), 0.0, -np.sin(e)], [0.0, 1.0, 0.0], [np.sin(e), 0.0, np.cos(e)]])  # R_y(−EL)
    rx = np.array([[1.0, 0.0, 0.0], [0.0, np.cos(r), -np.sin(r)], [0.0, np.sin(r), np.cos(r)]])
    return rotation_about_z(angles[0]) @ ry @ rx


def check_env_rotation(value: Any) -> np.ndarray | None:
    """The environment rotation as a (3, 3) float64 matrix, or None for none.

    Parameters
    ----------
    value
        None; a rotation matrix (3, 3) (orthonormal with determinant +1 within
        :data:`ORTHONORMAL_TOL`); or Euler angles in degrees ``(AZ, EL)`` or ``(AZ, EL, ROLL)``
        (:func:`env_rotation_matrix`).

    Raises
    ------
    BadInputError
        Another shape, non-finite values, a matrix that is not a rotation (a reflection, a
        scaling), echoing what was given.
    """
    if value is None:
        return None
    try:
        q = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise BadInputError(None, f"env_rotation must be a 3x3 rotation or angles (az, el[, roll]) in degrees, "
                            f"got {value!r}") from None
    if q.shape in ((2,), (3,)):
        return env_rotation_matrix(*q)
    if q.shape != (3, 3):
        raise BadInputError(None, f"env_rotation must be a 3x3 rotation or angles (az, el[, roll]) in degrees, "
                            f"got shape {q.shape}")
    if not np.all(np.isfinite(q)):
        raise BadInputError(None, "env_rotation must be finite")
    off = float(np.max(np.abs(q.T @ q - np.eye(3))))
    det = float(np.linalg.det(q))
    if off > ORTHONORMAL_TOL or abs(det - 1.0) > ORTHONORMAL_TOL:
        raise BadInputError(None, f"env_rotation is not a rotation (|QtQ - I| = {off:.3g}, det = {det:.6g})")
    return q


def to_map_frame(directions: np.ndarray, rotation: np.ndarray | Sequence[Sequence[float]] | None) -> np.ndarray:
    """Qᵀ d for each direction d (..., 3): world directions in the unrotated map's frame (the
    lookup of B_Q(R, V) = B(Qᵀ R, Qᵀ V)); the directions unchanged for ``rotation`` None."""
    d = np.asarray(directions, dtype=np.float64)
    if rotation is None:
        return d
    return d @ np.asarray(rotation, dtype=np.float64)  # row vectors: (Qᵀ d)ᵀ = dᵀ Q
