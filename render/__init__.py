"""Mesh rendering of measured BRDFs under environment maps: the SHRM shaders ([RH02] §6) and the
comparison render modes, offscreen through VTK (EGL or OSMesa), with a numpy reference renderer.
Imports :mod:`shrmkit.analysis` and :mod:`shrmkit.brdf_io`, never the CLI.

Public API — the names in ``__all__``, importable from ``shrmkit.render``:

- Rendering a scene: :func:`render_scene` (what ``shrm render`` calls) → :class:`SceneRender`;
  :func:`render_sequence` (one frame per environment) → :class:`SequenceRender`;
  :func:`render_frames` and :class:`Frame` (the frame loop under them);
  :class:`SHRMRenderer` and :class:`RenderResult` (the VTK renderer itself).
- Render modes, one table (``data_specs/render_outputs.md``): :data:`RENDER_MODES`,
  :class:`RenderMode`, :func:`get_mode`, :func:`mode_names` (``distant``, ``perpixel`` — the
  SHRM; ``rsibr`` [Cabral99]; ``kautz-mccool`` [KM00]; ``gaussian-lobes`` [Green07]) and
  :class:`RenderOptions`.
- Meshes and cameras: :class:`Mesh`, :func:`load_mesh`, :class:`Camera`, :func:`orbit_camera`,
  :func:`turntable_cameras`, :func:`light_turntable_rotations` (the lighting turned per frame).
- Images: :func:`write_comparison_strip` (the image strip of ``shrm compare``).
- The offscreen context: :func:`probe_offscreen`, :class:`OffscreenError`.

Modules not listed here are internal: their names may change without notice. Citation keys:
``data_specs/bibliography.md``. Names are imported on first use, so importing the package does
not load VTK.
"""

from __future__ import annotations

from ..brdf_io.lazy import lazy_exports as _lazy_exports

#: Public name → the module that defines it (imported on first use).
_LAZY = {
    "Mesh": "shrmkit.render.mesh",
    "load_mesh": "shrmkit.render.mesh",
    "Camera": "shrmkit.render.camera",
    "orbit_camera": "shrmkit.render.camera",
    "SHRMRenderer": "shrmkit.render.vtk_renderer",
    "RenderResult": "shrmkit.render.vtk_renderer",
    "render_frames": "shrmkit.render.pipeline",
    "Frame": "shrmkit.render.pipeline",
    "turntable_cameras": "shrmkit.render.pipeline",
    "light_turntable_rotations": "shrmkit.render.pipeline",
    "render_scene": "shrmkit.render.api",
    "SceneRender": "shrmkit.render.api",
    "render_sequence": "shrmkit.render.api",
    "SequenceRender": "shrmkit.render.api",
    "RenderOptions": "shrmkit.render.modes",
    "RenderMode": "shrmkit.render.modes",
    "RENDER_MODES": "shrmkit.render.modes",
    "get_mode": "shrmkit.render.modes",
    "mode_names": "shrmkit.render.modes",
    "write_comparison_strip": "shrmkit.render.strip",
    "OffscreenError": "shrmkit.render.offscreen",
    "probe_offscreen": "shrmkit.render.offscreen",
}

__all__ = list(_LAZY)


__getattr__, __dir__ = _lazy_exports(__name__, _LAZY, __all__)
