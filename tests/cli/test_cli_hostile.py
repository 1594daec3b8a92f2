"""Hostile inputs through the command line: one line on stderr naming the file, exit 2,
no partial output, and no waiting on special files (DEVELOPERS.md "Real users bring
files from other tools"; issue: real-world files and a fuzz harness)."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from shrmkit.brdf_io.hdr_codecs import write_exr, write_hdr


def _assert_one_line(done: tuple[int, str], names: str) -> None:
    """(exit code, stderr) of one command: exit 2, one line starting "shrm " and naming ``names``."""
    code, stderr = done
    assert code == 2, (code, stderr[-2000:])
    lines = stderr.strip().splitlines()
    assert len(lines) == 1, stderr[-2000:]
    assert lines[0].startswith("shrm ") and names in lines[0], lines[0]
    assert "Traceback" not in stderr


def _special_files(folder: Path, suffix: str) -> list[Path]:
    fifo = folder / f"fifo{suffix}"
    os.mkfifo(fifo)
    zero = folder / f"zero{suffix}"
    zero.symlink_to("/dev/zero")
    return [fifo, zero]


# The commands of each test run one after the other in one fresh interpreter (the run_each fixture
# of tests/cli/conftest.py: main(argv) per command, each with its own stderr): a reader that blocks
# on a FIFO or reads /dev/zero until memory runs out fails the test by the time limit or the exit
# status, as a process per command did, for one interpreter start instead of 18.


@pytest.mark.slow
def test_special_brdf_files_are_refused_at_once(tmp_path, run_each):
    """A FIFO would block a reader forever and /dev/zero would read until memory runs out (.binary,
    .npz, .brdf and .json readers)."""
    paths = [path for suffix in (".binary", ".npz", ".brdf", ".json") for path in _special_files(tmp_path, suffix)]
    for path, done in zip(paths, run_each([["orders", str(path)] for path in paths], timeout=240.0), strict=True):
        _assert_one_line(done, path.name)


@pytest.mark.slow
def test_hostile_environment_files_leave_no_output(tmp_path, run_each):
    out = tmp_path / "out"
    out.mkdir()
    image = np.full((8, 16, 3), 0.5, np.float32)
    good_exr, good_hdr = tmp_path / "good.exr", tmp_path / "good.hdr"
    write_exr(good_exr, image)
    write_hdr(good_hdr, image)
    truncated = tmp_path / "truncated.exr"
    truncated.write_bytes(good_exr.read_bytes()[: good_exr.stat().st_size // 2])
    bomb = tmp_path / "bomb.hdr"  # a header declaring 32767 × 1024 pixels over a few bytes of data
    bomb.write_bytes(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 32767 +X 1024\n" + bytes((2, 2, 4, 0)) * 64)
    hostile = [truncated, bomb, *_special_files(tmp_path, ".exr")]
    # one output name per command: a partial output left by any of them is in out/ under its name
    cases = [["prefilter", "--env", str(env), "--brdf", "phong:s=8", "-o", str(out / f"m{k}.shrm.npz")]
             for k, env in enumerate(hostile)]
    cases.append(["render", "builtin:sphere", "--env", str(bomb), "--size", "32", "-o", str(out / "r.png")])
    for name, done in zip([env.name for env in hostile] + [bomb.name], run_each(cases, timeout=240.0), strict=True):
        _assert_one_line(done, name)
    assert not list(out.iterdir())


@pytest.mark.slow
def test_hostile_mesh_and_shrm_files_leave_no_output(tmp_path, run_each):
    out = tmp_path / "out"
    out.mkdir()
    bad_shrm = tmp_path / "bad.shrm.npz"
    bad_shrm.write_bytes(b"PK\x03\x04" + bytes(60))
    meshes = [*_special_files(tmp_path, ".ply"), tmp_path / "missing.obj"]
    cases = [["render", str(mesh), "--env", "builtin:sky,height=16", "--size", "32", "-o", str(out / f"r{k}.png")]
             for k, mesh in enumerate(meshes)]
    *rendered, (code, stderr) = run_each([*cases, ["compare", str(bad_shrm)]], timeout=240.0)
    for mesh, done in zip(meshes, rendered, strict=True):
        _assert_one_line(done, mesh.name)
    assert code == 2 and "Traceback" not in stderr, stderr[-2000:]
    assert not list(out.iterdir())


def test_prefilter_size_is_planned_before_the_map_is_made(tmp_path, monkeypatch, capsys):
    """The memory plan of an option: `shrm prefilter --size 2048` plans 40 B × 2 · 2048² = 320 MiB; under
    SHRM_MAX_MEMORY_BYTES = 256 MiB it is one line naming the option and the estimate, exit 2, no
    output (before: the map was made, 33 B a pixel measured: 2.4 GB and 55 s at 6000 rows)."""
    from shrmkit.cli.main import main

    monkeypatch.setenv("SHRM_MAX_MEMORY_BYTES", str(256 * 2**20))
    out = tmp_path / "m.shrm.npz"
    code = main(["prefilter", "--env", "builtin:constant,height=16", "--brdf", "phong:s=8", "--size", "2048",
                 "--output", str(out)])
    err = capsys.readouterr().err.strip()
    assert code == 2 and not out.exists()
    assert err.count("\n") == 0 and "--size 2048: an SHRM map of 2048 x 4096 needs an estimated 320 MiB" in err, err


def test_render_size_is_planned_before_rendering(tmp_path, monkeypatch, capsys):
    """`shrm render --size S` plans 256 B a pixel (190-260 measured at 1024-2048 px; the range's 8192 px
    would take ~13 GB): under SHRM_MAX_MEMORY_BYTES = 64 MiB, --size 600 (87.9 MiB) is one line naming the
    option, exit 2, no image (before: rendered)."""
    from shrmkit.cli.main import main

    monkeypatch.setenv("SHRM_MAX_MEMORY_BYTES", str(64 * 2**20))
    out = tmp_path / "r.png"
    code = main(["render", "builtin:sphere", "--env", "builtin:constant,height=16", "--brdf", "phong:s=8",
                 "--size", "600", "-o", str(out)])
    err = capsys.readouterr().err.strip()
    assert code == 2 and not out.exists()
    assert err.count("\n") == 0 and "--size 600: a 600 x 600 render needs an estimated 87.9 MiB" in err, err
