"""The lights beside the SHRM (DESIGN §5a) in the VTK shaders, against the CPU reference.

Every SHRM render mode adds Σ_k ρ̂(ω_k; V, N) E_k, N = normalize(R + V), per pixel with the
BRDF's own GLSL (``render.brdf_glsl``, ``render/webgl/brdf_*.glsl``). References: the numpy ray
caster ``render.cpu_reference`` (Möller–Trumbore with the mesh's interpolated normals, so both
see the same R and V) shading :meth:`SHRM.radiance`, whose lights are
``analysis.lights.light_radiance`` — ``brdf.rho_hat`` of the models in ``brdf_io.models`` (an
independent float64 implementation) and ``brdf.eval`` of measured tables. Scenes: an environment
that is black apart from a few pixels (``lights="auto"`` takes them all out: the SHRM part is 0,
the image is the lights alone), for each model, seen from a generic view and with grazing views at
the silhouette; and the sky (SHRM part + sun) in every SHRM mode. RH02 = Ramamoorthi & Hanrahan
2002, doi:10.1145/566654.566611.
"""

from __future__ import annotations

import numpy as np
import pytest

import shrmkit
from shrmkit.analysis.shrm import SHRM
from shrmkit.brdf_io.errors import BadInputError
from shrmkit.brdf_io.latlong import bilinear_lookup
from shrmkit.brdf_io.specs import load_brdf
from shrmkit.brdf_io.table import TableBRDF, tabulate_table
from shrmkit.render.api import render_scene
from shrmkit.render.brdf_glsl import BRDF_GLSL, TABLE_SHADER, brdf_shader_for, light_shading, table_light_radiance
from shrmkit.render.camera import Camera
from shrmkit.render.cpu_reference import mesh_geometry, shade
from shrmkit.render.mesh import load_mesh, make_mesh
from shrmkit.render.modes import RenderOptions
from shrmkit.render.shader import distant_shading, perpixel_shading
from shrmkit.render.vtk_renderer import SHRMRenderer

pytestmark = pytest.mark.render

SIZE = 48
#: (spec, model class name): every model of the BRDF shader table, sharp lobes and RGB parameters
MODELS = [
    "phong:s=40,ks=1/0.8/0.6",
    "phong:s=3000",
    "microfacet:sigma=0.15,ks=1/0.5/0.25",
    "lambert:albedo=0.5/0.6/0.7",
    "lafortune:kd=0.1/0.2/0.3,cxy=-1,cz=1,n=20/30/40,ks=1,cxy2=-0.5,cz2=0.8,n2=5,ks2=0.3/0.2/0.1",
    "cook-torrance:kd=0.1,ks=1,alpha=0.2,f0=0.04/0.5/0.9,dist=beckmann",
    "cook-torrance:kd=0.05,ks=1,alpha=0.08,f0=0.9/0.6/0.3,dist=ggx",
]



@pytest.fixture(scope="module")
def sphere():
    return load_mesh("builtin:sphere:subdivisions=3")


#: the view of test_shrm_part_plus_lights_in_every_mode
SKY_CAMERA = Camera.looking_at(view=(0.8, -0.3, 0.6))


@pytest.fixture(scope="module")
def sphere_geometry(sphere):
    """``sphere_geometry(k)``: the ray caster's hits on the sphere at SIZE² for CAMERAS[k] (k = 0, 1)
    or SKY_CAMERA (k = "sky"), cast once per module (the brute-force Möller–Trumbore reference is
    ~0.4 s CPU a frame; the model tests ask for the same two frames seven times) and read-only."""
    cast: dict = {}

    def get(k):
        if k not in cast:
            geom = mesh_geometry(SKY_CAMERA if k == "sky" else CAMERAS[k], SIZE, SIZE, sphere)
            for value in vars(geom).values():
                if isinstance(value, np.ndarray):
                    value.setflags(write=False)
            cast[k] = geom
        return cast[k]

    return get


def compare(image, alpha, reference, hit, cos_v, max_view_deg: float = 89.0) -> tuple[float, float, float]:
    """(relative RMS, largest error over the peak, share of pixels within 1e-3 of the peak) on the
    pixels both cover with θ_v ≤ max_view_deg."""
    m = hit & (alpha > 0.5) & (cos_v >= np.cos(np.radians(max_view_deg)))
    diff = image[m] - reference[m]
    peak = float(np.abs(reference[m]).max())
    rel = float(np.sqrt(np.mean(diff**2)) / np.sqrt(np.mean(reference[m] ** 2)))
    per_pixel = np.abs(diff).max(axis=-1) / peak
    return rel, float(per_pixel.max()), float(np.mean(per_pixel <= 1e-3))


CAMERAS = [Camera.looking_at(view=(1.0, 0.3, 0.4)), Camera.looking_at(view=(-0.2, 1.0, -0.3), projection="ortho")]


@pytest.mark.parametrize("spec", MODELS)
def test_each_model_glsl_against_its_numpy_model(offscreen, sphere, sphere_geometry, lights_only, n_dots,
                                                 spec) -> None:
    """A sphere lit only by the lights, for each model of the table: the GLSL ρ̂ against the model's
    own ρ̂ (``light_radiance``) per pixel, perspective and ortho, grazing views (θ_v to 89°, where
    the lights at the horizon graze the surface) included; perpixel and distant (the lights do not
    go through its map) drawn forward and deferred equal."""
    brdf = load_brdf(spec)
    assert brdf_shader_for(brdf) is BRDF_GLSL[type(brdf)]
    shrm = lights_only(brdf)
    assert len(shrm.lights) == n_dots
    frames = {}
    for mode, deferred in (("perpixel", False), ("perpixel", True), ("distant", False), ("distant", True)):
        with SHRMRenderer(SIZE, SIZE, deferred=deferred) as r:
            r.add_object(sphere, shrm, mode=mode)
            assert r.deferred == deferred  # distant with lights has a deferred pass too
            frames[mode, deferred] = [r.render(cam) for cam in CAMERAS]
    for c in range(len(CAMERAS)):
        geom = sphere_geometry(c)
        ref = shade(geom, shrm.radiance)
        cos_v = np.sum(geom.N * geom.V, axis=-1)
        assert ref.max() > 0.0
        images = {key: value[c] for key, value in frames.items()}
        for res in images.values():
            rel, worst, share = compare(res.radiance, res.alpha, ref, geom.hit, cos_v)
            # measured ≤ 6e-4 relative RMS, silhouette pixels (a different interpolated normal) included
            assert rel < 5e-3 and share > 0.97, (spec, rel, worst, share)
        for mode in ("perpixel", "distant"):
            same = np.abs(images[mode, True].radiance - images[mode, False].radiance) <= 2e-5 * ref.max()
            assert np.mean(same) > 0.995  # V from the quad's point: a few silhouette pixels differ by rounding


def test_sharp_lobes_keep_float32_accuracy_near_the_peak(offscreen, lights_only) -> None:
    """Phong s = 3·10⁵ and GGX α = 0.01: a patch of a finely tessellated sphere about the highlight
    of one light, seen close up (ortho, a few hundredths of a radian across), so that the lobe spans
    many pixels; the GLSL (a series for log(1 − u), |N × H| for sin θ_h) matches the float64 model
    on the highlight."""
    fine = load_mesh("builtin:sphere:subdivisions=6")
    view = np.array([1.0, 0.3, 0.4]) / np.linalg.norm([1.0, 0.3, 0.4])
    for spec, half_width in (("phong:s=300000", 0.004), ("cook-torrance:kd=0,alpha=0.01,f0=1,dist=ggx", 0.03)):
        shrm = lights_only(load_brdf(spec))
        normal = shrm.lights.directions[0] + view
        normal /= np.linalg.norm(normal)
        near = np.linalg.norm(fine.vertices[fine.faces].mean(axis=1) - normal, axis=1) < 4 * half_width
        patch = make_mesh(fine.vertices, fine.faces[near], fine.normals, normalize=False)
        cam = Camera.looking_at(center=normal, view=view, radius=half_width, projection="ortho", distance=0.5)
        geom = mesh_geometry(cam, 64, 64, patch)
        ref = shade(geom, shrm.radiance)
        with SHRMRenderer(64, 64) as r:
            r.add_object(patch, shrm, mode="perpixel")
            res = r.render(cam)
        lit = geom.hit & (res.alpha > 0.5) & (ref.max(axis=-1) > 1e-2 * ref.max())
        assert lit.sum() >= 50, (spec, lit.sum())
        np.testing.assert_allclose(res.radiance[lit], ref[lit], rtol=3e-3, atol=1e-4 * ref.max(), err_msg=spec)


@pytest.fixture(scope="module")
def sky_shrm():
    """builtin:sky at 32 rows: its sun (4 pixels) is taken out as a light beside the SHRM of the sky."""
    env = shrmkit.load_env("builtin:sky", height=32)
    shrm = shrmkit.prefilter(env, "microfacet:sigma=0.25", eps=0.05, lights="auto")
    assert shrm.has_lights and np.any(shrm.coeffs)
    return shrm


@pytest.mark.parametrize("mode", ["distant", "perpixel", "kautz-mccool"])
def test_shrm_part_plus_lights_in_every_mode(offscreen, sphere, sphere_geometry, sky_shrm, mode) -> None:
    """The sky's SHRM plus its sun: perpixel = SHRM.radiance (RH02 eq. 8 + lights); distant = the
    frame's map looked up by R (RH02 eq. 12) + the lights at the pixel's own V; kautz-mccool = the
    perpixel sum of the same SHRM's maps + lights. Without the lights the image is far off."""
    shrm = sky_shrm
    cam = SKY_CAMERA
    geom = sphere_geometry("sky")
    cos_v = np.sum(geom.N * geom.V, axis=-1)
    if mode == "distant":
        view_map = shrm.view_map(cam.view_direction(np.zeros(3)))

        def radiance(R, V):
            return bilinear_lookup(view_map, R) + shrm.light_radiance(R, V)
    else:
        radiance = shrm.radiance
    ref = shade(geom, radiance)
    with SHRMRenderer(SIZE, SIZE) as r:
        r.add_object(sphere, shrm, mode=mode)
        res = r.render(cam)
    rel, _, share = compare(res.radiance, res.alpha, ref, geom.hit, cos_v)
    assert rel < 5e-3 and share > 0.95, (rel, share)
    no_lights = shade(geom, lambda R, V: radiance(R, V) - shrm.light_radiance(R, V))
    assert compare(no_lights, res.alpha, ref, geom.hit, cos_v)[0] > 10 * rel + 0.02


def test_measured_table_against_the_brdf_eval(offscreen, sphere, sphere_geometry, lights_only) -> None:
    """A tabulated BRDF (our table format, kind "tabulated": a Cook–Torrance sampled on a
    (θ_i, θ_o, φ_d) grid and interpolated by its reader) goes to the GPU as a half/difference table
    texture; the GLSL equals the numpy lookup of that table, and both the BRDF's own eval within
    the table error that is measured and reported (on the lights' reflection, θ_v ≤ 80°)."""
    source = load_brdf("cook-torrance:kd=0.2,alpha=0.3,f0=0.5/0.4/0.3,dist=ggx")
    axes = (np.linspace(0.0, np.pi / 2, 24), np.linspace(0.0, np.pi / 2, 24), np.linspace(0.0, np.pi, 24))
    ti, to, pd = axes
    brdf = TableBRDF(ti, to, pd, tabulate_table(source, theta_i=ti, theta_o=to, phi_d=pd), name="ct-table")
    assert brdf.kind != "analytic" and brdf_shader_for(brdf) is TABLE_SHADER
    shrm = lights_only(brdf)
    lights = light_shading(shrm)
    error = lights.table_error
    assert error is not None and error["rel_rms"] <= error["worst_band_rel_rms"] <= error["target"]
    cam = CAMERAS[0]
    geom = sphere_geometry(0)
    cos_v = np.sum(geom.N * geom.V, axis=-1)
    ref = shade(geom, shrm.radiance)

    tab = shade(geom, lambda R, V: table_light_radiance(lights.table, shrm.lights, R, V))
    with SHRMRenderer(SIZE, SIZE) as r:
        r.add_object(sphere, shrm, mode="perpixel")
        res = r.render(cam)
    assert compare(res.radiance, res.alpha, tab, geom.hit, cos_v)[0] < 1e-4  # the GLSL is the table's lookup
    rel = compare(res.radiance, res.alpha, ref, geom.hit, cos_v, max_view_deg=80.0)[0]
    assert 0.0 < rel < 3.0 * error["worst_band_rel_rms"] + 1e-3, (rel, error)


def test_render_scene_options_and_description(offscreen) -> None:
    """RenderOptions.lights goes to prefilter: "auto" lists the sun (count, samples, how it is
    shaded) in the description and info, "none" none; bad values are refused by check_lights."""
    env = shrmkit.load_env("builtin:sun", height=16)
    cam = Camera.looking_at(view=(1.0, 0.2, 0.5), projection="ortho")
    runs = {}
    for lights in ("auto", "none"):
        runs[lights] = render_scene("builtin:sphere:subdivisions=2", env, "phong:s=20", mode="perpixel", camera=cam,
                                    size=24, background="black", fps_frames=0, options=RenderOptions(lights=lights))
    auto, none = runs["auto"].built, runs["none"].built
    assert auto.info["lights"]["count"] == 1 and auto.info["lights"]["samples"] == 1
    assert auto.info["lights"]["brdf_glsl"] == "brdf_phong.glsl"
    assert any(line.startswith("lights: 1 (1 samples") for line in auto.description)
    assert none.info["lights"]["count"] == 0 and any(line == "lights: none (none requested)"
                                                      for line in none.description)
    assert RenderOptions(lights=3).lights == 3 and RenderOptions(lights="0").lights == "none"
    for bad in ("some", -1, 9, 2.5):
        with pytest.raises(BadInputError):
            RenderOptions(lights=bad)


def test_without_lights_the_shaders_hold_no_light_code(sphere) -> None:
    """n = 0 costs nothing: an SHRM without lights makes the same shaders as before (no light
    code, no uniforms, no table texture)."""
    shrm = SHRM(F=0, P=1, coeffs=np.ones((4, 8, 16, 3), np.float32))
    for shading in (distant_shading(shrm, sphere), perpixel_shading(shrm, sphere)):
        text = "".join(t for _, t in shading.fragment) + "".join(t for _, t in shading.deferred or [])
        assert "shrm_lights" not in text and not shading.uniforms and not shading.textures
