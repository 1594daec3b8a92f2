"""The per-band statement carried to a render's pixels (issue 29): ``band_signal_energy`` against a
closed form, ``pixels_statement`` against hand-computed factors."""

from __future__ import annotations

import numpy as np
import pytest

from shrmkit.analysis.compare.band_error import band_sample, band_signal_energy, pixels_statement

EDGES = (0.0, 30.0, 60.0, 90.0)


def test_band_signal_energy_is_the_uniform_mean_under_importance_sampling():
    """B(R, V) = (R_z, R_z, R_z): |B|² = 3 R_z², whose mean over R uniform on the sphere is 3 · 1/3 = 1
    in every band (B does not depend on V), however the sampler's density leans toward a map's
    bright pixel (a 1000× pixel near the pole: weights (1/4π)/q must undo it)."""
    radiance = np.ones((32, 64, 3))
    radiance[2, 5] = 1000.0
    energy = band_signal_energy(lambda R, V: np.repeat(R[:, 2:3], 3, axis=1), radiance, EDGES, per_band=2000, seed=3)
    np.testing.assert_allclose(energy, 1.0, rtol=0.05)
    unweighted = np.mean(3.0 * band_sample(radiance, 2000, EDGES, seed=3).R[:, 2] ** 2)
    assert unweighted > 2.0  # what the weights undo: most pairs look at the bright pixel near the pole
    # a V-dependent B on a constant map (uniform density, weights 1): |B|² = 3 (R·V)² = 3 cos²(2θ_v),
    # whose mean over θ_v uniform in [a, b) is 3/2 (1 + (sin 4b − sin 4a) / (4 (b − a)))
    energy = band_signal_energy(lambda R, V: np.repeat(np.sum(R * V, axis=1)[:, None], 3, axis=1),
                                np.ones((32, 64, 3)), EDGES, per_band=500, seed=4)
    a, b = np.radians(EDGES[:-1]), np.radians(EDGES[1:])
    np.testing.assert_allclose(energy, 1.5 * (1 + (np.sin(4 * b) - np.sin(4 * a)) / (4 * (b - a))), rtol=1e-3)


def test_pixels_statement_factors():
    """Band 0: pixels 4× dimmer in energy than the band → r × 2; band 1: pixels brighter → r itself
    (factor 1); band 2: no pixel → factor 1, ratio NaN."""
    bands = [{"theta_v_deg": [lo, hi], "predicted_rel_rms": 0.01 * (k + 1), "bound_rel_rms": 0.02 * (k + 1)}
             for k, (lo, hi) in enumerate(zip(EDGES[:-1], EDGES[1:], strict=True))]
    values = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 1.0], [3.0, 0.0, 0.0]])  # |B|² 1, 2 (band 0), 9 (band 1)
    theta = np.array([10.0, 20.0, 45.0])
    out = pixels_statement(bands, np.array([6.0, 4.5, 1.0]), values, theta)
    assert [r["pixels"] for r in out] == [2, 1, 0]
    np.testing.assert_allclose([r["energy_ratio"] for r in out[:2]], [6.0 / 1.5, 0.5])
    assert np.isnan(out[2]["energy_ratio"])
    np.testing.assert_allclose([r["factor"] for r in out], [2.0, 1.0, 1.0])
    np.testing.assert_allclose([r["predicted_rel_rms"] for r in out], [0.02, 0.02, 0.03])
    np.testing.assert_allclose([r["bound_rel_rms"] for r in out], [0.04, 0.04, 0.06])
    assert [r["stated_bound_rel_rms"] for r in out] == [0.02, 0.04, 0.06]
    with pytest.raises(ValueError, match="one energy per band"):
        pixels_statement(bands, np.ones(2), values, theta)
