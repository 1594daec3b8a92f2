"""Map rows with fast FFTs (analysis.synthesis.fast_rows): checked by factorizing, and a prefilter's
map against the rows its rule asks for."""

from __future__ import annotations

import numpy as np

import shrmkit
from shrmkit.analysis.map_size import default_size
from shrmkit.analysis.synthesis import fast_rows, sample_rows


def _largest_prime_factor(n: int) -> int:
    f, p = 1, 2
    while n > 1:
        while n % p == 0:
            f, n = p, n // p
        p += 1
    return f


def test_fast_rows_is_the_smallest_smooth_size_at_or_above():
    for rows in [1, 2, 17, 89, 97, 127, 257, 1000]:
        for multiple in (1, 4):
            S = fast_rows(rows, multiple)
            assert S >= rows and S % multiple == 0
            assert _largest_prime_factor(2 * S) <= 11, (rows, multiple, S)
            # nothing smaller qualifies (brute force over the multiples in between)
            for smaller in range(S - multiple, rows - 1, -multiple):
                if smaller >= 1:
                    assert _largest_prime_factor(2 * smaller) > 11
    assert fast_rows(89) == 90 and fast_rows(97) == 98 and fast_rows(257) == 264


def test_sample_rows_stay_multiples_of_four_with_smooth_rings():
    for F in range(0, 200, 7):
        for P in (0, 3, 17):
            rows = sample_rows(F, P)
            assert rows % 4 == 0 and rows >= max(16, 2.5 * (F + P) + 2)
            assert _largest_prime_factor(2 * rows) <= 11


def test_prefilter_map_rows_are_smooth_and_within_the_budget():
    shrm = shrmkit.prefilter("builtin:sky,height=32", "microfacet:sigma=0.1", eps=0.01, max_F=96)
    S = shrm.height
    assert _largest_prime_factor(2 * S) <= 11
    assert S <= default_size(shrm.F, shrm.P)  # within the memory budget
    assert np.all(np.isfinite(shrm.coeffs))
