"""Mesh rendering with the global SHRM through a pyvista/VTK GLSL shader (DESIGN §5).

Modules: ``mesh`` (loading, built-ins), ``camera`` (z-up frame = VTK world frame, rays),
``shader`` (GLSL replacements), ``offscreen`` (EGL/OSMesa context, float framebuffer),
``vtk_renderer`` (:class:`SHRMRenderer`), ``cpu_reference`` (numpy reference renderer),
``output`` (EXR/PNG/GIF, tone mapping), ``pipeline`` (:func:`render_frames` for the CLI).
Names are imported on first use so that importing the package does not load VTK.
"""

from __future__ import annotations

import importlib
from typing import Any

_LAZY = {
    "Mesh": "shrmkit.render.mesh",
    "load_mesh": "shrmkit.render.mesh",
    "Camera": "shrmkit.render.camera",
    "SHRMRenderer": "shrmkit.render.vtk_renderer",
    "RenderResult": "shrmkit.render.vtk_renderer",
    "render_frames": "shrmkit.render.pipeline",
    "OffscreenError": "shrmkit.render.offscreen",
    "probe_offscreen": "shrmkit.render.offscreen",
}

__all__ = list(_LAZY)


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'shrmkit.render' has no attribute {name!r}")
