"""The render-mode table (render.modes) and render_scene (render.api).

References: every mode's GPU image of a sphere under an orthographic camera against the CPU
renderer (analytic ray–sphere intersection + the built model's own numpy ``radiance``), the
distant and rsibr per-frame maps against ``SHRM.view_map`` and ``RSIBRMaps.view_map``, the
SHRM orders against an independent ``prefilter`` call, and a constant-colour mode added to
the table in the test (closed form: the colour where the sphere covers the pixel).
"""

from __future__ import annotations

import argparse

import numpy as np
import pytest

from shrmkit.analysis.baselines.gaussian_lobes import GaussianLobeModel, GaussianLobes, sg_mip_stack
from shrmkit.analysis.baselines.rsibr import RSIBRMaps, rsibr_from_shrm
from shrmkit.analysis.shrm import SHRM, prefilter
from shrmkit.analysis.tolerance import DEFAULT_EPS
from shrmkit.brdf_io.envmap import load_env
from shrmkit.brdf_io.errors import BadInputError
from shrmkit.cli.main import build_parser, main
from shrmkit.render import defaults as render_defaults
from shrmkit.render import modes
from shrmkit.render.api import render_scene
from shrmkit.render.camera import Camera
from shrmkit.render.cpu_reference import shade, sphere_geometry
from shrmkit.render.glsl import Shading, fragment_replacements, vertex_replacements
from shrmkit.render.mesh import load_mesh
from shrmkit.render.modes import (
    RENDER_MODES,
    BuiltModel,
    RenderMode,
    RenderOptions,
    get_mode,
    mode_names,
    self_shadow_modes,
)
from shrmkit.render.shader import atlas_layout, packed_tiles
from shrmkit.render.vtk_renderer import SHRMRenderer

ENV = "builtin:studio,height=16"
BRDF = "microfacet:sigma=0.3"  # P = 2 at DEFAULT_EPS: the SHRM modes differ
SPHERE = "builtin:sphere:subdivisions=4"
VIEW = (0.3, 1.0, 0.5)


def _render_subparser() -> argparse.ArgumentParser:
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return sub.choices["render"]


def _action(parser: argparse.ArgumentParser, option: str) -> argparse.Action:
    return next(a for a in parser._actions if option in a.option_strings)


def rel_rms(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.sqrt(np.mean((a - b) ** 2)) / np.sqrt(np.mean(b**2)))


# ----------------------------------------------------------------------------------------------
# The table and the CLI
# ----------------------------------------------------------------------------------------------


def test_table_holds_the_five_modes() -> None:
    assert mode_names() == ("distant", "perpixel", "rsibr", "kautz-mccool", "gaussian-lobes")
    assert self_shadow_modes() == ("gaussian-lobes",)
    assert [name for name, m in RENDER_MODES.items() if m.update is not None] == ["distant", "rsibr"]
    for name, record in RENDER_MODES.items():
        assert record.name == name and record.help and "\n" not in record.help


def test_cli_mode_choices_and_help_come_from_the_table() -> None:
    parser = _render_subparser()
    mode = _action(parser, "--mode")
    assert tuple(mode.choices) == mode_names()
    assert mode.default == modes.DEFAULT_MODE
    for record in RENDER_MODES.values():
        assert record.help in mode.help
    assert _action(parser, "--eps").default == DEFAULT_EPS
    assert _action(parser, "--lobes").default == RenderOptions().lobes
    assert _action(parser, "--elevations").default == RenderOptions().elevations


def test_unknown_mode_is_refused_clearly(tmp_path, capsys) -> None:
    with pytest.raises(BadInputError, match=r"unknown render mode 'phong'; known: distant, perpixel, rsibr"):
        get_mode("phong")
    # refused before any loading: the mesh file does not exist
    with pytest.raises(BadInputError, match="unknown render mode 'bogus'"):
        render_scene(tmp_path / "missing.obj", ENV, BRDF, mode="bogus")
    with pytest.raises(SystemExit) as exit_info:
        main(["render", "builtin:sphere", "--mode", "bogus", "-o", str(tmp_path / "x.png")])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert "invalid choice: 'bogus'" in err and "gaussian-lobes" in err
    assert not any(tmp_path.iterdir())


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"eps": 2.0}, r"eps must be in \(0, 1\)"),
        ({"size": 4}, r"size must be an integer in \[16, 8192\]"),
        ({"background": "grey"}, "background must be one of env, black, transparent"),
        ({"fps_frames": -1}, "fps_frames must be an integer >= 0"),
        ({"camera": []}, "non-empty sequence of Cameras"),
        ({"options": RenderOptions(self_shadow=True)}, "self_shadow needs mode gaussian-lobes, not 'distant'"),
    ],
)
def test_render_scene_checks_arguments_before_loading(tmp_path, kwargs, message) -> None:
    with pytest.raises(BadInputError, match=message):
        render_scene(tmp_path / "missing.obj", ENV, BRDF, **kwargs)


@pytest.mark.parametrize(("kwargs", "name"), [({"lobes": 9}, "lobes"), ({"elevations": 0}, "elevations"),
                                              ({"lobes": 2.5}, "lobes")])
def test_render_options_are_checked(kwargs, name) -> None:
    with pytest.raises(BadInputError, match=f"{name} must be an integer in"):
        RenderOptions(**kwargs)


# ----------------------------------------------------------------------------------------------
# Records without OpenGL: model checks, textures, per-frame updates
# ----------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def small_sphere():
    return load_mesh("builtin:sphere:subdivisions=2")


@pytest.fixture(scope="module")
def random_shrm() -> SHRM:
    rng = np.random.default_rng(5)
    return SHRM(F=3, P=2, coeffs=rng.normal(size=(9, 8, 16, 3)).astype(np.float32))


@pytest.fixture(scope="module")
def lobe_model() -> GaussianLobeModel:
    theta_v = np.linspace(0.0, np.radians(80.0), 3)
    lobes = GaussianLobes(theta_v, np.zeros((3, 1)), np.full((3, 1), 0.2), np.ones((3, 1, 3)), np.zeros(3))
    return GaussianLobeModel(lobes, sg_mip_stack(np.ones((16, 32, 3))))


def test_prepare_refuses_models_and_visibility_of_other_modes(small_sphere, random_shrm, lobe_model) -> None:
    with pytest.raises(ValueError, match="mode 'distant' takes a SHRM, got GaussianLobeModel"):
        get_mode("distant").prepare(lobe_model, small_sphere)
    with pytest.raises(ValueError, match="takes a GaussianLobeModel, got SHRM"):
        get_mode("gaussian-lobes").prepare(random_shrm, small_sphere)
    with pytest.raises(ValueError, match="only supported in mode 'gaussian-lobes'"):
        get_mode("perpixel").prepare(random_shrm, small_sphere, np.zeros((len(small_sphere.vertices), 25)))
    with pytest.raises(ValueError, match=r"visibility_sh must be finite \(n_vertices=162, 25\)"):
        get_mode("gaussian-lobes").prepare(lobe_model, small_sphere, np.zeros((3, 25)))


def test_distant_and_rsibr_updates_equal_the_models_view_maps(small_sphere, random_shrm) -> None:
    """The per-frame texture = SHRM.view_map (RH02 eq. 12, a tensordot) / RSIBRMaps.view_map."""
    view = np.array([0.2, -0.7, 0.4])
    view /= np.linalg.norm(view)
    maps = rsibr_from_shrm(random_shrm)
    for name, model, want in [("distant", random_shrm, random_shrm.view_map(view)),
                              ("rsibr", random_shrm, maps.view_map(view)),
                              ("rsibr", maps, maps.view_map(view))]:
        record = get_mode(name)
        shading = record.prepare(model, small_sphere)
        buffer = np.zeros(shading.texture.size, dtype=np.float32).reshape(-1, 3)
        record.update(shading.state, view, buffer)
        np.testing.assert_allclose(buffer.reshape(want.shape), want, rtol=1e-5, atol=1e-5)


def test_perpixel_atlas_tiles_hold_the_coefficient_maps(small_sphere, random_shrm) -> None:
    """The packed RGBA atlas: scalar map 3c + k (coefficient c, channel k) is component
    (3c + k) mod 4 of tile (3c + k) div 4, copied exactly; the 27 maps of P = 2 fill 7 tiles."""
    for name in ("perpixel", "kautz-mccool"):
        texture = get_mode(name).prepare(random_shrm, small_sphere).texture
        assert packed_tiles(9) == 7
        cols, rows = atlas_layout(7)
        assert texture.shape == (rows * 8, cols * 16, 4) and texture.dtype == np.float32
        for c in range(9):
            for k in range(3):
                r, q = divmod((3 * c + k) // 4, cols)
                tile = texture[r * 8:(r + 1) * 8, q * 16:(q + 1) * 16, (3 * c + k) % 4]
                np.testing.assert_array_equal(tile, random_shrm.coeffs[c, ..., k])
        assert np.all(texture[2 * 8:3 * 8, 0:16, 3] == 0.0)  # tile 6 (row 2, column 0), component 3: padding


def test_gaussian_visibility_travels_as_seven_vec4_attributes(small_sphere, lobe_model) -> None:
    vis = np.random.default_rng(2).normal(size=(len(small_sphere.vertices), 25))
    shading = get_mode("gaussian-lobes").prepare(lobe_model, small_sphere, vis, normalized_visibility=False)
    packed = np.concatenate([shading.attributes[f"glVis{i}"] for i in range(7)], axis=1)
    assert packed.shape == (len(small_sphere.vertices), 28)
    np.testing.assert_allclose(packed[:, :25], vis, rtol=1e-6)
    assert np.all(packed[:, 25:] == 0.0)
    assert "in vec4 glVis6;" in shading.vertex[0][1] and "in vec4 glVis6_f;" in shading.fragment[0][1]


# ----------------------------------------------------------------------------------------------
# Rendering through render_scene
# ----------------------------------------------------------------------------------------------


@pytest.mark.render
@pytest.mark.parametrize("mode", mode_names())
def test_every_mode_renders_a_sphere_through_render_scene(offscreen, mode) -> None:
    """Finite, non-zero image; inside the disc it equals the CPU render of the model built."""
    cam = Camera.looking_at(view=VIEW, projection="ortho")
    stages: list[str] = []
    result = render_scene(SPHERE, ENV, BRDF, mode=mode, camera=cam, size=40, background="black", fps_frames=0,
                          options=RenderOptions(lobes=2, elevations=4), progress=stages.append)
    assert stages == ["load", "build", "render"]
    assert result.mode == mode and len(result.frames) == 1 and result.size == 40
    frame = result.frames[0]
    assert frame.linear.shape == (40, 40, 3) and np.all(np.isfinite(frame.linear))
    assert frame.linear.max() > 0.0 and not frame.transparent
    assert isinstance(result.model, get_mode(mode).models)
    geom = sphere_geometry(cam, 40, 40)
    assert np.sum(geom.hit != (frame.alpha > 0.5)) <= 8
    inside = geom.hit & (frame.alpha > 0.5) & (np.sum(geom.N * geom.V, -1) > 0.3)
    cpu = shade(geom, result.model.radiance)
    assert rel_rms(frame.linear[inside], cpu[inside]) < 0.01
    assert np.all(frame.linear[frame.alpha == 0.0] == 0.0)  # black background
    assert result.built.description and all(isinstance(line, str) for line in result.built.description)


@pytest.mark.render
def test_render_scene_model_descriptions_match_independent_builds(offscreen) -> None:
    """SHRM orders and map size equal those of a separate prefilter call; Kautz–McCool is the
    q = 0 SHRM on the SHRM's (F, P) and rows (the table of methods); RSIBR holds twelve maps on the
    SHRM's grid; lobes as asked."""
    env = load_env(ENV)
    shrm = prefilter(env, BRDF, eps=DEFAULT_EPS)
    ref = prefilter(env, BRDF, eps=DEFAULT_EPS, F=shrm.F, P=shrm.P, size=shrm.height, azimuth_free=True)
    kw = {"camera": Camera.looking_at(projection="ortho"), "size": 16, "background": "black", "fps_frames": 0}
    results = {}
    for mode in ("distant", "perpixel", "kautz-mccool", "rsibr"):
        results[mode] = render_scene(SPHERE, env, BRDF, mode=mode, **kw)
        info = results[mode].built.info
        assert (info["F"], info["P"], info["height"], info["width"]) == (shrm.F, shrm.P, shrm.height, shrm.width)
        assert info["eps"] == DEFAULT_EPS and info["prefilter_seconds"] > 0
        assert info["azimuth_free"] is (mode == "kautz-mccool")
    rsibr = results["rsibr"]
    assert isinstance(rsibr.model, RSIBRMaps) and rsibr.model.maps.shape == (12, shrm.height, shrm.width, 3)
    km = results["kautz-mccool"].model
    # Kautz–McCool: the azimuth-free SHRM of prefilter(..., azimuth_free=True) on the SHRM's grid
    np.testing.assert_allclose(km.coeffs, ref.coeffs, rtol=1e-5, atol=1e-6 * np.abs(ref.coeffs).max())
    # the models differ from the full SHRM by far more than the 1 % the render test allows
    geom = sphere_geometry(Camera.looking_at(view=VIEW, projection="ortho"), 40, 40)
    inside = geom.hit & (np.sum(geom.N * geom.V, -1) > 0.3)
    full = shade(geom, shrm.radiance)[inside]
    for other in (km, rsibr.model):
        assert rel_rms(shade(geom, other.radiance)[inside], full) > 0.02
    lobes = render_scene(SPHERE, env, BRDF, mode="gaussian-lobes", options=RenderOptions(lobes=2, elevations=3), **kw)
    info = lobes.built.info
    assert (info["K"], info["elevations"]) == (2, 3) and lobes.model.lobes.mu.shape == (3, 2)
    assert info["max_fit_residual"] == pytest.approx(float(lobes.model.lobes.residual.max()))
    assert info["mip_levels"] == len(lobes.model.stack.levels)


@pytest.mark.render
def test_self_shadowing_on_a_convex_mesh_changes_nothing(offscreen) -> None:
    """A sphere never occludes itself: the normalized visibility is 1 and the image equals the
    unshadowed one."""
    kw = {"mode": "gaussian-lobes", "camera": Camera.looking_at(view=VIEW, projection="ortho"), "size": 32,
          "background": "black", "fps_frames": 0}
    mesh = "builtin:sphere:subdivisions=2"
    plain = render_scene(mesh, ENV, BRDF, options=RenderOptions(lobes=1, elevations=3), **kw)
    shadowed = render_scene(mesh, ENV, BRDF, options=RenderOptions(lobes=1, elevations=3, self_shadow=True), **kw)
    assert shadowed.built.visibility_sh.shape == (162, 25) and "visibility_seconds" in shadowed.built.info
    a, b = plain.frames[0].linear, shadowed.frames[0].linear
    assert a.max() > 0
    np.testing.assert_allclose(b, a, rtol=1e-4, atol=1e-5 * a.max())


# ----------------------------------------------------------------------------------------------
# A new mode is one table entry
# ----------------------------------------------------------------------------------------------


def _constant_shading(colour: np.ndarray, mesh) -> Shading:
    body = ["  vec3 shrmRad = texelFetch(shrmTex, ivec2(0, 0), 0).rgb;"]
    return Shading(colour.reshape(1, 1, 3).astype(np.float32), vertex_replacements(), fragment_replacements([], body))


def _constant_build(env, brdf, mesh, *, eps, options) -> BuiltModel:
    return BuiltModel(np.array([0.25, 2.0, 7.5]), {"colour": "constant"}, ("constant colour",))


@pytest.mark.render
def test_a_mode_added_to_the_table_reaches_the_renderer_and_the_cli(offscreen, monkeypatch) -> None:
    record = RenderMode("constant", "one colour everywhere", _constant_build, (np.ndarray,), _constant_shading)
    monkeypatch.setitem(RENDER_MODES, "constant", record)
    # the CLI's parser reads the modes' names and help from render.defaults (numpy-free, issue 26)
    monkeypatch.setitem(render_defaults.RENDER_MODE_HELP, "constant", record.help)
    assert "constant" in _action(_render_subparser(), "--mode").choices
    cam = Camera.looking_at(view=VIEW, projection="ortho")
    result = render_scene(SPHERE, ENV, BRDF, mode="constant", camera=cam, size=24, background="black", fps_frames=0)
    covered = result.frames[0].alpha > 0.5
    geom = sphere_geometry(cam, 24, 24)
    assert np.sum(geom.hit != covered) <= 6
    colour = np.array([0.25, 2.0, 7.5], dtype=np.float32)
    np.testing.assert_array_equal(result.frames[0].linear[covered], np.broadcast_to(colour, (covered.sum(), 3)))
    with SHRMRenderer(8, 8) as r:
        with pytest.raises(ValueError, match="unknown render mode 'constant2'"):
            r.add_object(load_mesh(SPHERE), np.zeros(3), mode="constant2")

