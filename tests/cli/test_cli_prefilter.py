"""`shrm prefilter`: a loadable SHRM file, bad input exits 2 with no file left behind."""

from __future__ import annotations

import shrmkit
from shrmkit.cli.main import main


def test_prefilter_writes_loadable_file(tmp_path, capsys):


    out = tmp_path / "m.shrm.npz"
    assert main(["prefilter", "--env", "builtin:sky,height=32", "--brdf", "phong:s=16", "-o", str(out)]) == 0
    m = shrmkit.load_shrm(out)
    assert m.P == 0 and m.F > 0
    assert "wrote" in capsys.readouterr().out


def test_prefilter_bad_input_leaves_no_file(tmp_path, capsys, run_main):
    out = tmp_path / "bad.shrm.npz"
    code, err = run_main("prefilter", "--env", str(tmp_path / "missing.exr"), "--brdf", "phong:s=8",
                         "-o", str(out))
    assert code == 2 and "missing.exr" in err
    code, err = run_main("prefilter", "--env", "builtin:sky", "--brdf", "lambert:albedo=0", "-o", str(out))
    assert code == 2 and "zero everywhere" in err
    assert not out.exists() and not list(tmp_path.iterdir())


def test_prefilter_eps_is_validated_by_the_one_rule(tmp_path, capsys, run_main):
    """--eps outside (0, 1) is a usage error (exit 2) with check_eps's message; no file is written."""
    out = tmp_path / "m.shrm.npz"
    code, err = run_main("prefilter", "--env", "builtin:sky,height=16", "--brdf", "phong:s=8", "--eps", "1.5",
                         "-o", str(out))
    assert code == 2 and "eps must be in (0, 1), got 1.5" in err
    assert not out.exists()


def test_pixel_rule_on_and_off(tmp_path, capsys):
    """`--pixel-rule off` keeps the energy rule's F_B (no per-direction check), `on` (default) raises it
    under a sun left in the map; both print the per-pixel statement."""
    shrms = {}
    for rule in ("on", "off"):
        out = tmp_path / f"{rule}.shrm.npz"
        assert main(["prefilter", "--env", "builtin:sun,height=32", "--brdf", "phong:s=100", "--lights", "none",
                     "--pixel-rule", rule, "-o", str(out)]) == 0
        assert "per pixel:" in capsys.readouterr().out
        shrms[rule] = shrmkit.load_shrm(out)
    assert shrms["off"].meta["pixel_rule"] is None
    assert shrms["on"].meta["pixel_rule"]["F_from"] == shrms["off"].F < shrms["on"].F
