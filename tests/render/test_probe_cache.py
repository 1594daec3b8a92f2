"""The offscreen probe's cache: successes remembered per graphics set-up, failures never."""

import subprocess

import pytest

from shrmkit.render import offscreen


class _Runs:
    def __init__(self, returncode: int, stdout: str = "", stderr: str = ""):
        self.calls = 0
        self.result = subprocess.CompletedProcess([], returncode, stdout, stderr)

    def __call__(self, *args, **kwargs):
        self.calls += 1
        return self.result


@pytest.fixture
def cache_dir(tmp_path, monkeypatch):
    monkeypatch.setenv("SHRMKIT_CACHE_DIR", str(tmp_path))
    monkeypatch.delenv("SHRMKIT_PROBE_CACHE", raising=False)
    return tmp_path


def test_a_success_is_answered_from_the_cache_until_the_set_up_changes(cache_dir, monkeypatch):
    runs = _Runs(0, "vtkOSOpenGLRenderWindow\n")
    monkeypatch.setattr(offscreen.subprocess, "run", runs)
    assert offscreen.probe_offscreen() == (True, "vtkOSOpenGLRenderWindow")
    assert offscreen.probe_offscreen() == (True, "vtkOSOpenGLRenderWindow")
    assert runs.calls == 1 and (cache_dir / offscreen.PROBE_CACHE_FILE).is_file()
    # another EGL vendor set-up, window override or display is another key: probed again
    monkeypatch.setenv("__EGL_VENDOR_LIBRARY_DIRS", str(cache_dir / "none"))
    offscreen.probe_offscreen()
    monkeypatch.setenv("VTK_DEFAULT_OPENGL_WINDOW", "vtkOSOpenGLRenderWindow")
    offscreen.probe_offscreen()
    assert runs.calls == 3
    offscreen.probe_offscreen(cache=False)
    monkeypatch.setenv("SHRMKIT_PROBE_CACHE", "0")
    offscreen.probe_offscreen()
    assert runs.calls == 5


def test_a_failure_is_never_remembered(cache_dir, monkeypatch):
    runs = _Runs(1, "", "Segmentation fault\n")
    monkeypatch.setattr(offscreen.subprocess, "run", runs)
    assert offscreen.probe_offscreen() == (False, "Segmentation fault")
    assert offscreen.probe_offscreen()[0] is False
    assert runs.calls == 2
    assert not (cache_dir / offscreen.PROBE_CACHE_FILE).exists()


def test_a_corrupt_or_unwritable_cache_only_costs_a_probe(cache_dir, monkeypatch):
    (cache_dir / offscreen.PROBE_CACHE_FILE).write_text("{not json", encoding="utf-8")
    runs = _Runs(0, "vtkEGLRenderWindow\n")
    monkeypatch.setattr(offscreen.subprocess, "run", runs)
    assert offscreen.probe_offscreen() == (True, "vtkEGLRenderWindow")
    monkeypatch.setenv("SHRMKIT_CACHE_DIR", str(cache_dir / "file" / "below"))
    (cache_dir / "file").write_text("", encoding="utf-8")  # a file where the folder should be
    assert offscreen.probe_offscreen() == (True, "vtkEGLRenderWindow")
    assert runs.calls == 2
