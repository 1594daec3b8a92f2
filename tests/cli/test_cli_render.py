"""``shrm render``: outputs, timings, turntable naming and bad input (exit 2, no output left).

References: the EXR is compared with the CPU reference of the same SHRM (analytic sphere
geometry + SHRM.radiance), built independently of the shader.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import OpenEXR
import pytest
from PIL import Image

import shrmkit
from shrmkit.analysis.tolerance import DEFAULT_EPS
from shrmkit.cli.main import main
from shrmkit.render.camera import Camera
from shrmkit.render.cpu_reference import shade, sphere_geometry


def _read_exr(path: Path) -> tuple[np.ndarray, np.ndarray]:
    with OpenEXR.File(str(path), separate_channels=True) as f:
        ch = {k: np.asarray(v.pixels) for k, v in f.channels().items()}
    return np.stack([ch["R"], ch["G"], ch["B"]], axis=-1), ch["A"]


@pytest.mark.render
def test_render_sphere_png_exr_and_timings(offscreen, tmp_path: Path, capsys) -> None:
    """Ortho sphere in distant mode: EXR = CPU reference of the same prefiltered SHRM inside the disc,
    environment behind it; PNG written; timings printed."""
    png, exr = tmp_path / "s.png", tmp_path / "s.exr"
    rc = main(["render", "builtin:sphere:subdivisions=5", "--env", "builtin:studio", "--brdf", "phong:s=8",
               "--size", "48", "--camera", "ortho", "--view", "0,1,0.5", "--fps-frames", "2",
               "-o", str(png), "--exr", str(exr)])
    assert rc == 0
    out = capsys.readouterr().out
    for word in ("prefilter:", "first frame:", "frames per second:"):
        assert word in out
    assert np.asarray(Image.open(png)).shape == (48, 48, 3)
    rad, alpha = _read_exr(exr)
    shrm = shrmkit.prefilter("builtin:studio", "phong:s=8", eps=DEFAULT_EPS)
    cam = Camera.looking_at(view=(0, 1, 0.5), projection="ortho")
    geom = sphere_geometry(cam, 48, 48)
    inside = geom.hit & (alpha > 0.5) & (np.sum(geom.N * geom.V, -1) > 0.2)
    ref = shade(geom, shrm.radiance)[inside]
    rel = np.sqrt(np.mean((rad[inside] - ref) ** 2)) / np.sqrt(np.mean(ref**2))
    assert rel < 5e-3
    assert np.all(rad[alpha == 0] >= 0) and rad[alpha == 0].max() > 0  # the environment behind


@pytest.mark.render
def test_turntable_transparent(offscreen, tmp_path: Path) -> None:
    png = tmp_path / "spin.png"
    rc = main(["render", "builtin:torus:segments=48,sides=12", "--size", "24", "--turntable", "3",
               "--background", "transparent", "--fps-frames", "0", "--mode", "perpixel", "-o", str(png)])
    assert rc == 0
    names = sorted(p.name for p in tmp_path.iterdir())
    assert names == ["spin.gif", "spin_0000.png", "spin_0001.png", "spin_0002.png"]
    rgba = np.asarray(Image.open(tmp_path / "spin_0001.png"))
    assert rgba.shape == (24, 24, 4) and rgba[0, 0, 3] == 0 and rgba[12, 6:18, 3].max() == 255


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["nan.obj"], "not finite"),
        (["missing.obj"], "no such file"),
        (["empty.obj"], "empty.obj"),
        (["builtin:sphere", "--view", "1,0"], "--view"),
        (["builtin:sphere", "--view", "0,0,1"], "parallel"),
        (["builtin:sphere", "--size", "4"], "--size"),
        (["builtin:sphere", "--eps", "2"], "--eps"),
        (["builtin:sphere", "--self-shadow"], "--self-shadow needs --mode gaussian-lobes"),
        (["builtin:sphere", "--lobes", "2"],
         "--lobes apply only to --mode gaussian-lobes (the Gaussian-lobe fit), not to --mode distant"),
        (["builtin:sphere", "--mode", "perpixel", "--lobes", "3", "--elevations", "15"],
         "--lobes and --elevations apply only to --mode gaussian-lobes (the Gaussian-lobe fit), not to --mode "
         "perpixel"),
        (["builtin:sphere", "--mode", "rsibr", "--elevations", "4"], "--elevations apply only to --mode gaussian"),
        (["builtin:sphere", "--mode", "gaussian-lobes", "--lobes", "9"], "lobes must be an integer in [1, 8], got 9"),
        (["stray.ply"], "stray.ply: is a FIFO"),
    ],
)
def test_bad_input_exits_2_without_output(tmp_path: Path, capsys, monkeypatch, args, message) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "nan.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 nan 0\nf 1 2 3\n")
    (tmp_path / "empty.obj").write_text("")
    os.mkfifo(tmp_path / "stray.ply")
    before = set(tmp_path.iterdir())
    rc = main(["render", *args, "-o", "out.png", "--exr", "out.exr"])
    assert rc == 2
    err = capsys.readouterr().err
    assert err.startswith("shrm render: error:") and message in err
    assert set(tmp_path.iterdir()) == before


def test_lobe_options_reach_the_gaussian_lobes_builder(monkeypatch, tmp_path: Path) -> None:
    """With --mode gaussian-lobes the given --lobes/--elevations are used; omitted ones keep
    the RenderOptions defaults (no render: the options are checked and built only)."""
    from shrmkit.cli import cmd_render
    from shrmkit.cli.main import build_parser
    from shrmkit.render.modes import RenderOptions

    parse = build_parser().parse_args
    out = str(tmp_path / "o.png")
    _, options = cmd_render._validate(parse(["render", "builtin:sphere", "--mode", "gaussian-lobes", "--lobes", "2",
                                             "-o", out]))
    assert (options.lobes, options.elevations) == (2, RenderOptions().elevations)
    _, options = cmd_render._validate(parse(["render", "builtin:sphere", "-o", out]))
    assert (options.lobes, options.elevations) == (RenderOptions().lobes, RenderOptions().elevations)


def test_default_exposure_brings_the_environment_mean_to_middle_grey(tmp_path, capsys):
    """Without --exposure the PNG is exposed so that the map's mean luminance is 0.18 (Grace's
    mean 0.016 rendered at exposure 0 was nearly black); the choice is printed and in --json."""
    import json

    import numpy as np

    from shrmkit import load_env

    spec = "builtin:studio,height=32"
    env = load_env(spec)
    # the solid-angle-weighted mean of the map (RGB average), written out
    mean = float((env.radiance.mean(axis=2).mean(axis=1) * env.solid_angles()).sum() / env.solid_angles().sum())
    expected = float(np.log2(0.18 / mean))
    assert main(["render", "builtin:sphere:subdivisions=2", "--env", spec, "--brdf", "lambert:albedo=0.5",
                 "--size", "24", "--fps-frames", "0", "-o", str(tmp_path / "a.png"), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert abs(doc["exposure"] - expected) < 1e-9
    assert main(["render", "builtin:sphere:subdivisions=2", "--env", spec, "--brdf", "lambert:albedo=0.5",
                 "--size", "24", "--fps-frames", "0", "-o", str(tmp_path / "b.png")]) == 0
    assert f"exposure {doc['exposure']:+.2f} stops" in capsys.readouterr().out


def test_render_of_scattered_measurements_goes_through_their_representation(shared_data, tmp_path, capsys):
    """Every verb accepts what report accepts (issue 24): a CURET sample is rendered through the
    representation chosen by held-out error, named in --json."""
    import json

    source = f"{shared_data / 'brdf' / 'curet' / 'abrdf.dat'}#1"
    assert main(["render", "builtin:sphere:subdivisions=2", "--env", "builtin:sky,height=16", "--brdf", source,
                 "--size", "16", "--fps-frames", "0", "-o", str(tmp_path / "c.png"), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    rep = doc["representation"]
    assert rep is not None and rep["line"].startswith("analysed through")
    assert (tmp_path / "c.png").is_file()
