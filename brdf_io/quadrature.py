"""Gauss–Legendre quadrature on [−1, 1], from ducc0 (one cached table per node count)."""

from __future__ import annotations

from functools import lru_cache

import ducc0
import numpy as np

__all__ = ["gauss_legendre"]


@lru_cache(maxsize=128)
def gauss_legendre(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss–Legendre nodes x (n,) ascending in (−1, 1) and weights w (n,), read-only float64.

    ``ducc0.misc.GL_thetas``/``GL_weights`` (the nodes as colatitudes θ, x = cos θ; weights of a
    ring of one pixel, 2π w): the same rule as ``scipy.special.roots_legendre`` and
    ``numpy.polynomial.legendre.leggauss``, more accurate at high n (Σ w P_l² = 2/(2l+1) to 2e-13 for
    every l < n at n = 2049, against 5e-11 for SciPy's) and without importing ``scipy.special``
    (~0.4 s of start-up).

    Raises
    ------
    ValueError
        n < 1.
    """
    if n < 1:
        raise ValueError(f"Gauss-Legendre needs n >= 1 nodes, got {n}")
    x = np.cos(ducc0.misc.GL_thetas(n))[::-1].copy()
    w = (ducc0.misc.GL_weights(n, 1) / (2.0 * np.pi))[::-1].copy()
    x.setflags(write=False)
    w.setflags(write=False)
    return x, w
