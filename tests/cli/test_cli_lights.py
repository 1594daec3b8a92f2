"""``--lights auto|none|N`` on the verbs that prefilter or state scene orders: default ``auto``,
listed in tables and ``--json``, passed to the SHRM file; a bad value exits 2 with one line.

Independent reference: the one-pixel sun of ``builtin:sun`` (closed form: one light at that
pixel, the rest a constant sky)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import shrmkit
from shrmkit.cli.main import main

SUN = "builtin:sun,height=32,elevation=30,azimuth=40"


def test_prefilter_takes_the_sun_out_and_lists_it(tmp_path: Path, capsys) -> None:
    out = tmp_path / "m.shrm.npz"
    assert main(["prefilter", "--env", SUN, "--brdf", "phong:s=100", "--json", "-o", str(out)]) == 0
    doc = json.loads(capsys.readouterr().out)
    lights = doc["meta"]["lights"]
    assert len(lights) == 1 and lights[0]["pixels"] == 1 and lights[0]["samples"] == 1
    assert abs(lights[0]["elevation_deg"] - 30.0) < 3.0 and abs(lights[0]["azimuth_deg"] - 40.0) < 3.0
    assert doc["meta"]["lights_requested"] == "auto" and doc["meta"]["capped"] is False
    back = shrmkit.load_shrm(out)
    assert back.has_lights and back.F <= 2  # the rest is a constant sky
    assert main(["prefilter", "--env", SUN, "--brdf", "phong:s=100", "-o", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "lights taken out of the map" in printed and "exact" in printed


def test_prefilter_lights_none_and_a_count(tmp_path: Path, capsys) -> None:
    out = tmp_path / "m.shrm.npz"
    assert main(["prefilter", "--env", SUN, "--brdf", "phong:s=100", "--lights", "none", "--json",
                 "-o", str(out)]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["meta"]["lights"] == [] and not shrmkit.load_shrm(out).has_lights and doc["F"] > 10
    image = np.full((32, 64, 3), 0.05)
    image[8, 10], image[20, 40], image[14, 25] = 900.0, 500.0, 300.0
    from shrmkit.brdf_io.pfm import write_pfm

    path = tmp_path / "three.pfm"
    write_pfm(path, image.astype(np.float32))
    assert main(["prefilter", "--env", str(path), "--brdf", "phong:s=50", "--lights", "2", "--json",
                 "-o", str(out)]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert len(doc["meta"]["lights"]) == 2 and doc["meta"]["lights_left_in_map"] == 1


@pytest.mark.parametrize("verb", ["prefilter", "orders", "report", "compare", "view", "render"])
def test_bad_lights_value_exits_2(verb, tmp_path: Path, capsys) -> None:
    args = {
        "prefilter": ["prefilter", "--env", SUN, "--brdf", "phong:s=8", "-o", str(tmp_path / "m.shrm.npz")],
        "orders": ["orders", "phong:s=8", "--env", SUN],
        "report": ["report", "phong:s=8", "--out", str(tmp_path / "rep")],
        "compare": ["compare", "phong:s=8", "--env", SUN],
        "view": ["view", "phong:s=8", "--env", SUN, "-o", str(tmp_path / "v.html")],
        "render": ["render", "builtin:sphere", "--env", SUN, "-o", str(tmp_path / "r.png")],
    }[verb]
    with pytest.raises(SystemExit) as exc:
        main([*args, "--lights", "bright"])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "--lights" in err and "auto, none or a number" in err
    assert not list(tmp_path.iterdir())


def test_orders_with_env_states_the_scene_without_its_lights(capsys) -> None:
    assert main(["orders", "microfacet:sigma=0.1", "--env", SUN, "--json"]) == 0
    lit = json.loads(capsys.readouterr().out)
    assert main(["orders", "microfacet:sigma=0.1", "--env", SUN, "--json", "--lights", "none"]) == 0
    bare = json.loads(capsys.readouterr().out)
    assert len(lit["lights"]) == 1 and bare["lights"] == []
    assert lit["F_B"] < bare["F_B"]


def test_report_lists_the_lights(tmp_path: Path) -> None:
    out = tmp_path / "rep"
    assert main(["report", "phong:s=100", "--out", str(out), "--quick", "--preview", "none", "--models", "lafortune",
                 "--tolerances", "0.1", "--eps", "0.1", "--pairs", "30", "--fit-samples", "1024", "--no-progress",
                 "--no-plots", "--env", SUN]) == 0
    doc = json.loads((out / "phong_s_100" / "report.json").read_text())
    assert doc["options"]["lights"] == "auto"
    env = doc["environments"][0]
    assert len(env["lights"]) == 1 and env["capped"] is False and env["capped_by"] == []
    assert doc["speed_vs_error"][0]["lights"] == 1


@pytest.mark.render
def test_render_prints_the_lights(offscreen, tmp_path: Path, capsys) -> None:
    png = tmp_path / "r.png"
    assert main(["render", "builtin:sphere", "--env", SUN, "--brdf", "phong:s=100", "--size", "24",
                 "--fps-frames", "0", "-o", str(png)]) == 0
    printed = capsys.readouterr().out
    assert "lights:" in printed and png.is_file()
    assert main(["render", "builtin:sphere", "--env", SUN, "--brdf", "phong:s=100", "--size", "24",
                 "--fps-frames", "0", "--lights", "none", "-o", str(png)]) == 0
    assert "lights: none" in capsys.readouterr().out
