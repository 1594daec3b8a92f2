"""Writes that fail (a full disk, a writer library's error) leave no partial set of outputs and
name the file in one line (issue 30 item 4); atomic writes keep no process-wide state, so
threads may write at once (issue 28)."""

from __future__ import annotations

import os
import stat
import threading

import OpenEXR
import pytest

from shrmkit.brdf_io.atomic import atomic_path, atomic_paths
from shrmkit.brdf_io.errors import BadInputError

RENDER = ["render", "builtin:sphere", "--env", "builtin:sky,height=16", "--brdf", "phong:s=8", "--size", "16",
          "--fps-frames", "0"]


def _full_disk_exr(monkeypatch) -> None:
    """OpenEXR's own message on ENOSPC (measured on a 64 KiB tmpfs): a RuntimeError naming its temp file."""
    def write(self, path):
        raise RuntimeError(f'Failed to write pixel data to image file "{path}". No space left on device.')

    monkeypatch.setattr(OpenEXR.File, "write", write)


def test_render_png_and_exr_appear_together_or_not_at_all(tmp_path, monkeypatch, run_main):
    _full_disk_exr(monkeypatch)
    png, exr = tmp_path / "a.png", tmp_path / "a.exr"
    code, err = run_main(*RENDER, "-o", str(png), "--exr", str(exr))
    assert code == 2
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1 and str(exr) in lines[0] and "No space left on device" in lines[0], err
    assert "Traceback" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == []  # neither output, no temporary file


def test_turntable_outputs_appear_together_or_not_at_all(tmp_path, monkeypatch, run_main):
    _full_disk_exr(monkeypatch)
    code, err = run_main(*RENDER, "-o", str(tmp_path / "t.png"), "--exr", str(tmp_path / "t.exr"),
                         "--turntable", "3")
    assert code == 2 and "No space left on device" in err and "t_0000.exr" in err
    assert list(tmp_path.iterdir()) == []


def test_failed_os_write_names_the_target_and_leaves_it_unchanged(tmp_path):
    target = tmp_path / "keep.txt"
    target.write_text("old")
    with pytest.raises(BadInputError, match="cannot write .No space left on device.; nothing was written") as raised:
        with atomic_path(target) as tmp:
            tmp.write_text("half")
            raise OSError(28, "No space left on device")
    assert str(target) in str(raised.value)
    assert target.read_text() == "old" and sorted(p.name for p in tmp_path.iterdir()) == ["keep.txt"]


def test_atomic_writes_from_many_threads_get_the_umask_mode(tmp_path):
    """Sixteen threads write at once while another thread changes nothing: every file is complete and
    has mode 0o666 less the umask (the kernel applies it; no thread reads or sets the umask)."""
    umask = os.umask(0o022)
    os.umask(umask)
    errors: list[BaseException] = []

    def write(k: int) -> None:
        try:
            for j in range(20):
                with atomic_paths([tmp_path / f"f{k}_{j}.bin", tmp_path / f"g{k}_{j}.bin"]) as (a, b):
                    a.write_bytes(bytes([k]) * 1000)
                    b.write_bytes(bytes([j]) * 10)
        except BaseException as err:  # noqa: BLE001 - reported below
            errors.append(err)

    threads = [threading.Thread(target=write, args=(k,)) for k in range(16)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors
    files = sorted(tmp_path.iterdir())
    assert len(files) == 16 * 20 * 2 and not [p for p in files if p.name.startswith(".")]
    for p in files:
        assert stat.S_IMODE(p.stat().st_mode) == 0o666 & ~umask
        k = int(p.name[1:].split("_")[0])
        assert p.read_bytes() == (bytes([k]) * 1000 if p.name[0] == "f" else bytes([int(p.stem.split("_")[1])]) * 10)


def test_writer_error_other_than_space_is_one_line_too(tmp_path):
    with pytest.raises(BadInputError, match="cannot write") as raised:
        with atomic_paths([tmp_path / "x.exr"]) as (tmp,):
            raise RuntimeError(f'Cannot open image file "{tmp}". Permission denied.')
    assert str(raised.value).count(str(tmp_path / "x.exr")) == 2 and ".x.exr." not in str(raised.value)
    assert list(tmp_path.iterdir()) == []
