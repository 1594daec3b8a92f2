"""Notebook display (``_repr_html_``, ``_repr_png_``) of what :func:`~shrmkit.render.api.render_scene`
and :func:`~shrmkit.render.api.render_sequence` return.

A frame's picture: its linear composite radiance (``Frame.linear``), every k-th pixel so that it is
at most :data:`THUMBNAIL_PIXELS` wide, the mean luminance brought to middle grey
(``brdf_io.display.middle_grey_exposure``; ``shrm render --exposure`` is the files' own choice),
filmic tone curve, sRGB. The card: mode, size, mesh, the model's description lines (orders,
stated error, window, lights, prefilter time), the renderer and the timings.

Public objects: :func:`frame_image`, :func:`scene_render_png`, :func:`scene_render_html`,
:func:`sequence_render_html`, :data:`THUMBNAIL_PIXELS`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..brdf_io.display import encode_png, middle_grey_exposure, to_8bit
from ..brdf_io.notebook import card, png_img

__all__ = ["frame_image", "scene_render_png", "scene_render_html", "sequence_render_html", "THUMBNAIL_PIXELS"]

#: Largest width of a frame's thumbnail, pixels.
THUMBNAIL_PIXELS = 256


def frame_image(frame: Any, pixels: int = THUMBNAIL_PIXELS) -> np.ndarray:
    """uint8 (h, w, 3|4) thumbnail of a ``pipeline.Frame`` (RGBA when its background is transparent)."""
    step = max(1, -(-frame.linear.shape[1] // pixels))
    linear = frame.linear[::step, ::step]
    alpha = frame.alpha[::step, ::step]
    exposure = middle_grey_exposure(linear, alpha if frame.transparent else None)
    return to_8bit(linear, alpha if frame.transparent else None, exposure=exposure, curve="filmic")


def scene_render_png(result: Any) -> bytes:
    """The first frame of a :class:`~shrmkit.render.api.SceneRender` as a PNG thumbnail."""
    return encode_png(frame_image(result.frames[0]))


def _timing_rows(timings: Any) -> list[tuple[str, Any]]:
    rows: list[tuple[str, Any]] = [("renderer", timings.backend), ("first frame", f"{timings.first_frame_s:.3f} s")]
    if timings.fps_frames:
        rows.append(("frames per second", f"{timings.fps:.1f} (over {timings.fps_frames} frames)"))
    return rows


def scene_render_html(result: Any) -> str:
    """The card of a :class:`~shrmkit.render.api.SceneRender`: the first frame, mode, size, mesh,
    what was built (``built.description``) and the timings."""
    rows: list[tuple[str, Any]] = [
        ("mode", result.mode),
        ("size", f"{result.size} × {result.size}, {len(result.frames)} frame(s)"),
        ("mesh", f"{result.mesh.name}: {result.mesh.n_triangles} triangles"),
    ]
    rows += [("model" if k == 0 else "", line) for k, line in enumerate(result.built.description)]
    rows += _timing_rows(result.timings)
    image = png_img(scene_render_png(result), "first frame (auto exposure)",
                    width=min(THUMBNAIL_PIXELS, result.size))
    return card(f"SceneRender ({result.mode})", rows, image=image)


def sequence_render_html(seq: Any) -> str:
    """The card of a :class:`~shrmkit.render.api.SequenceRender`: the frames side by side (at most
    eight), the shared orders and each map's build-and-render seconds."""
    rows: list[tuple[str, Any]] = [("frames", len(seq.renders)), ("mode", seq.renders[0].mode)]
    if seq.orders is not None:
        rows.append(("orders", f"F={seq.orders.F} P={seq.orders.P}, chosen once in {seq.orders_seconds:.3f} s"))
    rows += [(name, f"{seconds:.3f} s") for name, seconds in zip(seq.environments, seq.frame_seconds, strict=True)]
    pictures = "".join(png_img(encode_png(frame_image(r.frames[0], THUMBNAIL_PIXELS // 2)), name)
                       for r, name in list(zip(seq.renders, seq.environments, strict=True))[:8])
    return card("SequenceRender", rows, extra=f"<div style='display:flex;gap:4px'>{pictures}</div>")
