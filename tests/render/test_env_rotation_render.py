"""The environment rotated at view time in every render mode's GLSL, the background and render_scene.

References: the same mode rendered from an SHRM prefiltered anew from the rotated map (a closed-form
map evaluated at the rotated directions, no resampling); the numpy CPU renderer
(``cpu_reference.shade(env_rotation=)``: each model's own B at Qᵀ R, Qᵀ V); an exact column roll of
the lat-long map (``EnvironmentMap.rotated_z`` by whole columns) for the background.
"""

from __future__ import annotations

import numpy as np
import pytest

from shrmkit.analysis.baselines.gaussian_lobes import GaussianLobeModel, fit_gaussian_lobes, sg_mip_stack
from shrmkit.analysis.baselines.rsibr import rsibr_from_shrm
from shrmkit.analysis.baselines.selfshadow import hemisphere_step_sh, vertex_visibility_sh, visibility_hook
from shrmkit.analysis.shrm import prefilter
from shrmkit.brdf_io.env_rotation import env_rotation_matrix, to_map_frame
from shrmkit.brdf_io.envmap import EnvironmentMap
from shrmkit.brdf_io.errors import BadInputError
from shrmkit.brdf_io.latlong import bilinear_lookup, pixel_directions
from shrmkit.brdf_io.specs import load_brdf
from shrmkit.render.api import render_scene
from shrmkit.render.camera import Camera
from shrmkit.render.cpu_reference import interpolate_vertex_data, mesh_geometry, shade, sphere_geometry
from shrmkit.render.mesh import load_mesh
from shrmkit.render.modes import RenderOptions
from shrmkit.render.output import environment_background
from shrmkit.render.pipeline import light_turntable_rotations
from shrmkit.render.vtk_renderer import SHRMRenderer

pytestmark = pytest.mark.render

SIZE = 48
Q = env_rotation_matrix(70.0, 25.0, -40.0)
CAM = Camera.looking_at(view=(1.0, 0.4, 0.3), projection="ortho")
MU = np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8])
MU2 = np.array([-0.7, 0.2, -0.1]) / np.linalg.norm([-0.7, 0.2, -0.1])


def blob_radiance(d: np.ndarray, rotation: np.ndarray) -> np.ndarray:
    """A smooth closed-form map rotated by Q exactly: L(Qᵀ ω), at directions d (..., 3)."""
    a, b = rotation @ MU, rotation @ MU2
    return (0.2 + 5.0 * np.exp(8.0 * (d @ a - 1.0))[..., None] * [1.0, 0.8, 0.6]
            + 2.0 * np.exp(20.0 * (d @ b - 1.0))[..., None] * [0.3, 0.5, 1.0])


def blobs(rotation: np.ndarray, height: int = 64) -> EnvironmentMap:
    return EnvironmentMap(blob_radiance(pixel_directions(height, 2 * height), rotation).astype(np.float32),
                          name="blobs")


@pytest.fixture(scope="module")
def sphere():
    return load_mesh("builtin:sphere:subdivisions=5")


@pytest.fixture(scope="module")
def pair():
    """(SHRM of the map, SHRM prefiltered anew from the map rotated by Q), same orders."""
    brdf = load_brdf("microfacet:sigma=0.3")
    # 128-row maps: at 64 rows the lat-long sampling of the lighting (which turns with the map) is
    # 9e-4 of the difference, at 128 rows 3e-4
    base = prefilter(blobs(np.eye(3), 128), brdf, lights="none", F=20, P=3, size=128)
    fresh = prefilter(blobs(Q, 128), brdf, lights="none", F=20, P=3, size=128)
    return base, fresh


def rel_rms(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.sqrt(np.mean((a - b) ** 2)) / np.sqrt(np.mean(b**2)))


@pytest.mark.parametrize("mode", ["perpixel", "distant"])
def test_rotated_render_equals_render_of_fresh_prefilter(offscreen, sphere, pair, mode) -> None:
    """Both SHRM modes: the render with env_rotation Q = the render of the rotated map prefiltered anew
    (≤ 1e-3 relative RMS, same geometry; measured 3e-4 in both modes), and = the CPU
    reference of the same rotation (≤ 5e-3: mesh faceting, as the unrotated tests)."""
    base, fresh = pair
    with SHRMRenderer(SIZE, SIZE) as r:
        r.add_object(sphere, base, mode=mode)
        turned = r.render(CAM, env_rotation=Q)
        plain = r.render(CAM)
    with SHRMRenderer(SIZE, SIZE) as r:
        r.add_object(sphere, fresh, mode=mode)
        anew = r.render(CAM)
    m = (turned.alpha > 0.5) & (anew.alpha > 0.5)
    assert rel_rms(turned.radiance[m], anew.radiance[m]) <= 1e-3
    assert rel_rms(plain.radiance[m], anew.radiance[m]) > 0.05  # the rotation matters
    geom = sphere_geometry(CAM, SIZE, SIZE)
    inside = m & geom.hit & (np.sum(geom.N * geom.V, -1) > 0.2)
    if mode == "perpixel":
        cpu = shade(geom, base.radiance, env_rotation=Q)
    else:  # one map per frame, for the view Qᵀ Ṽ, looked up at Qᵀ R
        view_map = base.view_map(CAM.view_direction(np.zeros(3)), env_rotation=Q).astype(np.float64)
        cpu = shade(geom, lambda R, V: bilinear_lookup(view_map, R), env_rotation=Q)
    assert rel_rms(turned.radiance[inside], cpu[inside]) < 5e-3


def test_deferred_equals_forward_under_rotation(offscreen, sphere, pair) -> None:
    """The deferred screen pass turns the R it reads back and its V as the forward prelude does."""
    base, _ = pair
    images = []
    for deferred in (False, True):
        with SHRMRenderer(SIZE, SIZE, deferred=deferred) as r:
            r.add_object(sphere, base, mode="perpixel")
            assert r.deferred == deferred
            images.append(r.render(Camera.looking_at(view=(-0.3, 1.0, 0.2)), env_rotation=Q))
    peak = float(images[0].radiance.max())
    assert np.mean(np.abs(images[0].radiance - images[1].radiance) <= 2e-5 * peak) > 0.995


def test_lights_and_rsibr_turn_with_the_map(offscreen, sphere) -> None:
    """Explicit lights (per pixel, perpixel and distant) and the twelve RSIBR maps, rotated: each mode
    against its own numpy model on the CPU at the same rotation."""
    d = pixel_directions(32, 64)
    sky = 0.3 + 0.2 * d[..., 2:3] * np.ones(3)
    sky[6, 10] = (400.0, 300.0, 200.0)  # one sun pixel: an explicit light
    shrm = prefilter(EnvironmentMap(sky.astype(np.float32), name="sun"), "microfacet:sigma=0.15", lights="auto")
    assert shrm.has_lights
    geom = sphere_geometry(CAM, SIZE, SIZE)
    inside = geom.hit & (np.sum(geom.N * geom.V, -1) > 0.2)
    for mode in ("perpixel", "distant"):
        with SHRMRenderer(SIZE, SIZE) as r:
            r.add_object(sphere, shrm, mode=mode)
            res = r.render(CAM, env_rotation=Q)
        m = inside & (res.alpha > 0.5)
        if mode == "perpixel":
            cpu = shade(geom, shrm.radiance, env_rotation=Q)
        else:
            view_map = shrm.view_map(CAM.view_direction(np.zeros(3)), env_rotation=Q).astype(np.float64)
            cpu = shade(geom, lambda R, V, m_=view_map: bilinear_lookup(m_, R) + shrm.light_radiance(R, V),
                        env_rotation=Q)
        assert rel_rms(res.radiance[m], cpu[m]) < 5e-3, mode
    maps = rsibr_from_shrm(shrm)
    with SHRMRenderer(SIZE, SIZE) as r:
        r.add_object(sphere, maps, mode="rsibr")
        res = r.render(CAM, env_rotation=Q)
    m = inside & (res.alpha > 0.5)
    assert rel_rms(res.radiance[m], shade(geom, maps.radiance, env_rotation=Q)[m]) < 0.02  # as test_rsibr_render


def test_gaussian_lobes_rotated_with_and_without_self_shadowing(offscreen) -> None:
    """Green et al.'s lobes read in the map's frame; the self-shadowing visibility is the mesh's, at
    the world direction Q d: against GaussianLobeModel.radiance at Qᵀ R, Qᵀ V with the visibility hook
    fed Q d (as test_gaussian_lobes_render without rotation)."""
    glr = GaussianLobeModel(fit_gaussian_lobes(load_brdf("phong:s=8"), K=2, n_elevations=4),
                            sg_mip_stack(blobs(np.eye(3), height=32).radiance))
    torus = load_mesh("builtin:torus:segments=40,sides=12")
    coeffs = vertex_visibility_sh(torus, n_dirs=256)
    cam = Camera.looking_at(view=(0.5, -0.3, 1.0), projection="perspective")
    with SHRMRenderer(SIZE, SIZE) as r:
        r.add_object(torus, glr, mode="gaussian-lobes")
        plain = r.render(cam, env_rotation=Q)
    with SHRMRenderer(SIZE, SIZE) as r:
        r.add_object(torus, glr, mode="gaussian-lobes", visibility_sh=coeffs)
        shadowed = r.render(cam, env_rotation=Q)
    geom = mesh_geometry(cam, SIZE, SIZE, torus)
    m = geom.hit & (plain.alpha > 0.5)
    assert rel_rms(plain.radiance[m], shade(geom, glr.radiance, env_rotation=Q)[m]) < 0.02
    per_pixel = interpolate_vertex_data(geom, torus, coeffs)
    steps = interpolate_vertex_data(geom, torus, hemisphere_step_sh(torus.normals))
    hook = visibility_hook(per_pixel, geom.N[geom.hit], steps)

    def world_hook(dirs: np.ndarray, rows: np.ndarray) -> np.ndarray:
        return hook(dirs @ Q.T, rows)  # map frame -> world: Q d

    cpu = shade(geom, lambda R, V: glr.radiance(R, V, visibility=world_hook), env_rotation=Q)
    assert rel_rms(shadowed.radiance[m], cpu[m]) < 0.02


def test_background_turns_with_the_map() -> None:
    """The environment behind the object: a roll by whole columns is exact; any rotation matches the
    closed-form rotated map seen along the rays (bilinear lookup error only)."""
    env = blobs(np.eye(3))
    cam = Camera.looking_at(view=(0.3, 1.0, 0.4), projection="perspective")
    rolled = env.rotated_z(np.radians(45.0))  # 16 of 128 columns
    np.testing.assert_allclose(environment_background(env.radiance, cam, 40, 40, env_rotation=env_rotation_matrix(45)),
                               environment_background(rolled.radiance, cam, 40, 40), rtol=1e-5, atol=1e-6)
    _, rays = cam.rays(40, 40)
    exact = blob_radiance(rays, Q)
    got = environment_background(env.radiance, cam, 40, 40, env_rotation=Q)
    assert rel_rms(got, exact) < 5e-3
    assert rel_rms(environment_background(env.radiance, cam, 40, 40), exact) > 0.05


def test_render_scene_light_turntable_and_refusals(offscreen) -> None:
    """RenderOptions(env_rotation=) through render_scene: a lighting turntable is N frames from one
    camera and one build, frame k = frame 0 rendered with R_z(360°k/N); a wrong count is refused."""
    cam = Camera.looking_at(view=(1.0, 0.2, 0.3))
    rotations = light_turntable_rotations(3)
    np.testing.assert_allclose(rotations[1], env_rotation_matrix(120.0), atol=1e-15)
    result = render_scene("builtin:sphere:subdivisions=3", "builtin:studio,height=16", "phong:s=8", mode="perpixel",
                          camera=[cam] * 3, size=32, fps_frames=0, options=RenderOptions(env_rotation=rotations))
    assert len(result.frames) == 3 and len(result.timings.frame_seconds) == 3
    assert result.timings.later_frame_s > 0
    single = render_scene("builtin:sphere:subdivisions=3", "builtin:studio,height=16", "phong:s=8", mode="perpixel",
                          camera=cam, size=32, fps_frames=0, options=RenderOptions(env_rotation=(120.0, 0.0)))
    np.testing.assert_allclose(result.frames[1].linear, single.frames[0].linear, rtol=1e-5, atol=1e-6)
    assert np.abs(result.frames[0].linear - result.frames[1].linear).max() > 0.01
    with pytest.raises(BadInputError, match="3 rotations for 2 camera"):
        render_scene("builtin:sphere:subdivisions=3", "builtin:studio,height=16", "phong:s=8", camera=[cam] * 2,
                     size=32, fps_frames=0, options=RenderOptions(env_rotation=rotations))
    with pytest.raises(BadInputError, match="not a rotation"):
        RenderOptions(env_rotation=-np.eye(3))
    assert RenderOptions(env_rotation=(0.0, 0.0)) == RenderOptions(env_rotation=np.eye(3))
    assert to_map_frame(np.array([1.0, 0.0, 0.0]), None)[0] == 1.0
