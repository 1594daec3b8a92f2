"""Gauss–Legendre from ducc0 against closed forms and the exactness of the rule."""

import numpy as np
import pytest

from shrmkit.brdf_io.quadrature import gauss_legendre


def test_three_point_rule_is_the_textbook_one():
    x, w = gauss_legendre(3)
    np.testing.assert_allclose(x, [-np.sqrt(0.6), 0.0, np.sqrt(0.6)], atol=1e-15)
    np.testing.assert_allclose(w, [5 / 9, 8 / 9, 5 / 9], rtol=1e-14)


@pytest.mark.parametrize("n", [1, 2, 17, 200, 1025])
def test_rule_integrates_legendre_squares_exactly(n):
    """∫ P_l² = 2/(2l+1) for every l < n (degree 2l ≤ 2n − 1), nodes ascending inside (−1, 1)."""
    x, w = gauss_legendre(n)
    assert np.all(np.diff(x) > 0) and -1 < x[0] and x[-1] < 1
    assert not x.flags.writeable
    p0, p1 = np.ones_like(x), x.copy()
    assert abs(w.sum() - 2.0) < 1e-13
    for l in range(1, n):
        assert abs((w * p1 * p1).sum() * (2 * l + 1) / 2 - 1) < 1e-12, l
        p0, p1 = p1, ((2 * l + 1) * x * p1 - l * p0) / (l + 1)


def test_zero_nodes_is_refused():
    with pytest.raises(ValueError, match="n >= 1"):
        gauss_legendre(0)
