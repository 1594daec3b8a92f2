"""``shrm render --env-rotation`` and ``--light-turntable``: frames, the per-frame cost line, the sense
of AZ, and bad input (exit 2, one line, no output left).

References: ``--env-azimuth`` (the map rolled at load by a whole number of columns, prefiltered
anew) for ``--env-rotation AZ,0``; the file names of the camera turntable (``turntable_paths``).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import OpenEXR
import pytest

from shrmkit.cli.main import main

COMMON = ["builtin:sphere:subdivisions=3", "--env", "builtin:studio,height=32", "--brdf", "phong:s=8",
          "--size", "32", "--fps-frames", "0"]


def _read_exr(path: Path) -> tuple[np.ndarray, np.ndarray]:
    with OpenEXR.File(str(path), separate_channels=True) as f:
        ch = {k: np.asarray(v.pixels) for k, v in f.channels().items()}
    return np.stack([ch["R"], ch["G"], ch["B"]], axis=-1), ch["A"]


@pytest.mark.render
def test_light_turntable_frames_and_cost_line(offscreen, tmp_path: Path, capsys) -> None:
    """N frames named as the camera turntable's, built once, the per-frame cost printed; the frames
    differ (the lighting turns) while the coverage (the camera) stays."""
    png = tmp_path / "light.png"
    assert main(["render", *COMMON, "--light-turntable", "3", "-o", str(png), "--exr", str(tmp_path / "l.exr")]) == 0
    out = capsys.readouterr().out
    assert out.count("prefilter:") == 1
    line = next(s for s in out.splitlines() if s.startswith("light turntable:"))
    assert "3 frames" in line and "ms per frame" in line and "built once in" in line
    names = sorted(p.name for p in tmp_path.iterdir())
    assert names == ["l_0000.exr", "l_0001.exr", "l_0002.exr", "light.gif", "light_0000.png", "light_0001.png",
                     "light_0002.png"]
    (a, alpha_a), (b, alpha_b) = _read_exr(tmp_path / "l_0000.exr"), _read_exr(tmp_path / "l_0001.exr")
    assert np.array_equal(alpha_a, alpha_b)
    assert np.abs(a - b).max() > 0.01


@pytest.mark.render
def test_env_rotation_renders_what_env_azimuth_renders(offscreen, tmp_path: Path) -> None:
    """``--env-rotation 90,0`` (one prefilter, turned at view time) = ``--env-azimuth 90`` (the map
    rolled by 16 of 64 columns at load and prefiltered anew): object and background."""
    images = {}
    for name, option in (("rot", ["--env-rotation", "90,0"]), ("az", ["--env-azimuth", "90"]), ("no", [])):
        exr = tmp_path / f"{name}.exr"
        assert main(["render", *COMMON, *option, "-o", str(tmp_path / f"{name}.png"), "--exr", str(exr)]) == 0
        images[name] = _read_exr(exr)
    (rot, alpha), (az, _), (no, _) = images["rot"], images["az"], images["no"]
    m = alpha > 0.5
    assert np.sqrt(np.mean((rot[m] - az[m]) ** 2)) <= 1e-3 * np.sqrt(np.mean(az[m] ** 2))
    np.testing.assert_allclose(rot[~m], az[~m], rtol=1e-5, atol=1e-6)
    assert np.sqrt(np.mean((no[m] - az[m]) ** 2)) > 0.05 * np.sqrt(np.mean(az[m] ** 2))


@pytest.mark.parametrize(("args", "message"), [
    (["--env-rotation", "70,x"], "--env-rotation must be two or three finite numbers AZ,EL[,ROLL] in degrees, "
                                 "got '70,x'"),
    (["--env-rotation", "70"], "got '70'"),
    (["--env-rotation", "1,2,3,4"], "got '1,2,3,4'"),
    (["--env-rotation", "nan,0"], "got 'nan,0'"),
    (["--light-turntable", "-1"], "--light-turntable"),
    (["--turntable", "2", "--light-turntable", "2"], "choose one"),
])
def test_bad_rotation_options_exit_2_without_output(tmp_path: Path, capsys, monkeypatch, args, message) -> None:
    monkeypatch.chdir(tmp_path)
    rc = main(["render", "builtin:sphere", *args, "-o", "out.png", "--exr", "out.exr"])
    assert rc == 2
    err = capsys.readouterr().err
    assert err.startswith("shrm render: error:") and message in err and err.count("\n") == 1
    assert list(tmp_path.iterdir()) == []
