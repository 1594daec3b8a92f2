"""`shrm orders`: output, JSON keys, exit codes."""

from __future__ import annotations

import json

import numpy as np
import pytest

from shrmkit.cli.main import main


def test_orders_json(capsys):
    assert main(["orders", "phong:s=64", "--eps", "0.01", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    for key in ("F", "P", "eps", "tolerance", "table", "seconds"):
        assert key in doc
    assert doc["P"] == 0 and abs(doc["F"] - np.sqrt(-64 * np.log(0.01))) <= 1
    assert np.asarray(doc["table"]).shape[1] > doc["P"]


def test_orders_with_env_json(capsys):
    assert main(["orders", "microfacet:sigma=0.3", "--env", "builtin:studio,height=32", "--json",
                 "--criterion", "rh02"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["F_B"] == min(doc["F"], doc["F_L"]) and doc["P_B"] == doc["P"] and 0 <= doc["bound"] <= 1
    assert doc["criterion"] == "rh02"


def test_orders_bands_json_states_every_view_band(capsys):
    """The default rule: the worst band inside the 80° limit meets eps under a point light, and the
    per-band statement says so (eps = rel_rms²); the scene's bands are relative RMS."""
    assert main(["orders", "microfacet:sigma=0.3", "--env", "builtin:studio,height=32", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["criterion"] == "bands" and doc["max_view_deg"] == 80.0 and not doc["capped"]
    bands = doc["view_bands"]
    assert [b["theta_v_deg"][0] for b in bands] == [0, 15, 30, 45, 60, 70, 75, 80, 85]
    inside = [b for b in bands if b["inside"]]
    assert len(inside) == 7 and max(b["eps"] for b in inside) == pytest.approx(doc["eps"])
    assert doc["eps"] <= 0.03 and all(abs(b["rel_rms_point_light"] ** 2 - b["eps"]) < 1e-12 for b in bands)
    scene = doc["scene_view_bands"]
    assert all(0.0 < b["predicted_rel_rms"] <= b["bound_rel_rms"] for b in scene)
    assert max(b["predicted_rel_rms"] for b in scene if b["inside"]) <= np.sqrt(0.03) + 1e-9
    assert doc["bound_units"].startswith("relative RMS")


def test_max_view_angle_and_criterion_are_validated(capsys, run_main):
    for args in (["--max-view-angle", "95"], ["--max-view-angle", "0"], ["--criterion", "rh03"]):
        code, err = run_main("orders", "phong:s=8", *args)
        assert code == 2 and ("max-view-angle" in err or "criterion" in err)


def test_orders_table_output(capsys):
    assert main(["orders", "microfacet:sigma=0.4"]) == 0
    out = capsys.readouterr().out
    assert "eps(F, P)" in out and "orders for microfacet:sigma=0.4" in out


def test_capped_note_names_the_options(capsys):
    """The library's advice ("raise max_F/max_P") is printed with the options that set the caps."""
    assert main(["orders", "phong:s=32", "--max-F", "8"]) == 0
    out = capsys.readouterr().out
    assert "raise --max-F/--max-P" in out and "max_F" not in out


def test_bad_input_exit_2_one_line(capsys, run_main):
    for args in (["orders", "nosuch:a=1"], ["orders", "phong:s=8", "--eps", "2"], ["orders", "/no/file.binary"]):
        code, err = run_main(*args)
        assert code == 2, args
        assert err.strip().count("\n") == 0 or "usage" in err
        assert err.startswith(("shrm orders: error:", "usage: shrm orders")), err


def test_env_orientation_options_reach_the_loader(capsys):
    """--env-azimuth rotates a built-in map: a spot moved by 180° changes F_L's table not at all,
    but the prefiltered map is the rotated one (checked through the JSON bound, which is
    rotation invariant, and the run succeeding)."""
    assert main(["orders", "phong:s=8", "--env", "builtin:spot,height=16", "--env-azimuth", "180", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["environment"] and 0 <= doc["bound"] <= 1


def test_out_of_memory_is_one_line_naming_the_input(capsys, monkeypatch, run_main):
    """A MemoryError anywhere in a verb (issue 30: small files that ask for gigabytes) ends as one
    line naming the input, exit 2, no traceback."""
    import shrmkit.cli.cmd_orders as cmd_orders

    def exhausted(*args, **kwargs):
        raise MemoryError

    monkeypatch.setattr(cmd_orders, "choose_orders", exhausted)
    code, err = run_main("orders", "phong:s=10")
    assert code == 2 and "Traceback" not in err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "phong:s=10" in lines[0] and "out of memory" in lines[0], err


def test_long_messages_are_cut_with_a_count(capsys, run_main):
    """A 6,000-character spec echoed in its error (issue 30: 5-10 KB lines, 161 KB of a file's raw
    bytes) is cut to its start and end with the count left out, on one line."""
    code, err = run_main("orders", "phong:s=" + "9" * 6000)
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and len(lines[0]) < 600 and "characters left out" in lines[0], err[:300]
    assert lines[0].startswith("shrm orders: error: phong:s=999")
