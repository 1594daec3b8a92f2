"""Cabral et al. 1999 (RSIBR) comparator: icosahedron, spherical barycentric weights, maps.

References: the closed-form area of the sphere (4π) and of an icosahedron face (4π/20);
the brute-force angular integral of analysis.reference (RH02 eq. 2) at the sample views.
"""

from __future__ import annotations

import numpy as np
import pytest

from shrmkit.analysis.baselines.icosahedron import barycentric_weights, icosahedron, spherical_excess
from shrmkit.analysis.baselines.rsibr import rsibr_reference, warp_normal
from shrmkit.analysis.reference import reference_radiance
from shrmkit.brdf_io.envmap import load_env
from shrmkit.brdf_io.latlong import pixel_directions
from shrmkit.brdf_io.specs import load_brdf


@pytest.fixture(scope="module")
def env():
    return load_env("builtin:studio,height=16")


def _unit(n: int, seed: int) -> np.ndarray:
    x = np.random.default_rng(seed).normal(size=(n, 3))
    return x / np.linalg.norm(x, axis=1, keepdims=True)


def test_icosahedron_faces_tile_the_sphere() -> None:
    """12 unit vertices, 20 counter-clockwise faces of equal area 4π/20 (closed form)."""
    v, f = icosahedron()
    assert v.shape == (12, 3) and f.shape == (20, 3)
    np.testing.assert_allclose(np.linalg.norm(v, axis=1), 1.0, atol=1e-15)
    area = spherical_excess(v[f[:, 0]], v[f[:, 1]], v[f[:, 2]])
    np.testing.assert_allclose(area, 4.0 * np.pi / 20.0, rtol=1e-12)


def test_barycentric_weights_nonnegative_sum_to_one_and_interpolate_vertices() -> None:
    """Inside each face the three sub-triangle areas are >= 0 and add up to the face area
    (the weights are returned unclipped and unnormalized, so this is a geometric check);
    at a vertex all weight sits on that vertex; barycentric weights of a face's centroid
    direction are 1/3 each (symmetry)."""
    v, f = icosahedron()
    idx, w = barycentric_weights(_unit(5000, 1))
    assert w.min() >= -1e-12
    np.testing.assert_allclose(w.sum(axis=1), 1.0, atol=1e-12)
    idx, w = barycentric_weights(v)
    for i in range(12):
        assert w[i, list(idx[i]).index(i)] == pytest.approx(1.0, abs=1e-12)
    c = v[f].sum(axis=1)
    c /= np.linalg.norm(c, axis=1, keepdims=True)
    idx, w = barycentric_weights(c)
    np.testing.assert_allclose(w, 1.0 / 3.0, atol=1e-12)
    assert np.all(np.sort(idx, axis=1) == np.sort(f, axis=1))


def test_warp_normal_reflects_sample_view_into_r() -> None:
    """n_i = normalize(v_i + r) reflects v_i into r: 2(n·v_i)n − v_i = r (the identity that
    makes the reflection-space warp of an R-indexed map the identity lookup)."""
    r, vi = _unit(100, 2), _unit(100, 3)
    n = warp_normal(r, vi)
    refl = 2.0 * np.sum(n * vi, axis=1, keepdims=True) * n - vi
    np.testing.assert_allclose(refl, r, atol=1e-12)


def test_cabral_reproduces_reference_at_sample_views(env) -> None:
    """At v = v_i the reconstruction is map i: equal to the angular reference at the map's
    pixel centres (float32 storage only) and within map resolution between them."""
    brdf = load_brdf("microfacet:sigma=0.4")
    maps = rsibr_reference(env, brdf, 16)
    centres = pixel_directions(16, 32).reshape(-1, 3)[::5]
    for i, vi in enumerate(maps.views[::3]):
        V = np.broadcast_to(vi, centres.shape)
        ref = reference_radiance(env, brdf, centres, V)
        np.testing.assert_allclose(maps.radiance(centres, V), ref, rtol=1e-5, atol=1e-6 * ref.max())
        R = _unit(200, 10 + i)
        R = R[np.sum(R * vi, axis=1) > -0.5]  # away from the r = −v_i singularity
        ref = reference_radiance(env, brdf, R, np.broadcast_to(vi, R.shape))
        err = np.sqrt(np.mean((maps.radiance(R, np.broadcast_to(vi, R.shape)) - ref) ** 2) / np.mean(ref**2))
        assert err < 0.03
