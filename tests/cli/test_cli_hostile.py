"""Hostile inputs through the command line: one line on stderr naming the file, exit 2,
no partial output, and no waiting on special files (DEVELOPERS.md "Real users bring
files from other tools"; issue: real-world files and a fuzz harness)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from shrmkit.brdf_io.hdr_codecs import write_exr, write_hdr


def run_cli(*args: str, timeout: float = 120.0) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "shrmkit.cli.main", *args], capture_output=True, text=True, timeout=timeout
    )


def _assert_one_line(proc: subprocess.CompletedProcess, names: str) -> None:
    assert proc.returncode == 2, (proc.returncode, proc.stderr[-2000:])
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1, proc.stderr[-2000:]
    assert lines[0].startswith("shrm ") and names in lines[0], lines[0]
    assert "Traceback" not in proc.stderr


def _special_files(folder: Path, suffix: str) -> list[Path]:
    fifo = folder / f"fifo{suffix}"
    os.mkfifo(fifo)
    zero = folder / f"zero{suffix}"
    zero.symlink_to("/dev/zero")
    return [fifo, zero]


@pytest.mark.slow
@pytest.mark.parametrize("suffix", [".binary", ".npz", ".brdf", ".json"])
def test_special_brdf_files_are_refused_at_once(tmp_path, suffix):
    """A FIFO would block a reader forever and /dev/zero would read until memory runs out."""
    for path in _special_files(tmp_path, suffix):
        _assert_one_line(run_cli("orders", str(path), timeout=60.0), path.name)


@pytest.mark.slow
def test_hostile_environment_files_leave_no_output(tmp_path):
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
    for env in hostile:
        target = out / "m.shrm.npz"
        proc = run_cli("prefilter", "--env", str(env), "--brdf", "phong:s=8", "-o", str(target), timeout=60.0)
        _assert_one_line(proc, env.name)
        assert not list(out.iterdir()), list(out.iterdir())
    png = out / "r.png"
    proc = run_cli("render", "builtin:sphere", "--env", str(bomb), "--size", "32", "-o", str(png), timeout=60.0)
    _assert_one_line(proc, bomb.name)
    assert not list(out.iterdir())


@pytest.mark.slow
def test_hostile_mesh_and_shrm_files_leave_no_output(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    bad_shrm = tmp_path / "bad.shrm.npz"
    bad_shrm.write_bytes(b"PK\x03\x04" + bytes(60))
    for mesh in [*_special_files(tmp_path, ".ply"), tmp_path / "missing.obj"]:
        proc = run_cli("render", str(mesh), "--env", "builtin:sky,height=16", "--size", "32",
                       "-o", str(out / "r.png"), timeout=60.0)
        _assert_one_line(proc, mesh.name)
    proc = run_cli("compare", str(bad_shrm), timeout=60.0)
    assert proc.returncode == 2 and "Traceback" not in proc.stderr, proc.stderr[-2000:]
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
