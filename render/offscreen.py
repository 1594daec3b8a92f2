"""Offscreen OpenGL contexts for VTK (EGL or OSMesa, Mesa llvmpipe or a GPU) with a float framebuffer.

The VTK ≥ 9.4 wheels load their OpenGL back end at run time. On a machine without a display
we create the window class directly instead of going through the object factory (which tries
X first and prints a warning): ``vtkEGLRenderWindow`` first (Mesa's EGL gives llvmpipe on a
CPU-only machine, the vendor's EGL uses the GPU), then ``vtkOSOpenGLRenderWindow`` (OSMesa).
The environment variable ``VTK_DEFAULT_OPENGL_WINDOW`` (a VTK convention) overrides the
choice; with a ``DISPLAY`` set and no override, the factory default is used. Without a display
an override is tried first and EGL, OSMesa follow it. A class that a safe query shows would
crash VTK (a segmentation fault, not an error) is skipped and named (:func:`skipped_window_classes`,
printed on ``shrm render``'s renderer line): EGL when glvnd finds no vendor library, an X window
when ``DISPLAY`` is not set.

Float readback: VTK's render and display framebuffers are 8-bit RGBA by default. After the
first render we re-populate both with 32-bit float colour attachments (``GL_RGBA32F``), so
:func:`read_rgba_float` returns the fragment shader's linear output bit for bit. The format
is checked after every readback set-up; anything else raises :class:`OffscreenError`.

The probe (:func:`probe_offscreen`, a subprocess that makes one 8 × 8 float context: ~0.6 s
CPU) remembers its successes in ``offscreen_probe.json`` under ``$SHRMKIT_CACHE_DIR`` (default
``$XDG_CACHE_HOME/shrmkit``, else ``~/.cache/shrmkit``), keyed by everything that decides which
context works: the Python and VTK installs, the graphics environment variables (``DISPLAY``,
``VTK_*``, ``__EGL_*``, ``LIBGL_*``, ``MESA_*``, ``LD_LIBRARY_PATH``…), glvnd's vendor files and
the boot. Failures are never remembered, and ``SHRMKIT_PROBE_CACHE=0`` turns the cache off
(``data_specs/render_outputs.md``).

Debian packages needed (see ``.ci/apt-packages.txt``): libegl1, libegl-mesa0, libgl1,
libgl1-mesa-dri, libglx-mesa0 (and libosmesa6 for the OSMesa fallback).
"""

from __future__ import annotations

import hashlib
import importlib.util
import json
import os
import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from ..brdf_io.errors import ShrmError

__all__ = [
    "OffscreenError", "make_render_window", "read_rgba_float", "probe_offscreen", "window_classes", "gl_renderer",
    "is_software_rasterizer", "SOFTWARE_RASTERIZERS", "skipped_window_classes", "egl_vendor_available",
    "probe_key", "probe_cache_dir", "PROBE_CACHE_FILE",
]

#: Substrings of ``GL_RENDERER`` that name a rasterizer running on the CPU (Mesa's llvmpipe,
#: softpipe and swrast, Google's SwiftShader, Microsoft's WARP/GDI).
SOFTWARE_RASTERIZERS = ("llvmpipe", "softpipe", "swrast", "swiftshader", "software rasterizer", "gdi generic")

#: GL_RGBA32F, the internal format of a float32 RGBA colour attachment.
GL_RGBA32F = 0x8814
#: vtkType.h VTK_FLOAT
VTK_FLOAT = 10


class OffscreenError(ShrmError, RuntimeError):
    """No offscreen OpenGL context with float colour buffers could be created."""


#: Window classes that need an X display (VTK crashes, exit 139, when one is made without it).
X_WINDOW_CLASSES = ("vtkXOpenGLRenderWindow",)
#: glvnd's default folders of EGL vendor files (``__EGL_VENDOR_LIBRARY_DIRS`` replaces them).
EGL_VENDOR_DIRS = ("/etc/glvnd/egl_vendor.d", "/usr/share/glvnd/egl_vendor.d")


def egl_vendor_available() -> bool:
    """Whether glvnd can find an EGL vendor library: a file of ``__EGL_VENDOR_LIBRARY_FILENAMES``,
    or a ``*.json`` in ``__EGL_VENDOR_LIBRARY_DIRS`` (default :data:`EGL_VENDOR_DIRS`). Without one
    ``vtkEGLRenderWindow`` dies in its first render with a segmentation fault (many containers and
    CI runners have libEGL but no vendor file; pyvista #1278, #2142), so it is not tried."""
    files = os.environ.get("__EGL_VENDOR_LIBRARY_FILENAMES")
    if files:
        return any(os.path.isfile(f) for f in files.split(":") if f)
    dirs = os.environ.get("__EGL_VENDOR_LIBRARY_DIRS")
    for folder in (dirs.split(":") if dirs else EGL_VENDOR_DIRS):
        try:
            if any(name.endswith(".json") for name in os.listdir(folder)):
                return True
        except OSError:
            continue
    return False


def window_classes() -> list[str]:
    """Names of the VTK render-window classes to try, in order (see module docstring), without
    those a safe query shows would crash: :func:`skipped_window_classes` says which and why."""
    skipped = dict(skipped_window_classes())
    return [name for name in _candidates() if name not in skipped]


def skipped_window_classes() -> list[tuple[str, str]]:
    """(class, reason) of the candidates left out: an X window without ``DISPLAY``, EGL without a
    vendor library (:func:`egl_vendor_available`)."""
    has_display = bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))
    out = []
    for name in _candidates():
        if name in X_WINDOW_CLASSES and not has_display:
            out.append((name, "needs an X display and DISPLAY is not set"))
        elif name == "vtkEGLRenderWindow" and not egl_vendor_available():
            out.append((name, "no EGL vendor library (glvnd egl_vendor.d holds no .json)"))
    return out


def _candidates() -> list[str]:
    override = os.environ.get("VTK_DEFAULT_OPENGL_WINDOW")
    if os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"):
        return [override or "vtkRenderWindow"]
    # an override is tried first; without a display the offscreen classes follow it as fallbacks
    names = ([override] if override else []) + ["vtkEGLRenderWindow", "vtkOSOpenGLRenderWindow"]
    return list(dict.fromkeys(names))


def _new_window(name: str):  # -> vtkRenderWindow
    import vtkmodules.vtkRenderingCore as core  # lazy: VTK is loaded only when rendering
    import vtkmodules.vtkRenderingOpenGL2 as gl2  # lazy; registers the OpenGL factory overrides

    if name == "vtkRenderWindow":
        return core.vtkRenderWindow()
    cls = getattr(gl2, name, None)
    if cls is None:
        raise OffscreenError(f"this VTK build has no {name}")
    return cls()


def make_render_window(width: int, height: int):  # -> vtkRenderWindow
    """An offscreen VTK render window of ``width`` × ``height`` pixels with float32 colour buffers.

    Multisampling is off (one sample at each pixel centre), so the image is a point sampling
    of the shaded surface. The window holds one vtkRenderer
    (``window.GetRenderers().GetFirstRenderer()``). Raises :class:`OffscreenError` when no
    back end works.
    """
    import vtkmodules.vtkRenderingCore as core  # lazy: VTK is loaded only when rendering

    if width < 1 or height < 1:
        raise ValueError(f"image size must be positive, got {width}x{height}")
    problems = []
    for name in window_classes():
        try:
            window = _new_window(name)
        except OffscreenError as err:
            problems.append(str(err))
            continue
        window.SetOffScreenRendering(1)
        window.SetMultiSamples(0)
        window.SetAlphaBitPlanes(1)
        window.SetSize(int(width), int(height))
        # the window creates its framebuffers on the first render that has a renderer
        window.AddRenderer(core.vtkRenderer())
        window.Render()  # creates the context and the default (8-bit) framebuffers
        if not window.SupportsOpenGL():
            problems.append(f"{name}: no OpenGL 3.2 context")
            window.Finalize()
            continue
        for fbo in (window.GetRenderFramebuffer(), window.GetDisplayFramebuffer()):
            if fbo is None:
                break
            fbo.Bind()
            # (width, height, use textures, 1 colour attachment, float data, depth, 32-bit
            # depth, no multisampling, no stencil)
            fbo.PopulateFramebuffer(int(width), int(height), True, 1, VTK_FLOAT, True, 32, 0, False)
        window.Render()
        read_rgba_float(window)  # binds the display framebuffer for reading
        fmt = window.GetColorBufferInternalFormat(0)
        if fmt != GL_RGBA32F:
            problems.append(f"{name}: colour buffer format 0x{fmt:x} is not GL_RGBA32F")
            window.Finalize()
            continue
        return window
    problems += [f"{name} skipped: {why}" for name, why in skipped_window_classes()]
    raise OffscreenError("no offscreen OpenGL context: " + "; ".join(problems))


def gl_renderer(window) -> str:
    """The ``GL_RENDERER`` string of an initialized VTK render window (``""`` when VTK does not
    report it), e.g. ``"llvmpipe (LLVM 15.0.6, 256 bits)"``."""
    for line in (window.ReportCapabilities() or "").splitlines():
        key, _, value = line.partition(":")
        if key.strip().lower() == "opengl renderer string":
            return value.strip()
    return ""


def is_software_rasterizer(window) -> bool:
    """Whether the window's OpenGL runs on the CPU (:data:`SOFTWARE_RASTERIZERS`)."""
    name = gl_renderer(window).lower()
    return any(s in name for s in SOFTWARE_RASTERIZERS)


def read_rgba_float(window) -> np.ndarray:
    """The window's colour buffer as float32 (H, W, 4), row 0 at the top of the image."""
    from vtkmodules.util.numpy_support import vtk_to_numpy  # lazy: VTK is loaded only when rendering
    from vtkmodules.vtkCommonCore import vtkFloatArray  # lazy: VTK

    width, height = window.GetSize()
    arr = vtkFloatArray()
    window.GetRGBAPixelData(0, 0, width - 1, height - 1, 0, arr, 0)
    # OpenGL rows run bottom to top; flip so that row 0 is the top of the image
    return vtk_to_numpy(arr).reshape(height, width, 4)[::-1].copy()


_PROBE = """
import numpy as np
from shrmkit.render.offscreen import make_render_window, read_rgba_float
w = make_render_window(8, 8)
img = read_rgba_float(w)
assert img.shape == (8, 8, 4)
print(w.GetClassName())
"""


#: Environment variables that decide which offscreen context works (the probe cache's key).
_GRAPHICS_ENV = re.compile(
    r"^(DISPLAY|WAYLAND_DISPLAY|LD_LIBRARY_PATH|LD_PRELOAD|CUDA_VISIBLE_DEVICES|VTK_\w*|__EGL_\w*|__GLX_\w*"
    r"|EGL_\w*|LIBGL_\w*|MESA_\w*|GALLIUM_\w*|NVIDIA_\w*)$"
)
PROBE_CACHE_FILE = "offscreen_probe.json"


def probe_cache_dir() -> Path:
    """Folder of the probe cache: ``$SHRMKIT_CACHE_DIR``, else ``$XDG_CACHE_HOME/shrmkit``, else
    ``~/.cache/shrmkit``."""
    if os.environ.get("SHRMKIT_CACHE_DIR"):
        return Path(os.environ["SHRMKIT_CACHE_DIR"])
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "shrmkit"


def _stat_token(path: str) -> str:
    try:
        st = os.stat(path)
    except OSError:
        return f"{path}:-"
    return f"{path}:{st.st_mtime_ns}:{st.st_size}"


def probe_key() -> str:
    """What decides whether an offscreen context works here, hashed (the probe cache's key)."""
    spec = importlib.util.find_spec("vtkmodules")
    vtk_origin = str(spec.origin) if spec is not None and spec.origin else "-"
    parts = [sys.executable, sys.version, _stat_token(vtk_origin), _stat_token(__file__)]
    parts += [f"{k}={v}" for k, v in sorted(os.environ.items()) if _GRAPHICS_ENV.match(k)]
    dirs = os.environ.get("__EGL_VENDOR_LIBRARY_DIRS")
    for folder in (dirs.split(":") if dirs else EGL_VENDOR_DIRS):
        parts.append(_stat_token(folder))
        try:
            parts += [_stat_token(os.path.join(folder, n)) for n in sorted(os.listdir(folder))]
        except OSError:
            pass
    try:
        parts.append(Path("/proc/sys/kernel/random/boot_id").read_text().strip())
    except OSError:
        pass
    return hashlib.sha256("\n".join(parts).encode("utf-8", "surrogateescape")).hexdigest()


def _cache_enabled() -> bool:
    return os.environ.get("SHRMKIT_PROBE_CACHE", "1").strip().lower() not in ("0", "no", "off", "false")


def _read_cache(path: Path) -> dict:
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    return data if isinstance(data, dict) else {}


def _remember(key: str, message: str) -> None:
    """Add a success to the cache (best effort: a cache that cannot be written is skipped)."""
    path = probe_cache_dir() / PROBE_CACHE_FILE
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        data = _read_cache(path)
        data = {k: v for k, v in data.items() if isinstance(v, dict)}
        data[key] = {"ok": True, "message": message, "time": time.time()}
        if len(data) > 64:  # keep the newest entries
            data = dict(sorted(data.items(), key=lambda kv: kv[1].get("time", 0.0))[-64:])
        tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
        tmp.write_text(json.dumps(data, indent=1), encoding="utf-8")
        os.replace(tmp, path)
    except OSError:
        pass


def probe_offscreen(timeout: float = 120.0, *, cache: bool = True) -> tuple[bool, str]:
    """Try to create an offscreen float context in a subprocess (a broken driver cannot crash us).

    A success is remembered (module docstring: the probe cache) and answered from the cache
    while nothing that decides it has changed; ``cache=False`` or ``SHRMKIT_PROBE_CACHE=0``
    always probes.

    Returns ``(ok, message)``: the window class used, or why it failed.
    """
    use_cache = cache and _cache_enabled()
    key = probe_key() if use_cache else ""
    if use_cache:
        hit = _read_cache(probe_cache_dir() / PROBE_CACHE_FILE).get(key)
        if isinstance(hit, dict) and hit.get("ok") is True and isinstance(hit.get("message"), str):
            return True, hit["message"]
    try:
        proc = subprocess.run(
            [sys.executable, "-c", _PROBE], capture_output=True, text=True, timeout=timeout, check=False
        )
    except (OSError, subprocess.TimeoutExpired) as err:
        return False, f"offscreen probe failed: {err}"
    if proc.returncode == 0:
        message = proc.stdout.strip().splitlines()[-1] if proc.stdout.strip() else "ok"
        if use_cache:
            _remember(key, message)
        return True, message
    lines = (proc.stderr or proc.stdout or "no output").strip().splitlines()
    return False, lines[-1] if lines else f"offscreen probe exited with {proc.returncode}"
