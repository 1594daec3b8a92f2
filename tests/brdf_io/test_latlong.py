"""Lat-long geometry (brdf_io/latlong.py) pinned to the DESIGN §2 convention by closed forms."""

from __future__ import annotations

import numpy as np
import pytest

from shrmkit.brdf_io.latlong import (
    bilinear_lookup,
    default_gather_samples,
    direction_angles,
    gather_to_latlong,
    pixel_angles,
    pixel_directions,
    pixel_index,
    row_edges_cos,
    row_solid_angles,
    subsample_cos_theta,
    subsample_phi,
)


@pytest.mark.parametrize(("height", "width"), [(1, 2), (3, 5), (4, 8), (17, 34), (64, 128)])
def test_pixel_centres_closed_form(height, width):
    """Row i centre θ = (i + ½)π/H, column j centre φ = 2π(j + ½)/W, ω = (sin θ cos φ, sin θ sin φ, cos θ)."""
    theta, phi = pixel_angles(height, width)
    for i in range(height):
        assert theta[i] == pytest.approx((i + 0.5) * np.pi / height, abs=1e-15)
    for j in range(width):
        assert phi[j] == pytest.approx(2 * np.pi * (j + 0.5) / width, abs=1e-15)
    d = pixel_directions(height, width)
    assert d.shape == (height, width, 3) and d.dtype == np.float64
    i, j = height // 2, width - 1
    t, p = (i + 0.5) * np.pi / height, 2 * np.pi * (j + 0.5) / width
    np.testing.assert_allclose(d[i, j], [np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], atol=1e-15)
    np.testing.assert_allclose(np.linalg.norm(d, axis=-1), 1.0, atol=1e-15)
    # the top row is next to the zenith +z, φ grows from +x towards +y
    assert d[0, 0, 2] > 0 and (height == 1 or d[0, 0, 2] > d[1, 0, 2])
    back_theta, back_phi = direction_angles(d)
    np.testing.assert_allclose(back_theta, np.broadcast_to(theta[:, None], back_theta.shape), atol=1e-12)
    np.testing.assert_allclose(back_phi, np.broadcast_to(phi[None, :], back_phi.shape), atol=1e-12)


@pytest.mark.parametrize(("height", "width"), [(1, 2), (4, 8), (90, 180), (1000, 7)])
def test_solid_angles_closed_form(height, width):
    """Ω_i = (2π/W)(cos(iπ/H) − cos((i+1)π/H)) = (4π/W) sin((i+½)π/H) sin(π/2H); Σ over the map = 4π."""
    omega = row_solid_angles(height, width)
    i = np.arange(height)
    closed = (4 * np.pi / width) * np.sin((i + 0.5) * np.pi / height) * np.sin(np.pi / (2 * height))
    np.testing.assert_allclose(omega, closed, rtol=1e-10, atol=1e-300)
    assert omega.sum() * width == pytest.approx(4 * np.pi, rel=1e-13)
    edges = row_edges_cos(height)
    assert edges[0] == 1.0 and edges[-1] == -1.0 and np.all(np.diff(edges) < 0)


def test_pixel_index_inverts_pixel_directions():
    h, w = 7, 12
    rows, cols = pixel_index(pixel_directions(h, w), h, w)
    assert np.array_equal(rows, np.broadcast_to(np.arange(h)[:, None], (h, w)))
    assert np.array_equal(cols, np.broadcast_to(np.arange(w)[None, :], (h, w)))
    # the poles and the φ = 0 seam fall in the first/last row and the first column
    r, c = pixel_index(np.array([[0.0, 0.0, 1.0], [0.0, 0.0, -1.0], [1.0, 0.0, 0.0], [1.0, -1e-17, 0.0]]), h, w)
    assert r.tolist() == [0, h - 1, 3, 3] and c.tolist()[:3] == [0, 0, 0]


def test_bilinear_lookup_hits_pixel_centres_and_interpolates():
    rng = np.random.default_rng(5)
    image = rng.random((5, 10, 2))
    np.testing.assert_allclose(bilinear_lookup(image, pixel_directions(5, 10)), image, atol=1e-12)
    # halfway between the centres of columns 2 and 3 in row 1
    t, p = 1.5 * np.pi / 5, 2 * np.pi * 3.0 / 10
    d = np.array([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)])
    np.testing.assert_allclose(bilinear_lookup(image, d), 0.5 * (image[1, 2] + image[1, 3]), atol=1e-12)


def test_subsamples_are_equal_area_and_gather_keeps_constants():
    h, s = 6, 4
    cos_t = subsample_cos_theta(h, s)
    edges = row_edges_cos(h)
    # s sub-rows per row, uniform in cos θ between the row's edges
    np.testing.assert_allclose(np.diff(cos_t, axis=1), np.diff(edges)[:, None] / s * np.ones((1, s - 1)), atol=1e-15)
    np.testing.assert_allclose(cos_t.mean(axis=1), 0.5 * (edges[:-1] + edges[1:]), atol=1e-15)
    np.testing.assert_allclose(subsample_phi(12, s)[3], 2 * np.pi * (3 + (np.arange(s) + 0.5) / s) / 12)
    np.testing.assert_array_equal(subsample_cos_theta(h, s, np.array([2, 4])), cos_t[[2, 4]])
    # one texel of value 3 covering the sphere stays 3 everywhere
    out = gather_to_latlong(np.array([[3.0, 3.0, 3.0]]), lambda x, y, z: np.zeros(x.shape, np.int64), np.eye(3), h, s)
    assert out.shape == (h, 2 * h, 3)
    np.testing.assert_array_equal(out, 3.0)
    assert default_gather_samples(128, 512) == 8 and default_gather_samples(1024, 4) == 2
