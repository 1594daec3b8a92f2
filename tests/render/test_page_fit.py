"""The view page's resampling and lookups (``render/_page_fit.py``) against independent dense
references: the solid-angle-weighted mean of the overlapped pixels, and
``brdf_io.latlong.bilinear_lookup`` (the rule the shader follows)."""

from __future__ import annotations

import subprocess
import sys

import numpy as np

from shrmkit.brdf_io.latlong import bilinear_lookup, pixel_directions, row_edges_cos
from shrmkit.render._page_fit import _area_resample, _lookup


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


def test_area_resample_is_the_solid_angle_mean_of_the_overlapped_pixels() -> None:
    rng = np.random.default_rng(3)
    for H, W, h, w in [(12, 24, 5, 7), (9, 1, 4, 1), (8, 16, 8, 16)]:
        maps = rng.random((2, H, W, 3), dtype=np.float32) * 4.0
        np.testing.assert_allclose(_area_resample(maps, h, w), _dense_area_mean(maps.astype(float), h, w),
                                   rtol=2e-6, atol=1e-6)


def test_lookup_is_the_bilinear_lookup_at_poles_seams_and_one_column_maps() -> None:
    rng = np.random.default_rng(4)
    d = rng.normal(size=(500, 3))
    d = np.concatenate([d / np.linalg.norm(d, axis=1, keepdims=True), [[0, 0, 1.0], [0, 0, -1.0], [1, 0, 0]]])
    for h, w in [(6, 12), (5, 1), (1, 3)]:
        maps = rng.random((3, h, w, 3), dtype=np.float32)
        dirs = np.concatenate([d, pixel_directions(h, w).reshape(-1, 3)])
        want = np.stack([bilinear_lookup(m.astype(float), dirs) for m in maps], axis=1)
        np.testing.assert_allclose(_lookup(maps, dirs), want, rtol=1e-6, atol=1e-7)


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
        np.testing.assert_array_equal(_lookup(maps, dirs)[:, 0], bilinear_lookup(maps[0].astype(float), dirs))
