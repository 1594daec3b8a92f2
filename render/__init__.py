"""Mesh rendering of measured BRDFs under environment maps: SHRM and comparison render modes.

Modules: ``mesh`` (loading, built-ins), ``camera`` (z-up frame = VTK world frame, rays),
``modes`` (the render-mode table: how each mode builds its model and shades it),
``glsl`` (the shared shader prelude), ``shader`` (SHRM modes), ``gaussian_shader``
(Gaussian lobes), ``offscreen`` (EGL/OSMesa context, float framebuffer), ``vtk_renderer``
(:class:`SHRMRenderer`), ``pipeline`` (:func:`render_frames`), ``api`` (:func:`render_scene`,
what ``shrm render`` calls; :func:`render_sequence`, one frame per environment),
``cpu_reference`` (numpy reference renderer), ``output``
(EXR/PNG/GIF, tone mapping), ``preview`` and ``strip`` (report images).
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
    "render_scene": "shrmkit.render.api",
    "SceneRender": "shrmkit.render.api",
    "render_sequence": "shrmkit.render.api",
    "SequenceRender": "shrmkit.render.api",
    "RenderOptions": "shrmkit.render.modes",
    "RenderMode": "shrmkit.render.modes",
    "RENDER_MODES": "shrmkit.render.modes",
    "get_mode": "shrmkit.render.modes",
    "mode_names": "shrmkit.render.modes",
    "OffscreenError": "shrmkit.render.offscreen",
    "probe_offscreen": "shrmkit.render.offscreen",
}

__all__ = list(_LAZY)


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'shrmkit.render' has no attribute {name!r}")
