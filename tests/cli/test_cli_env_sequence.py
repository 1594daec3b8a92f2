"""``shrm render --env A B C`` (several maps, a folder, a glob): one frame per map, the BRDF's orders
chosen once, and a bad member refused before anything is computed or written.

References: separate ``shrm render`` runs, one per map (each choosing its own orders), for the
frames; a call count of ``choose_orders`` for "once"; the turntable's file names
(``render.output.turntable_paths``) for the outputs.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import OpenEXR
import pytest

import shrmkit.analysis._prefilter as shrm_module  # prefilter's orders stage
import shrmkit.render.api as api_module
from shrmkit.brdf_io.envmap import load_env
from shrmkit.brdf_io.errors import BadInputError
from shrmkit.brdf_io.hdr_codecs import write_image
from shrmkit.cli.common import env_sources_arg
from shrmkit.cli.main import main

# one exposure for all: by default a sequence takes its first map's (no flicker) and a single render its own
COMMON = ["builtin:sphere:subdivisions=3", "--brdf", "phong:s=8", "--size", "32", "--fps-frames", "0",
          "--exposure", "0.5"]
MAPS = ["builtin:studio,height=32", "builtin:sky,height=32"]


def _read_exr(path: Path) -> tuple[np.ndarray, np.ndarray]:
    with OpenEXR.File(str(path), separate_channels=True) as f:
        ch = {k: np.asarray(v.pixels) for k, v in f.channels().items()}
    return np.stack([ch["R"], ch["G"], ch["B"]], axis=-1), ch["A"]


def _count_order_choices(monkeypatch) -> list[int]:
    """Count ``choose_orders`` calls wherever the render path can make one (the sequence's
    shared choice, and ``prefilter``'s own when it is given none)."""
    calls = [0]
    original = shrm_module.choose_orders

    def counting(*args, **kwargs):
        calls[0] += 1
        return original(*args, **kwargs)

    monkeypatch.setattr(shrm_module, "choose_orders", counting)
    monkeypatch.setattr(api_module, "choose_orders", counting)
    return calls


@pytest.mark.render
def test_sequence_frames_equal_separate_renders_and_orders_are_chosen_once(
    offscreen, tmp_path: Path, capsys, monkeypatch
) -> None:
    """Each frame of the sequence is pixel for pixel the frame of a separate ``shrm render`` of its map
    (linear EXR and PNG), and the sequence chooses the BRDF's orders once where the separate runs
    choose them once each; one cost line per map with its stated error."""
    calls = _count_order_choices(monkeypatch)
    out = tmp_path / "seq"
    out.mkdir()
    rc = main(["render", *COMMON, "--env", *MAPS, "-o", str(out / "s.png"), "--exr", str(out / "s.exr")])
    assert rc == 0
    assert calls[0] == 1
    text = capsys.readouterr().out
    lines = [s for s in text.splitlines() if s.startswith("frame ")]
    assert len(lines) == 2 and all("prefilter" in s and "stated relative RMS" in s for s in lines)
    assert "chosen once" in text and "environment sequence: 2 maps" in text
    assert sorted(p.name for p in out.iterdir()) == ["s.gif", "s_0000.exr", "s_0000.png", "s_0001.exr",
                                                     "s_0001.png"]
    calls[0] = 0
    for k, spec in enumerate(MAPS):
        one = tmp_path / f"one{k}"
        one.mkdir()
        assert main(["render", *COMMON, "--env", spec, "-o", str(one / "o.png"), "--exr", str(one / "o.exr")]) == 0
        seq_rgb, seq_alpha = _read_exr(out / f"s_{k:04d}.exr")
        one_rgb, one_alpha = _read_exr(one / "o.exr")
        np.testing.assert_array_equal(seq_rgb, one_rgb)
        np.testing.assert_array_equal(seq_alpha, one_alpha)
        assert (out / f"s_{k:04d}.png").read_bytes() == (one / "o.png").read_bytes()
    assert calls[0] == len(MAPS)
    a, b = _read_exr(out / "s_0000.exr")[0], _read_exr(out / "s_0001.exr")[0]
    assert np.abs(a - b).max() > 0.01  # the two maps light the sphere differently


def _write_maps(folder: Path, n: int) -> list[Path]:
    env = load_env("builtin:studio,height=8")
    paths = []
    for k in range(n):
        path = folder / f"t{k:02d}.hdr"
        write_image(path, env.radiance * (1.0 + k))
        paths.append(path)
    return paths


def test_folder_and_glob_expand_to_sorted_maps(tmp_path: Path) -> None:
    """A folder gives its map files sorted by name (other files left out), a pattern its matches; a
    cube-map folder stays one map; a single plain source is not a sequence."""
    paths = _write_maps(tmp_path, 3)
    (tmp_path / "notes.txt").write_text("not a map")
    expected = [str(p) for p in paths]
    assert env_sources_arg([str(tmp_path)]) == (expected, True)
    assert env_sources_arg([str(tmp_path / "t*.hdr")]) == (expected, True)
    assert env_sources_arg(["builtin:sky"]) == (["builtin:sky"], False)
    assert env_sources_arg(["builtin:sky", str(paths[0])]) == (["builtin:sky", expected[0]], True)
    cube = tmp_path / "cube"
    cube.mkdir()
    (cube / "px.hdr").write_bytes(b"")
    assert env_sources_arg([str(cube)]) == ([str(cube)], False)
    with pytest.raises(BadInputError, match="matches no file"):
        env_sources_arg([str(tmp_path / "none*.exr")])
    empty = tmp_path / "empty"
    empty.mkdir()
    with pytest.raises(BadInputError, match="holds no"):
        env_sources_arg([str(empty)])


@pytest.mark.parametrize("how", ["list", "folder"])
def test_bad_member_exits_2_with_one_line_and_writes_nothing(tmp_path: Path, capsys, monkeypatch, how) -> None:
    """An unreadable map in the middle of the sequence: exit 2, one line naming that file, no frame,
    GIF or temporary file written, and no order choice or prefilter started."""
    maps = tmp_path / "maps"
    maps.mkdir()
    good = _write_maps(maps, 2)
    bad = maps / "t00b.hdr"  # sorts between the two good maps
    bad.write_bytes(b"#?RADIANCE\nnot a radiance file\n")
    calls = _count_order_choices(monkeypatch)
    out = tmp_path / "out"
    out.mkdir()
    monkeypatch.chdir(out)
    members = [str(maps)] if how == "folder" else [str(good[0]), str(bad), str(good[1])]
    rc = main(["render", *COMMON, "--env", *members, "-o", "s.png", "--exr", "s.exr"])
    assert rc == 2
    err = capsys.readouterr().err
    assert err.startswith("shrm render: error:") and err.count("\n") == 1 and "t00b.hdr" in err
    assert list(out.iterdir()) == []
    assert calls[0] == 0


def test_sequence_refuses_one_map_options(tmp_path: Path, capsys, monkeypatch) -> None:
    """--turntable, --light-turntable and --error-image apply to one map: refused with a sequence."""
    monkeypatch.chdir(tmp_path)
    for extra in (["--turntable", "2"], ["--light-turntable", "2"], ["--error-image", "e.png"]):
        rc = main(["render", *COMMON, "--env", *MAPS, *extra, "-o", "s.png"])
        assert rc == 2
        err = capsys.readouterr().err
        assert "one frame per map" in err and err.count("\n") == 1
    assert list(tmp_path.iterdir()) == []
