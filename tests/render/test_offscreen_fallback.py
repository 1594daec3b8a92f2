"""`shrm render` where a back end would crash (issue 28 item 1): libEGL without a vendor library
(``__EGL_VENDOR_LIBRARY_DIRS`` pointing nowhere, as on many containers and CI runners) and a forced
X window class without a display both died with a segmentation fault (exit 139) although OSMesa
works. Now the classes a safe query shows would crash are skipped, and named on the renderer line:
exit 0 with an image, or exit 2 with one line — never a signal."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from shrmkit.render.offscreen import egl_vendor_available, skipped_window_classes, window_classes

pytestmark = pytest.mark.render

CASES = {
    "egl without vendor": {"__EGL_VENDOR_LIBRARY_DIRS": "/nonexistent"},
    "forced x window, no display": {"VTK_DEFAULT_OPENGL_WINDOW": "vtkXOpenGLRenderWindow"},
}


def _env(extra: dict[str, str]) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY", "VTK_DEFAULT_OPENGL_WINDOW",
                                                         "__EGL_VENDOR_LIBRARY_DIRS", "__EGL_VENDOR_LIBRARY_FILENAMES")}
    return {**env, **extra}


@pytest.mark.parametrize("case", list(CASES))
def test_render_never_dies_of_a_signal(tmp_path, case):
    out = tmp_path / "r.png"
    proc = subprocess.run(
        [sys.executable, "-m", "shrmkit.cli.main", "render", "builtin:sphere", "--env", "builtin:sky,height=16",
         "--brdf", "phong:s=20", "--size", "32", "--fps-frames", "0", "-o", str(out)],
        env=_env(CASES[case]), capture_output=True, text=True, timeout=300,
    )
    assert proc.returncode in (0, 2), (proc.returncode, proc.stderr[-2000:])
    if proc.returncode == 0:
        assert out.stat().st_size > 0
        line = next(x for x in proc.stdout.splitlines() if x.startswith("renderer: "))
        skipped = "vtkEGLRenderWindow skipped" if case.startswith("egl") else "vtkXOpenGLRenderWindow skipped"
        assert skipped in line, line
    else:
        assert len(proc.stderr.strip().splitlines()) == 1 and not out.exists(), proc.stderr


def test_safe_queries(monkeypatch, tmp_path):
    """The queries themselves: glvnd's vendor folders and the display variables."""
    for var in ("DISPLAY", "WAYLAND_DISPLAY", "VTK_DEFAULT_OPENGL_WINDOW", "__EGL_VENDOR_LIBRARY_FILENAMES"):
        monkeypatch.delenv(var, raising=False)
    monkeypatch.setenv("__EGL_VENDOR_LIBRARY_DIRS", str(tmp_path))
    assert not egl_vendor_available() and window_classes() == ["vtkOSOpenGLRenderWindow"]
    (tmp_path / "50_mesa.json").write_text("{}")
    assert egl_vendor_available() and window_classes() == ["vtkEGLRenderWindow", "vtkOSOpenGLRenderWindow"]
    monkeypatch.setenv("VTK_DEFAULT_OPENGL_WINDOW", "vtkXOpenGLRenderWindow")
    assert window_classes() == ["vtkEGLRenderWindow", "vtkOSOpenGLRenderWindow"]
    assert dict(skipped_window_classes()) == {"vtkXOpenGLRenderWindow": "needs an X display and DISPLAY is not set"}
    monkeypatch.setenv("DISPLAY", ":0")
    assert window_classes() == ["vtkXOpenGLRenderWindow"]
