"""Sampled (R, V) pairs for error measurements, with grazing views well represented."""

from __future__ import annotations

import numpy as np

__all__ = ["sample_pairs"]


def sample_pairs(n: int, *, seed: int = 0, max_view_deg: float = 88.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``n`` (R, V) pairs: V uniform on the sphere, the view elevation θ_v = angle(N, V)
    stratified uniformly *in angle* on [0, max_view_deg] (so grazing views are as frequent
    as normal ones), the normal's azimuth about V uniform; R = 2(N·V)N − V.

    Returns
    -------
    R, V
        Unit vectors (n, 3), z-up frame.
    theta_v
        (n,) view elevations in radians.
    """
    if n < 1 or not 0.0 < max_view_deg < 90.0:
        raise ValueError(f"need n >= 1 and max_view_deg in (0, 90), got {n}, {max_view_deg}")
    rng = np.random.default_rng(seed)
    V = rng.normal(size=(n, 3))
    V /= np.linalg.norm(V, axis=1, keepdims=True)
    theta_v = (np.arange(n) + rng.random(n)) / n * np.radians(max_view_deg)
    rng.shuffle(theta_v)
    az = rng.random(n) * 2.0 * np.pi
    helper = np.where(np.abs(V[:, 2:3]) < 0.9, [0.0, 0.0, 1.0], [1.0, 0.0, 0.0])
    t = np.cross(V, helper)
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    b = np.cross(V, t)
    N = np.cos(theta_v)[:, None] * V + np.sin(theta_v)[:, None] * (np.cos(az)[:, None] * t + np.sin(az)[:, None] * b)
    R = 2.0 * np.sum(N * V, axis=1, keepdims=True) * N - V
    R /= np.linalg.norm(R, axis=1, keepdims=True)
    return R, V, theta_v
