"""Self-shadowing (Green, Kautz & Durand 2007 eq. 7): per-vertex SH-4 visibility by ray casting.

References: the closed-form SH projection of a hemisphere step (Funk–Hecke, checked here
against direct quadrature of ∫ Y_l0 over the hemisphere) for every vertex of a convex
sphere; the closed-form projection of a spherical cap for the bottom of a hemispherical
bowl (visible directions: the 45° cone through the rim); the unshadowed CPU render of the
same Gaussian lobes on a torus (inner ring darker, outer half unchanged).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import integrate

from shrmkit.analysis.baselines.gaussian_lobes import GaussianLobeModel, fit_gaussian_lobes, sg_mip_stack
from shrmkit.analysis.baselines.selfshadow import (
    hemisphere_step_sh,
    hemisphere_step_zonal,
    vertex_visibility_sh,
    visibility_at,
    visibility_hook,
)
from shrmkit.analysis.sh import real_sph_harm
from shrmkit.brdf_io.errors import BadInputError
from shrmkit.brdf_io.specs import load_brdf
from shrmkit.render.camera import Camera
from shrmkit.render.cpu_reference import interpolate_vertex_data, mesh_geometry, shade
from shrmkit.render.mesh import load_mesh, make_mesh


def test_step_closed_form_against_hemisphere_quadrature() -> None:
    """c_l0 of the step about +z = ∫_{z>0} Y_l0 dω by adaptive quadrature; S(1) = 13/16 by hand."""
    c = hemisphere_step_sh(np.array([0.0, 0.0, 1.0]), order=4)
    for l in range(5):
        def y(theta, l=l):
            d = np.array([np.sin(theta), 0.0, np.cos(theta)])
            return real_sph_harm(4, d)[l * l + l] * 2.0 * np.pi * np.sin(theta)

        ref, _ = integrate.quad(y, 0.0, np.pi / 2, epsabs=1e-13)
        assert c[l * l + l] == pytest.approx(ref, abs=1e-10)
    assert hemisphere_step_zonal(1.0) == pytest.approx(13.0 / 16.0, abs=1e-14)  # 1/2 + 3/4 − 7/16
    assert hemisphere_step_zonal(0.0) == pytest.approx(0.5, abs=1e-14)


def test_convex_sphere_visibility_is_the_hemisphere_step() -> None:
    """(a) On a convex icosphere every vertex sees exactly its upper hemisphere: projected
    coefficients = closed-form step about the vertex normal within 1e-2 (measured ~1e-14)."""
    sphere = load_mesh("builtin:sphere:subdivisions=2")
    c = vertex_visibility_sh(sphere, n_dirs=256)
    ref = hemisphere_step_sh(sphere.normals)
    assert c.shape == (162, 25)
    assert np.max(np.abs(c - ref)) < 1e-2
    # V evaluated from the SH: the truncated step, and exactly 1 once normalized
    rng = np.random.default_rng(0)
    d = rng.normal(size=(162, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    t = np.sum(d * sphere.normals, axis=1)
    assert np.allclose(visibility_at(c, d), np.clip(hemisphere_step_zonal(t), 0.0, 1.0), atol=1e-2)
    up = t > 0.05
    assert np.allclose(visibility_at(c[up], d[up], sphere.normals[up]), 1.0, atol=1e-6)


def bowl(n_rings: int = 16, n_seg: int = 64):
    """Inside of a unit hemispherical bowl (bottom at −z, rim on z = 0), normals pointing inward."""
    alpha = np.arange(1, n_rings + 1) * (np.pi / 2) / n_rings
    phi = np.arange(n_seg) * 2.0 * np.pi / n_seg
    A, P = np.meshgrid(alpha, phi, indexing="ij")
    ring = np.stack([np.sin(A) * np.cos(P), np.sin(A) * np.sin(P), -np.cos(A)], -1).reshape(-1, 3)
    v = np.vstack([[0.0, 0.0, -1.0], ring])
    faces = [[0, 1 + j, 1 + (j + 1) % n_seg] for j in range(n_seg)]
    for i in range(n_rings - 1):
        for j in range(n_seg):
            a, b = 1 + i * n_seg + j, 1 + i * n_seg + (j + 1) % n_seg
            faces += [[a, a + n_seg, b], [b, a + n_seg, b + n_seg]]
    return make_mesh(v, np.array(faces), -v, name="bowl", normalize=False)


def test_bowl_bottom_sees_the_cone_through_the_rim() -> None:
    """Bottom of a hemispherical bowl: V = 1 within 45° of +z (the rim seen from the bottom),
    0 elsewhere: c_l0 = 2π ∫_{cos 45°}^1 P_l dt · √((2l+1)/4π), c_lm = 0 otherwise. Tolerance
    3e-2: the Gauss–Legendre rows straddle the cap edge (and the rim is a 64-gon)."""
    mesh = bowl()
    c = vertex_visibility_sh(mesh, n_dirs=20000, vertices=np.array([0]))[0]
    ref = np.zeros(25)
    t0 = np.cos(np.pi / 4)
    for l in range(5):
        p = np.polynomial.legendre.Legendre.basis(l).integ()
        ref[l * l + l] = 2.0 * np.pi * (p(1.0) - p(t0)) * np.sqrt((2 * l + 1) / (4.0 * np.pi))
    assert np.max(np.abs(c - ref)) < 3e-2
    # far less than the unoccluded hemisphere: visible solid angle 2π(1 − cos 45°) = 1.84 sr vs 2π
    assert c[0] / hemisphere_step_sh(np.array([0.0, 0.0, 1.0]))[0] == pytest.approx(1.0 - t0, abs=0.02)


@pytest.fixture(scope="module")
def torus_renders():
    """CPU renders of a torus under a constant environment: Gaussian lobes fitted to Phong s=8,
    without and with self-shadowing (normalized and plain SH visibility)."""
    torus = load_mesh("builtin:torus:segments=48,sides=16")
    lobes = fit_gaussian_lobes(load_brdf("phong:s=8"), K=3, n_elevations=8, n_theta=48, n_psi=24)
    glr = GaussianLobeModel(lobes, sg_mip_stack(np.ones((32, 64, 3))))
    coeffs = vertex_visibility_sh(torus, n_dirs=512)
    cam = Camera.looking_at(view=(0.5, -0.3, 1.0), projection="perspective")
    geom = mesh_geometry(cam, 56, 56, torus)
    per_pixel = interpolate_vertex_data(geom, torus, coeffs)
    n_hit = geom.N[geom.hit]
    steps = interpolate_vertex_data(geom, torus, hemisphere_step_sh(torus.normals))
    plain = shade(geom, glr.radiance)[geom.hit, 1]
    shadowed = shade(geom, lambda R, V: glr.radiance(R, V, visibility=visibility_hook(per_pixel, n_hit, steps)))
    raw = shade(geom, lambda R, V: glr.radiance(R, V, visibility=visibility_hook(per_pixel)))
    pos = geom.position[geom.hit]
    rho = np.linalg.norm(pos[:, :2], axis=1)
    radial = np.sum(n_hit[:, :2] * pos[:, :2], axis=1) / np.maximum(rho, 1e-12)
    return plain, shadowed[geom.hit, 1], raw[geom.hit, 1], rho, radial


def test_concavity_receives_less_light(torus_renders) -> None:
    """(b) Inner ring of the torus (distance from the axis < 0.55, inside the hole, facing the
    opposite side of the ring): mean radiance ratio shadowed / unshadowed well below 1."""
    plain, shadowed, _, rho, radial = torus_renders
    inner = (rho < 0.55) & (radial < -0.3)
    assert inner.sum() > 50
    ratio = shadowed[inner] / plain[inner]
    assert np.mean(ratio) < 0.8
    assert np.all(ratio <= 1.0 + 1e-9)


def test_unoccluded_points_unchanged(torus_renders) -> None:
    """(c) Outer half of the torus (on its convex hull, nothing above the tangent plane):
    normalized visibility leaves the radiance unchanged within 2 %; plain SH-4 visibility
    scales each lobe by about the truncated step S(t) ∈ [0.5, 1.07], so the ratio stays in that
    range (± 0.06: blending steps about the three vertex normals of a 16-sided tube)."""
    plain, shadowed, raw, rho, radial = torus_renders
    outer = (rho > 0.72) & (radial > 0.3)
    assert outer.sum() > 50
    ratio = shadowed[outer] / plain[outer]
    assert np.max(np.abs(ratio - 1.0)) < 0.02
    t = np.linspace(0.0, 1.0, 1001)
    lo, hi = hemisphere_step_zonal(t).min(), min(hemisphere_step_zonal(t).max(), 1.0)
    raw_ratio = raw[outer] / plain[outer]
    assert np.all((raw_ratio > lo - 0.06) & (raw_ratio < hi + 0.06))


def test_bad_parameters() -> None:
    sphere = load_mesh("builtin:sphere:subdivisions=1")
    with pytest.raises(BadInputError, match="order"):
        vertex_visibility_sh(sphere, order=-1)
    with pytest.raises(BadInputError, match="directions"):
        vertex_visibility_sh(sphere, n_dirs=2)
    with pytest.raises(BadInputError, match="columns"):
        visibility_at(np.zeros((2, 24)), np.zeros((2, 3)))
