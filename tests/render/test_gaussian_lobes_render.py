"""Render mode ``gaussian-lobes`` (Green, Kautz & Durand 2007) in the GLSL shader.

References: the numpy path ``GaussianLobeModel.radiance`` evaluated on the CPU reference
renderer's geometry (analytic ray–sphere or Möller–Trumbore ray casting), with and without
the self-shadowing hook of ``analysis.baselines.selfshadow``; and a closed form (constant
environment: every normalized SG convolution is the constant, so B = c Σ_k w_k(θ_v) with
θ_v = angle(N, V) interpolated linearly between the fitted elevations).
"""

from __future__ import annotations

import numpy as np
import OpenEXR
import pytest

from shrmkit.analysis.baselines.gaussian_lobes import (
    GaussianLobeModel,
    GaussianLobes,
    fit_gaussian_lobes,
    sg_mip_stack,
)
from shrmkit.analysis.baselines.selfshadow import hemisphere_step_sh, vertex_visibility_sh, visibility_hook
from shrmkit.brdf_io.envmap import load_env
from shrmkit.brdf_io.latlong import pixel_directions
from shrmkit.brdf_io.specs import load_brdf
from shrmkit.cli.main import main
from shrmkit.render.camera import Camera
from shrmkit.render.cpu_reference import interpolate_vertex_data, mesh_geometry, shade, sphere_geometry
from shrmkit.render.mesh import load_mesh
from shrmkit.render.vtk_renderer import SHRMRenderer

pytestmark = pytest.mark.render


def random_lobes(seed: int = 1, N: int = 7, K: int = 3) -> GaussianLobes:
    """Lobes with offsets of both signs and widths from below σ_0 to several mip levels."""
    rng = np.random.default_rng(seed)
    theta_v = np.linspace(0.0, np.radians(89.0), N)
    mu = rng.uniform(-0.3, 0.5, (N, K))
    sigma = np.sort(rng.uniform(0.03, 0.9, (N, K)), axis=1)
    sigma[0, 0] = 0.01  # narrower than the stack's σ_0: level 0 only
    weight = rng.uniform(0.2, 1.0, (N, K, 3))
    return GaussianLobes(theta_v, mu, sigma, weight, np.zeros(N))


@pytest.fixture(scope="module")
def glr() -> GaussianLobeModel:
    d = pixel_directions(64, 128)
    env = (1.0 + 0.8 * d[..., 2:3]) * np.array([1.0, 0.8, 0.6]) + 3.0 * np.maximum(d[..., 0:1], 0.0) ** 8
    return GaussianLobeModel(random_lobes(), sg_mip_stack(env))


@pytest.fixture(scope="module")
def sphere():
    return load_mesh("builtin:sphere:subdivisions=5")


def rel_rms(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.sqrt(np.mean((a - b) ** 2)) / np.sqrt(np.mean(b**2)))


@pytest.mark.parametrize("projection", ["ortho", "perspective"])
def test_shader_matches_cpu_lobes_on_sphere(offscreen, sphere, glr, projection) -> None:
    """Per pixel, shader = GaussianLobeModel.radiance within 2 % relative RMS (measured ~5e-4)."""
    cam = Camera.looking_at(view=(1.0, 0.4, 0.3), projection=projection)
    with SHRMRenderer(96, 96) as r:
        r.add_object(sphere, glr, mode="gaussian-lobes")
        res = r.render(cam)
    geom = sphere_geometry(cam, 96, 96)
    assert np.sum(geom.hit != (res.alpha > 0.5)) <= 8
    m = geom.hit & (res.alpha > 0.5)
    cpu = shade(geom, glr.radiance)
    assert rel_rms(res.radiance[m], cpu[m]) < 0.02
    # interior pixels (away from the faceted silhouette) agree much more tightly
    inner = m & (np.sum(geom.N * geom.V, -1) > 0.3)
    assert rel_rms(res.radiance[inner], cpu[inner]) < 3e-3
    assert np.all(res.radiance[~(res.alpha > 0.5)] == 0.0)


def test_constant_environment_closed_form(offscreen, sphere) -> None:
    """L ≡ c: B = c Σ_k w_k interpolated in θ_v = angle(N, V) between the fitted elevations."""
    lobes = random_lobes(seed=3)
    c = np.array([0.5, 2.0, 7.0])
    stack = sg_mip_stack(np.broadcast_to(c, (32, 64, 3)).copy())
    cam = Camera.looking_at(view=(0.2, -1.0, 0.5), projection="perspective")
    with SHRMRenderer(64, 64) as r:
        r.add_object(sphere, GaussianLobeModel(lobes, stack), mode="gaussian-lobes")
        res = r.render(cam)
    geom = sphere_geometry(cam, 64, 64)
    m = geom.hit & (res.alpha > 0.5) & (np.sum(geom.N * geom.V, -1) > 0.2)
    tv = np.arccos(np.clip(np.sum(geom.N[m] * geom.V[m], -1), -1.0, 1.0))
    total = lobes.weight.sum(axis=1)  # (N, 3)
    exact = np.stack([np.interp(tv, lobes.theta_v, total[:, ch]) for ch in range(3)], -1) * c
    assert rel_rms(res.radiance[m], exact) < 5e-3


def test_shader_matches_cpu_on_torus_knot(offscreen, glr) -> None:
    """Perspective torus knot (self-occluding, back faces visible): shader vs ray-cast CPU render."""
    knot = load_mesh("builtin:torus-knot:segments=96,sides=8")
    cam = Camera.looking_at(view=(0.3, 1.0, 0.6), projection="perspective")
    with SHRMRenderer(64, 64) as r:
        r.add_object(knot, glr, mode="gaussian-lobes")
        res = r.render(cam)
    geom = mesh_geometry(cam, 64, 64, knot)
    m = geom.hit & (res.alpha > 0.5)
    assert np.sum(geom.hit != (res.alpha > 0.5)) < 0.03 * geom.hit.sum()
    assert rel_rms(res.radiance[m], shade(geom, glr.radiance)[m]) < 0.02


@pytest.fixture(scope="module")
def shadowed_torus():
    """(torus, its per-vertex SH-4 visibility, camera, the ray caster's hits at 48²): the visibility
    (1.2 s CPU) and the brute-force hits (0.8 s) computed once for both tests below, read-only."""
    torus = load_mesh("builtin:torus:segments=40,sides=12")
    coeffs = vertex_visibility_sh(torus, n_dirs=256)
    cam = Camera.looking_at(view=(0.5, -0.3, 1.0), projection="perspective")
    geom = mesh_geometry(cam, 48, 48, torus)
    for value in (coeffs, *vars(geom).values()):
        if isinstance(value, np.ndarray):
            value.setflags(write=False)
    return torus, coeffs, cam, geom


@pytest.mark.parametrize("normalized", [True, False])
def test_self_shadowed_shader_matches_cpu(offscreen, glr, shadowed_torus, normalized) -> None:
    """25 SH-4 visibility coefficients per vertex as vertex attributes: shader = CPU hook path
    (barycentrically interpolated coefficients, each lobe × V(d_k)); shadowing is visible."""
    torus, coeffs, cam, geom = shadowed_torus
    with SHRMRenderer(48, 48) as r:
        r.add_object(torus, glr, mode="gaussian-lobes", visibility_sh=coeffs, normalized_visibility=normalized)
        res = r.render(cam)
    m = geom.hit & (res.alpha > 0.5)
    per_pixel = interpolate_vertex_data(geom, torus, coeffs)
    steps = interpolate_vertex_data(geom, torus, hemisphere_step_sh(torus.normals))
    hook = visibility_hook(per_pixel, geom.N[geom.hit], steps) if normalized else visibility_hook(per_pixel)
    cpu = shade(geom, lambda R, V: glr.radiance(R, V, visibility=hook))
    assert rel_rms(res.radiance[m], cpu[m]) < 0.02
    plain = shade(geom, glr.radiance)
    ratio = cpu.sum(-1) / np.maximum(plain.sum(-1), 1e-300)
    shadowed = m & (ratio < 0.97)  # the pixels where visibility matters: compare them on their own
    assert shadowed.sum() > 0.1 * m.sum()
    assert rel_rms(res.radiance[shadowed], cpu[shadowed]) < 0.01


def test_add_object_checks_representation(offscreen, sphere, glr) -> None:
    with SHRMRenderer(16, 16) as r:
        with pytest.raises(ValueError, match="GaussianLobeModel"):
            r.add_object(sphere, glr, mode="distant")
        with pytest.raises(ValueError, match="visibility_sh"):
            r.add_object(sphere, glr, mode="gaussian-lobes", visibility_sh=np.zeros((3, 25)))


def test_cli_render_gaussian_lobes(offscreen, tmp_path, capsys) -> None:
    """``shrm render --mode gaussian-lobes``: fit time printed; EXR = CPU render of the same fit."""
    png, exr = tmp_path / "g.png", tmp_path / "g.exr"
    rc = main(["render", "builtin:sphere:subdivisions=5", "--env", "builtin:studio", "--brdf", "phong:s=8",
               "--mode", "gaussian-lobes", "--elevations", "4", "--size", "40", "--camera", "ortho",
               "--view", "0,1,0.5", "--fps-frames", "2", "-o", str(png), "--exr", str(exr)])
    assert rc == 0
    out = capsys.readouterr().out
    for word in ("fit:", "SG mip stack:", "first frame:", "frames per second:"):
        assert word in out
    with OpenEXR.File(str(exr), separate_channels=True) as f:
        ch = {k: np.asarray(v.pixels) for k, v in f.channels().items()}
    rad, alpha = np.stack([ch["R"], ch["G"], ch["B"]], -1), ch["A"]
    glr = GaussianLobeModel(fit_gaussian_lobes(load_brdf("phong:s=8"), K=3, n_elevations=4),
                               sg_mip_stack(load_env("builtin:studio")))
    cam = Camera.looking_at(view=(0, 1, 0.5), projection="ortho")
    geom = sphere_geometry(cam, 40, 40)
    inside = geom.hit & (alpha > 0.5) & (np.sum(geom.N * geom.V, -1) > 0.2)
    assert rel_rms(rad[inside], shade(geom, glr.radiance)[inside]) < 5e-3
