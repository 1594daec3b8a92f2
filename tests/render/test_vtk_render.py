"""The GLSL SHRM shader against independent CPU computations.

References: closed forms (B depending only on R, or only on V through the real SH of
analysis.sh), the numpy CPU renderer (analytic ray–sphere / Möller–Trumbore ray casting +
SHRM.radiance), and the brute-force angular-domain integral analysis.reference (RH02 eq. 2;
RH02 = Ramamoorthi & Hanrahan 2002, doi:10.1145/566654.566611).
"""

from __future__ import annotations

import numpy as np
import OpenEXR
import pytest

import shrmkit
from shrmkit.analysis.reference import reference_radiance
from shrmkit.analysis.sh import real_sph_harm
from shrmkit.analysis.shrm import SHRM
from shrmkit.analysis.tolerance import DEFAULT_EPS
from shrmkit.brdf_io.envmap import load_env
from shrmkit.brdf_io.latlong import bilinear_lookup, pixel_directions
from shrmkit.brdf_io.specs import load_brdf
from shrmkit.render.camera import Camera
from shrmkit.render.cpu_reference import mesh_geometry, shade, sphere_geometry
from shrmkit.render.mesh import load_mesh
from shrmkit.render.output import write_exr
from shrmkit.render.vtk_renderer import SHRMRenderer

pytestmark = pytest.mark.render

Y00 = 1.0 / np.sqrt(4.0 * np.pi)


@pytest.fixture(scope="module")
def sphere():
    return load_mesh("builtin:sphere:subdivisions=5")


def shrm_of_R(func, P: int = 1, H: int = 32, W: int = 64) -> SHRM:
    """An SHRM whose radiance is func(R) for every V: only the p = 0 maps are non-zero."""
    c = np.zeros(((P + 1) ** 2, H, W, 3), np.float32)
    c[0] = func(pixel_directions(H, W)) / Y00
    return SHRM(F=H - 1, P=P, coeffs=c)


def interior(geom, result, max_deg: float = 80.0) -> np.ndarray:
    cos_v = np.sum(geom.N * geom.V, axis=-1)
    return geom.hit & (result.alpha > 0.5) & (cos_v >= np.cos(np.deg2rad(max_deg)))


def test_float_readback_matches_closed_form_in_R(offscreen, sphere) -> None:
    """B(R) = (1 + R_x, 1e-3 (1 + R_y), 300 (1 + R_z)): values far outside [0, 1] and below
    8-bit resolution come back in float; ortho silhouette equals the analytic disc."""
    scale = np.array([1.0, 1e-3, 300.0])
    shrm = shrm_of_R(lambda d: (1.0 + d) * scale, H=64, W=128)
    cam = Camera.looking_at(view=(1.0, 0.4, 0.3), projection="ortho")
    with SHRMRenderer(64, 64) as r:
        r.add_object(sphere, shrm, mode="distant")
        res = r.render(cam)
    geom = sphere_geometry(cam, 64, 64)
    assert np.sum(geom.hit != (res.alpha > 0.5)) <= 4  # pixel centres on the polygon edge
    m = interior(geom, res)
    exact = (1.0 + geom.R[m]) * scale
    rel = np.abs(res.radiance[m] - exact) / scale
    assert rel.max() < 0.02
    # against the same SHRM looked up on the CPU: only mesh faceting differs
    cpu = shade(geom, shrm.radiance)[m]
    rms = np.sqrt(np.mean(((res.radiance[m] - cpu) / scale) ** 2))
    assert rms < 2e-3
    assert np.all(res.radiance[~(res.alpha > 0.5)] == 0.0)


def test_perpixel_sh_basis_matches_analysis_sh(offscreen, sphere) -> None:
    """Coefficients constant in R: B(V) = Σ c_k Y^r_k(V) per pixel under perspective, with the
    GLSL real SH checked against analysis.sh.real_sph_harm for P = 4 (25 functions)."""
    rng = np.random.default_rng(7)
    P = 4
    coef = rng.normal(size=((P + 1) ** 2, 3))
    c = np.broadcast_to(coef[:, None, None, :], ((P + 1) ** 2, 8, 16, 3)).astype(np.float32)
    shrm = SHRM(F=4, P=P, coeffs=np.ascontiguousarray(c))
    cam = Camera.looking_at(view=(0.3, -0.5, 0.8), up=(0, 0, 1), projection="perspective", distance=1.6)
    with SHRMRenderer(64, 48) as r:
        r.add_object(sphere, shrm, mode="perpixel")
        res = r.render(cam)
    geom = sphere_geometry(cam, 64, 48)
    m = geom.hit & (res.alpha > 0.5)
    # V depends on the rasterized point; on the polygon it differs from the sphere by ≲ 1e-4
    want = real_sph_harm(P, geom.V[m]) @ coef.astype(np.float32)
    # the SHRM modes clamp the radiance at 0 (render.shader): these random coefficients go negative
    assert (want > 0.1).mean() > 0.2 and (want < -0.1).mean() > 0.2
    np.testing.assert_allclose(res.radiance[m], np.maximum(want, 0.0), atol=2e-3 * np.abs(want).max())


def _random_smooth_shrm(P: int, H: int = 32, W: int = 64, seed: int = 0) -> SHRM:
    """A smooth random SHRM: low-order real SH in R for every coefficient map."""
    rng = np.random.default_rng(seed)
    basis = real_sph_harm(3, pixel_directions(H, W))  # (H, W, 16)
    mix = rng.normal(size=((P + 1) ** 2, 16, 3))
    c = np.einsum("hwk,nkc->nhwc", basis, mix).astype(np.float32)
    c[0] += 3.0  # keep radiance away from zero so relative errors mean something
    return SHRM(F=3, P=P, coeffs=c)


def test_distant_and_perpixel_modes_against_cpu(offscreen, sphere) -> None:
    """perpixel = Σ B̃_pq(R) Y_pq(V_pixel) (RH02 eq. 8); distant = Σ B̃_pq(R) Y_pq(Ṽ) with Ṽ the
    direction from the object centre to the eye (RH02 eq. 12), both under perspective."""
    shrm = _random_smooth_shrm(P=2)
    cam = Camera.looking_at(view=(-0.4, 1.0, 0.2), projection="perspective", distance=2.5)
    geom = sphere_geometry(cam, 64, 64)
    v_tilde = cam.eye / np.linalg.norm(cam.eye)
    # distant is the one map Σ B̃_pq Y_pq(Ṽ) of the frame (clamped at 0, as the renderer's) looked up by R
    view_map = shrm.view_map(v_tilde).astype(np.float64)
    for mode, radiance in [
        ("perpixel", shrm.radiance),
        ("distant", lambda R, V: bilinear_lookup(view_map, R)),
    ]:
        with SHRMRenderer(64, 64) as r:
            r.add_object(sphere, shrm, mode=mode)
            res = r.render(cam)
        m = interior(geom, res)
        ref = shade(geom, radiance)[m]
        rel = np.sqrt(np.mean((res.radiance[m] - ref) ** 2)) / np.sqrt(np.mean(ref**2))
        assert rel < 5e-3, mode
    # the two modes really differ under this close perspective camera
    per = shade(geom, shrm.radiance)[m]
    dist = shade(geom, lambda R, V: shrm.radiance(R, np.broadcast_to(v_tilde, R.shape)))[m]
    assert np.sqrt(np.mean((per - dist) ** 2)) / np.sqrt(np.mean(per**2)) > 0.02


def test_mesh_against_ray_cast_reference(offscreen) -> None:
    """A coarse torus knot (interpolated normals) against brute-force Möller–Trumbore casting."""
    mesh = load_mesh("builtin:torus-knot:segments=96,sides=8")
    shrm = _random_smooth_shrm(P=1, seed=3)
    cam = Camera.looking_at(view=(0.2, 0.3, 1.0), projection="perspective")
    with SHRMRenderer(48, 48) as r:
        r.add_object(mesh, shrm, mode="perpixel")
        res = r.render(cam)
    geom = mesh_geometry(cam, 48, 48, mesh)
    cover = res.alpha > 0.5
    assert np.sum(geom.hit != cover) <= 0.02 * geom.hit.sum()
    m = geom.hit & cover
    ref = shade(geom, shrm.radiance)[m]
    err = np.sqrt(np.sum((res.radiance[m] - ref) ** 2, axis=-1)) / np.linalg.norm(ref, axis=-1)
    # a few pixels may see a different (occluding) surface at depth edges
    assert np.mean(err < 1e-3) > 0.97


def test_several_objects_with_their_own_shrm(offscreen) -> None:
    """Two spheres at x = ∓0.5 with constant radiance 1 and 2; seen from −y, left is 1, right 2."""
    small = load_mesh("builtin:sphere:subdivisions=3")
    with SHRMRenderer(64, 32) as r:
        r.add_object(small.transformed(scale=0.45, translate=(-0.5, 0, 0)), shrm_of_R(lambda d: 1.0 + 0 * d))
        r.add_object(small.transformed(scale=0.45, translate=(0.5, 0, 0)), shrm_of_R(lambda d: 2.0 + 0 * d),
                     mode="perpixel")
        cam = Camera.looking_at(view=(0, -1, 0), projection="ortho", radius=0.5)
        res = r.render(cam)
    np.testing.assert_allclose(res.radiance[16, 16], 1.0, rtol=1e-6)
    np.testing.assert_allclose(res.radiance[16, 48], 2.0, rtol=1e-6)
    assert res.alpha[16, 32] == 0.0


@pytest.fixture(scope="module")
def prefiltered():
    env = load_env("builtin:studio", height=64)
    brdf = load_brdf("microfacet:sigma=0.2")
    eps = DEFAULT_EPS
    return env, brdf, eps, shrmkit.prefilter(env, brdf, eps=eps)


@pytest.mark.parametrize(("mode", "projection"), [("distant", "ortho"), ("perpixel", "perspective")])
def test_accuracy_against_angular_reference(offscreen, sphere, prefiltered, tmp_path, mode, projection) -> None:
    """Acceptance: relative RMS between the rendered EXR and the angular-domain reference
    (interior pixels, θ_v ≤ 80°) ≤ 2·sqrt(ε) + 2%. 300 random interior pixels are integrated."""
    env, brdf, eps, shrm = prefiltered
    cam = Camera.looking_at(view=(1.0, 0.5, 0.4), projection=projection)
    with SHRMRenderer(64, 64) as r:
        r.add_object(sphere, shrm, mode=mode)
        res = r.render(cam)
    path = tmp_path / "frame.exr"
    write_exr(path, res.radiance, res.alpha)
    with OpenEXR.File(str(path), separate_channels=True) as f:
        ch = {k: np.asarray(v.pixels) for k, v in f.channels().items()}
    exr = np.stack([ch["R"], ch["G"], ch["B"]], axis=-1)
    geom = sphere_geometry(cam, 64, 64)
    idx = np.flatnonzero(interior(geom, res).ravel())
    idx = np.random.default_rng(0).choice(idx, 300, replace=False)
    ref = reference_radiance(env, brdf, geom.R.reshape(-1, 3)[idx], geom.V.reshape(-1, 3)[idx])
    got = exr.reshape(-1, 3)[idx]
    rel = np.sqrt(np.mean((got - ref) ** 2)) / np.sqrt(np.mean(ref**2))
    assert rel <= 2.0 * np.sqrt(eps) + 0.02
    assert rel < 0.1  # measured ≈ 0.05 with this environment and BRDF


@pytest.mark.parametrize(("spot", "view", "bright_half"), [("x", (0, -1, 0), "right"), ("z", (1, 0, 0), "top")])
def test_spot_lights_the_matching_side(offscreen, sphere, spot, view, bright_half) -> None:
    """builtin:spot at +x seen from −y lights the right half (image right = +x); a spot at +z
    seen from +x lights the top half."""
    env = load_env(f"builtin:spot,dir={spot}", height=32)
    shrm = shrmkit.prefilter(env, "microfacet:sigma=0.3", eps=0.05)
    cam = Camera.looking_at(view=view, projection="ortho")
    with SHRMRenderer(32, 32) as r:
        r.add_object(sphere, shrm)
        lum = r.render(cam).radiance.sum(-1)
    if bright_half == "right":
        a, b = lum[:, 16:].sum(), lum[:, :16].sum()
    else:
        a, b = lum[:16].sum(), lum[16:].sum()
    assert a > 5.0 * b
