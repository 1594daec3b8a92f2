"""The per-band statement of an SHRM carried to a render's pixels (issue 29): ``pixels_statement``
against hand-computed values on a stand-in SHRM whose reflection is known in closed form."""

from __future__ import annotations

import numpy as np
import pytest

from shrmkit.analysis.compare.band_error import pixels_statement
from shrmkit.analysis.error_image import band_signal

EDGES = (0.0, 30.0, 60.0, 90.0)


class _Constant:
    """A stand-in SHRM: B(R, V) = (c, c, c) everywhere, no lights, stated r = 1, 2, 3 % (predicted)
    and 2, 4, 6 % (bound) per band."""

    has_lights = False

    def __init__(self, c: float):
        self.c = c
        self.meta = {"view_bands": [
            {"theta_v_deg": [lo, hi], "predicted_rel_rms": 0.01 * (k + 1), "bound_rel_rms": 0.02 * (k + 1)}
            for k, (lo, hi) in enumerate(zip(EDGES[:-1], EDGES[1:], strict=True))]}

    def radiance(self, R, V, lights=True):
        return np.full((np.asarray(R).shape[0], 3), self.c)


def test_pixels_statement_takes_the_larger_of_the_relative_and_the_spread_error():
    """The band's absolute RMS is e_b = r_b · c (the SHRM's RMS is c in every band). Band 0: pixels of
    RMS c/2 (dark) → r_pix = e_b / (c/2) = 2 r; band 1: pixels of RMS 3c (bright) → r itself (the
    spread model would say r/3); band 2: no pixel → r."""
    shrm = _Constant(2.0)
    c = shrm.c
    values = np.array([[c / 2] * 3, [c / 2] * 3, [3 * c, 3 * c, 3 * c]])
    theta = np.array([10.0, 20.0, 45.0])
    signal = band_signal(shrm, pairs_per_band=8)
    np.testing.assert_allclose(signal.rms, c)
    out = pixels_statement(shrm, values, theta, signal=signal)
    assert [r["pixels"] for r in out] == [2, 1, 0]
    np.testing.assert_allclose([r["predicted_rel_rms"] for r in out], [0.02, 0.02, 0.03])
    np.testing.assert_allclose([r["bound_rel_rms"] for r in out], [0.04, 0.04, 0.06])
    np.testing.assert_allclose([r["factor"] for r in out], [2.0, 1.0, 1.0])
    assert [r["stated_bound_rel_rms"] for r in out] == [0.02, 0.04, 0.06]
    # an uneven band: pixels c/2 and c·√(7/4)... RMS² = (1/4 + 7/4)/2 = 1 → r_pix = r (factor 1)
    out = pixels_statement(shrm, np.array([[c / 2] * 3, [c * np.sqrt(7 / 4)] * 3]), np.array([5.0, 25.0]),
                           signal=signal)
    np.testing.assert_allclose(out[0]["predicted_rel_rms"], 0.01)
    with pytest.raises(ValueError, match=r"values \(n, 3\)"):
        pixels_statement(shrm, values, theta[:2], signal=signal)


def test_a_band_without_a_statement_has_no_factor():
    """A band that states nothing (None) reads as NaN — its r and its factor — never 0 or 1."""
    shrm = _Constant(2.0)
    shrm.meta["view_bands"][1]["predicted_rel_rms"] = None
    signal = band_signal(_Constant(2.0), pairs_per_band=8)
    out = pixels_statement(shrm, np.array([[1.0] * 3, [1.0] * 3]), np.array([10.0, 45.0]), signal=signal)
    assert np.isnan(out[1]["stated_predicted_rel_rms"]) and np.isnan(out[1]["factor"])
    assert out[0]["factor"] > 0.0 and not np.isnan(out[0]["factor"])
