"""The fit's low-discrepancy points (``sampling.kronecker_points``) against closed forms."""

import numpy as np
import pytest

from shrmkit.analysis.fit.sampling import kronecker_points


def test_steps_are_the_generalised_golden_ratios():
    # d = 1: the golden ratio φ (φ² = φ + 1); d = 2: the plastic number (g³ = g + 1)
    u1 = kronecker_points(2, 1, seed=0)
    assert (u1[1, 0] - u1[0, 0]) % 1.0 == pytest.approx((np.sqrt(5.0) - 1.0) / 2.0, abs=1e-14)
    plastic = 1.324717957244746
    u2 = kronecker_points(2, 2, seed=0)
    assert (u2[1] - u2[0]) % 1.0 == pytest.approx([plastic**-1, plastic**-2], abs=1e-14)


def test_quadrature_error_is_quasi_monte_carlo_small():
    # ∫ ∏ (π/2) sin(π x_j) dx over [0, 1)^3 = 1; random points give an error ~ 1/√n ≈ 0.01
    u = kronecker_points(4096, 3, seed=7)
    assert u.shape == (4096, 3) and u.min() >= 0.0 and u.max() < 1.0
    estimate = np.mean(np.prod(0.5 * np.pi * np.sin(np.pi * u), axis=1))
    assert abs(estimate - 1.0) < 2e-3


def test_every_cell_is_filled_evenly_and_seeds_differ():
    u = kronecker_points(4096, 3, seed=1)
    counts = np.histogramdd(u, bins=(8, 8, 8), range=[(0, 1)] * 3)[0]
    assert counts.min() >= 4 and counts.max() <= 12  # 8 per cell on average; uniform random: 2 and 18
    assert np.array_equal(u, kronecker_points(4096, 3, seed=1))
    assert not np.allclose(u, kronecker_points(4096, 3, seed=2))
