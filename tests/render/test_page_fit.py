"""The view page's resampling, lookups and budget rule (``render/_page_fit.py``) against
independent slow references: the solid-angle-weighted mean of the overlapped pixels (explicit sums
and a dense overlap matrix built by loops), the bilinear lookup rule written out per direction
(``data_specs/view_html.md``, the rule the shader follows), and the budget rule's choice by
measuring every candidate whole."""

from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest

from shrmkit.brdf_io.errors import BadInputError
from shrmkit.brdf_io.latlong import bilinear_lookup, pixel_directions, row_edges_cos
from shrmkit.render._page_fit import (
    _area_resample,
    _atlas_fits,
    _lookup,
    _lookup_matrix,
    _sphere_samples,
    _texel_major,
    fit_coefficients,
)


def _dense_area_mean(maps: np.ndarray, h: int, w: int) -> np.ndarray:
    """Each new pixel: Σ overlap solid angle × value / its own solid angle, by an explicit sum."""
    _, H, W, _ = maps.shape
    mu, mu_new = 1.0 - row_edges_cos(H), 1.0 - row_edges_cos(h)
    out = np.zeros((maps.shape[0], h, w, 3))
    for i in range(h):
        for j in range(w):
            total = np.zeros((maps.shape[0], 3))
            for a in range(H):
                dy = max(0.0, min(mu_new[i + 1], mu[a + 1]) - max(mu_new[i], mu[a]))
                if dy == 0.0:
                    continue
                for b in range(W):
                    dx = max(0.0, min((j + 1) / w, (b + 1) / W) - max(j / w, b / W))
                    total += dy * dx * maps[:, a, b]
            out[:, i, j] = total / ((mu_new[i + 1] - mu_new[i]) / w)
    return out


def _dense_overlap(src: np.ndarray, dst: np.ndarray) -> np.ndarray:
    """(len(dst)−1, len(src)−1): the fraction of each new interval each old one covers, by loops."""
    m = np.zeros((len(dst) - 1, len(src) - 1))
    for i in range(len(dst) - 1):
        for a in range(len(src) - 1):
            m[i, a] = max(0.0, min(dst[i + 1], src[a + 1]) - max(dst[i], src[a])) / (dst[i + 1] - dst[i])
    return m


def _dense_resample(maps: np.ndarray, h: int, w: int) -> np.ndarray:
    """The area means as two dense overlap matrices (rows in 1 − cos θ, columns in φ), float64."""
    _, H, W, _ = maps.shape
    rows = _dense_overlap(1.0 - row_edges_cos(H), 1.0 - row_edges_cos(h))
    cols = _dense_overlap(np.linspace(0.0, 1.0, W + 1), np.linspace(0.0, 1.0, w + 1))
    return np.einsum("jb,nibc->nijc", cols, np.einsum("ia,nabc->nibc", rows, maps.astype(np.float64)))


def _bilinear_loop(maps: np.ndarray, dirs: np.ndarray) -> np.ndarray:
    """(N, n, 3): the lookup rule written out one direction at a time: y = θH/π − ½ clamped to the
    row centres, x = φW/2π − ½ wrapping, the four neighbours weighted bilinearly."""
    _, H, W, _ = maps.shape
    out = np.zeros((len(dirs), maps.shape[0], 3))
    for s, (dx, dy, dz) in enumerate(dirs):
        theta = math.acos(min(1.0, max(-1.0, dz)))
        phi = math.atan2(dy, dx) % (2.0 * math.pi)
        y = min(max(theta * H / math.pi - 0.5, 0.0), H - 1.0)
        x = phi * W / (2.0 * math.pi) - 0.5
        y0 = min(int(math.floor(y)), max(H - 2, 0))
        fy, fx = y - y0, x - math.floor(x)
        y1, x0 = min(y0 + 1, H - 1), int(math.floor(x)) % W
        x1 = (x0 + 1) % W
        top = (1 - fx) * maps[:, y0, x0].astype(float) + fx * maps[:, y0, x1]
        bottom = (1 - fx) * maps[:, y1, x0].astype(float) + fx * maps[:, y1, x1]
        out[s] = (1 - fy) * top + fy * bottom
    return out


def _looked_up(maps: np.ndarray, dirs: np.ndarray) -> np.ndarray:
    """The module's lookups of (n, h, w, 3) maps at ``dirs`` as (N, n, 3)."""
    n, h, w, _ = maps.shape
    return np.moveaxis(_lookup(_texel_major(maps), _lookup_matrix(dirs, h, w)).reshape(len(dirs), 3, n), 2, 1)


def test_area_resample_is_the_solid_angle_mean_of_the_overlapped_pixels() -> None:
    rng = np.random.default_rng(3)
    for H, W, h, w in [(12, 24, 5, 7), (9, 1, 4, 1), (8, 16, 8, 16)]:
        maps = rng.random((2, H, W, 3), dtype=np.float32) * 4.0
        np.testing.assert_allclose(_area_resample(maps, h, w), _dense_area_mean(maps.astype(float), h, w),
                                   rtol=2e-6, atol=1e-6)


def test_area_resample_is_the_dense_overlap_product_in_chunks_of_maps() -> None:
    """Signed maps (as coefficient maps are), several chunks of maps and band widths from 1 to 9
    rows or columns (h, w not dividing H, W): a band edge one off changes the means by ~1/band."""
    rng = np.random.default_rng(5)
    for n, H, W, h, w in [(37, 40, 80, 9, 17), (5, 31, 62, 30, 61), (3, 17, 5, 16, 3), (2, 6, 12, 6, 12)]:
        maps = rng.normal(size=(n, H, W, 3)).astype(np.float32)
        np.testing.assert_allclose(_area_resample(maps, h, w, chunk=16), _dense_resample(maps, h, w),
                                   rtol=0, atol=2e-6)


def test_lookup_is_the_bilinear_lookup_at_poles_seams_and_one_column_maps() -> None:
    rng = np.random.default_rng(4)
    d = rng.normal(size=(500, 3))
    d = np.concatenate([d / np.linalg.norm(d, axis=1, keepdims=True), [[0, 0, 1.0], [0, 0, -1.0], [1, 0, 0]]])
    for h, w in [(6, 12), (5, 1), (1, 3)]:
        maps = rng.random((3, h, w, 3), dtype=np.float32)
        dirs = np.concatenate([d, pixel_directions(h, w).reshape(-1, 3)])
        want = np.stack([bilinear_lookup(m.astype(float), dirs) for m in maps], axis=1)
        np.testing.assert_allclose(_looked_up(maps, dirs), want, rtol=1e-6, atol=1e-7)


def test_lookup_of_many_maps_is_the_rule_written_out_per_direction() -> None:
    """20 signed maps looked up together (texel-major rows of 60 values) at 300 directions and the
    pixel centres, against the rule applied one direction at a time."""
    rng = np.random.default_rng(6)
    d = rng.normal(size=(300, 3))
    for h, w in [(7, 13), (2, 4)]:
        maps = rng.normal(size=(20, h, w, 3)).astype(np.float32)
        dirs = np.concatenate([d / np.linalg.norm(d, axis=1, keepdims=True), pixel_directions(h, w).reshape(-1, 3)])
        np.testing.assert_allclose(_looked_up(maps, dirs), _bilinear_loop(maps, dirs), rtol=0, atol=1e-6)


def _lookups(maps: np.ndarray, dirs: np.ndarray) -> np.ndarray:
    """(N, n, 3): ``brdf_io.latlong.bilinear_lookup`` of each map, in float64."""
    return np.stack([bilinear_lookup(m.astype(np.float64), dirs) for m in maps], axis=1)


def _fit_by_every_candidate(coeffs: np.ndarray, P: int, max_bytes: int, samples: int
                            ) -> tuple[int, tuple[int, int], float]:
    """The budget rule of ``data_specs/view_html.md`` by measuring every candidate whole, with the
    dense resampling and ``bilinear_lookup``: (P', (h, w), added relative RMS) of the least error,
    ties to the larger P'."""
    n, H, W, _ = coeffs.shape
    dirs = _sphere_samples(samples)
    given = _lookups(coeffs, dirs)  # (N, n, 3)
    energy = 4.0 * np.pi / samples * (given**2).sum(axis=(0, 2))
    found = []
    for p in range(P, -1, -1):
        h = next((h for h in range(H, 0, -1)
                  if _atlas_fits(p, h, max(1, round(h * W / H)), max_bytes, 2048)), 0)
        if h < 8:
            continue
        m, w = (p + 1) ** 2, max(1, round(h * W / H))
        err = float(energy[m:].sum())
        if h < H:
            diff = _lookups(_dense_resample(coeffs[:m], h, w), dirs) - given[:, :m]
            err += 4.0 * np.pi / samples * float((diff**2).sum())
        found.append((err, -p, h, w))
        if h >= H:
            break
    err, p, h, w = min(found)
    return -p, (h, w), math.sqrt(err / energy.sum())


def test_budget_rule_is_the_least_error_over_every_candidate() -> None:
    """The best-first search (each candidate's maps measured only until its error passes the
    least) against measuring every candidate whole, on SHRM-like maps (energy falling with the
    view order p, detail rising with it) under budgets whose winners are a middle P' at fewer rows
    (two budgets: 12 and 22 rows) and at full resolution."""
    rng = np.random.default_rng(7)
    P, H, W = 5, 24, 48
    pix = pixel_directions(H, W)
    coeffs = np.empty(((P + 1) ** 2, H, W, 3), np.float32)
    for i in range((P + 1) ** 2):
        p = math.isqrt(i)
        lobes = sum(np.exp((2.0 + 6.0 * p) * (pix @ (v / np.linalg.norm(v)) - 1.0)) for v in rng.normal(size=(3, 3)))
        coeffs[i] = (lobes[..., None] * rng.uniform(0.5, 1.5, 3) * 0.35**p * rng.choice([-1.0, 1.0])).astype(np.float32)
    winners = set()
    for max_bytes in (27648, 110592, 150000):
        fit = fit_coefficients(coeffs, P, max_bytes, samples=512)
        p, shape, rel = _fit_by_every_candidate(coeffs, P, max_bytes, samples=512)
        assert (fit.P, fit.coeffs.shape[1:3]) == (p, shape)
        assert fit.added_rel_rms == pytest.approx(rel, rel=1e-5, abs=1e-9)
        if shape[0] < H:
            np.testing.assert_allclose(fit.coeffs, _dense_resample(coeffs[:(p + 1) ** 2], *shape), rtol=0, atol=2e-6)
        winners.add((p, shape[0] == H))
    assert len(winners) >= 3, winners
    # one NaN or inf texel would decide the choice (every resampled candidate's error NaN): refused
    for bad in (np.nan, np.inf, -np.inf):
        broken = coeffs.copy()
        broken[8, 3, 5, 1] = bad
        with pytest.raises(BadInputError, match="NaN or infinite"):
            fit_coefficients(broken, P, 27648, samples=512)
    assert fit_coefficients(broken, P, 10**7).P == P  # maps that fit as they are: nothing is fitted


def test_a_view_page_imports_no_scipy() -> None:
    """The page's fit used scipy.sparse: with it, ~0.3-0.4 s CPU of every report and ``shrm view``."""
    code = ("import sys, shrmkit\n"
            "from shrmkit.render.webgl_page import view_html\n"
            "env = shrmkit.load_env('builtin:sky,height=16')\n"
            "view_html(shrmkit.prefilter(env, 'microfacet:sigma=0.3', eps=0.1), env)\n"
            "print(sorted(m for m in sys.modules if m == 'scipy' or m.startswith('scipy.')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert out == "[]"


def test_an_infinite_pixel_reaches_only_the_pixels_that_overlap_it() -> None:
    """Entries a banded row does not hold (padding, merged duplicates) are skipped, not multiplied
    by 0: an infinite texel gives inf where it is read and nothing (not NaN) elsewhere."""
    maps = np.ones((1, 7, 11, 3), dtype=np.float32)
    maps[0, 3, 5] = np.inf
    out = _area_resample(maps, 3, 4)[0]
    mu, mu_new = 1.0 - row_edges_cos(7), 1.0 - row_edges_cos(3)
    rows = [(mu_new[i] < mu[4]) and (mu_new[i + 1] > mu[3]) for i in range(3)]
    cols = [(j / 4 < 6 / 11) and ((j + 1) / 4 > 5 / 11) for j in range(4)]
    hit = np.outer(rows, cols)
    assert np.isposinf(out[hit]).all() and np.isfinite(out[~hit]).all()
    every_other = np.ones((1, 7, 11, 3), dtype=np.float32)
    every_other[0, :, ::2] = np.inf  # the first column of padded rows: padding read it as 0 · inf = NaN
    assert np.isposinf(_area_resample(every_other, 3, 4)).all()
    # the lookups follow bilinear_lookup there too (a neighbour's weight 0 times inf is NaN in both)
    dirs = pixel_directions(7, 11).reshape(-1, 3)
    with np.errstate(invalid="ignore"):
        np.testing.assert_array_equal(_looked_up(maps, dirs)[:, 0], bilinear_lookup(maps[0].astype(float), dirs))
