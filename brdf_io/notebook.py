"""Notebook display (IPython/Jupyter ``_repr_html_`` and ``_repr_png_``) of the toolkit's objects.

The shared pieces — an HTML card (a picture beside a table of key numbers), an HTML table, a
PNG as a base64 ``data:`` URI — and the pictures and cards of this layer's objects:
:class:`~shrmkit.brdf_io.envmap.EnvironmentMap` (a tone-mapped lat-long thumbnail, size,
orientation, dynamic range) and :class:`~shrmkit.brdf_io.brdf.BRDF` (a lit sphere, name, kind).
The layers above build their cards (order choices, SHRMs, renders, reports) from the same
pieces. Only numpy and the standard library are used (PNGs by :func:`~shrmkit.brdf_io.display.encode_png`),
so that a thumbnail imports nothing heavy; each picture here costs well under 0.2 s.

Public objects: :func:`card`, :func:`html_table`, :func:`png_img`, :func:`number`,
:func:`env_thumbnail`, :func:`env_png`, :func:`env_html`, :func:`env_orientation`,
:func:`lit_sphere_radiance`, :func:`lit_sphere_image`, :func:`brdf_png`, :func:`brdf_html`,
:data:`THUMBNAIL_ROWS`, :data:`SPHERE_PIXELS`, :data:`SPHERE_LIGHT`.
"""

from __future__ import annotations

import base64
import html
import math
import re
from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np

from .colour import REC709_LUMA
from .display import encode_png, middle_grey_exposure, to_8bit

__all__ = [
    "card",
    "html_table",
    "png_img",
    "number",
    "env_thumbnail",
    "env_png",
    "env_html",
    "env_orientation",
    "lit_sphere_radiance",
    "lit_sphere_image",
    "brdf_png",
    "brdf_html",
    "THUMBNAIL_ROWS",
    "SPHERE_PIXELS",
    "SPHERE_LIGHT",
]

#: Rows of an environment map's thumbnail (twice as many columns).
THUMBNAIL_ROWS = 64
#: Width and height of a BRDF's lit-sphere thumbnail, pixels.
SPHERE_PIXELS = 96
#: Direction toward the thumbnail sphere's distant light (viewer along +z, x right, y up): upper left.
SPHERE_LIGHT = (-0.5, 0.5, math.sqrt(0.5))
#: Pixel of the dark background around the sphere (sRGB 8 bits).
_BACKDROP = 40


def number(value: Any, digits: int = 3) -> str:
    """A value as a table cell: floats to ``digits`` significant digits, None as "—"."""
    if value is None:
        return "—"
    if isinstance(value, bool | np.bool_):
        return "yes" if value else "no"
    if isinstance(value, float | np.floating):
        return "nan" if not math.isfinite(float(value)) else f"{float(value):.{digits}g}"
    return str(value)


def png_img(png: bytes, alt: str, *, width: int | None = None) -> str:
    """An ``<img>`` holding ``png`` as a base64 ``data:`` URI (the notebook file carries it)."""
    size = "" if width is None else f' width="{int(width)}"'
    data = base64.b64encode(png).decode("ascii")
    return f'<img src="data:image/png;base64,{data}" alt="{html.escape(alt)}"{size} style="image-rendering:auto">'


def html_table(headers: Sequence[str], rows: Iterable[Sequence[Any]], *, caption: str = "") -> str:
    """A small HTML table; cells are escaped (numbers through :func:`number`)."""
    pad = "style='padding:0 0.6em;text-align:right'"
    head = "".join(f"<th {pad}>{html.escape(h)}</th>" for h in headers)
    body = "".join("<tr>" + "".join(f"<td {pad}>{html.escape(number(c))}</td>" for c in row) + "</tr>"
                   for row in rows)
    cap = f"<caption style='text-align:left'>{html.escape(caption)}</caption>" if caption else ""
    return f"<table style='border-collapse:collapse;font-size:90%'>{cap}<thead><tr>{head}</tr></thead>" \
           f"<tbody>{body}</tbody></table>"


def card(title: str, rows: Sequence[tuple[str, Any]], *, image: str = "", extra: str = "") -> str:
    """The HTML of a notebook card: ``title`` over ``image`` (an ``<img>`` from :func:`png_img`, or
    nothing) beside a key/value table of ``rows``, then ``extra`` HTML (more tables)."""
    table = "".join(
        f"<tr><th style='text-align:left;padding-right:1em'>{html.escape(k)}</th>"
        f"<td style='text-align:left'>{html.escape(number(v))}</td></tr>" for k, v in rows
    )
    picture = f"<div style='margin-right:1em'>{image}</div>" if image else ""
    return (f"<div class='shrmkit-card'><strong>{html.escape(title)}</strong>"
            f"<div style='display:flex;align-items:flex-start;margin-top:0.3em'>{picture}"
            f"<table style='border-collapse:collapse;font-size:90%'>{table}</table></div>{extra}</div>")


# ------------------------------------------------------------------------------------------------
# environment maps
# ------------------------------------------------------------------------------------------------
def _column_sums(env: Any, columns: int) -> np.ndarray:
    """(H, columns, 3) float64 sums of ``columns`` blocks of whole columns (one pass over the map)."""
    edges = np.linspace(0, env.width, columns + 1).round().astype(int)[:-1]
    return np.add.reduceat(env.radiance, edges, axis=1, dtype=np.float64)


def _thumbnail_from(env: Any, sums: np.ndarray, rows: int) -> np.ndarray:
    """uint8 thumbnail from the column-block sums: solid-angle-weighted row blocks, the mean luminance
    brought to middle grey, filmic tone curve, sRGB."""
    widths = np.diff(np.append(np.linspace(0, env.width, sums.shape[1] + 1).round().astype(int)[:-1], env.width))
    omega = env.solid_angles()
    r_edges = np.linspace(0, env.height, rows + 1).round().astype(int)[:-1]
    block_omega = np.add.reduceat(omega, r_edges)
    small = np.add.reduceat(sums * omega[:, None, None], r_edges, axis=0)
    small /= (block_omega[:, None] * widths[None, :])[..., None]
    exposure = middle_grey_exposure(small, block_omega[:, None])
    return to_8bit(small, exposure=exposure, curve="filmic")


def env_thumbnail(env: Any, rows: int = THUMBNAIL_ROWS) -> np.ndarray:
    """uint8 (rows, 2·rows, 3), or the map's own size when it is smaller: solid-angle-weighted block
    means of whole pixels, the mean luminance brought to middle grey, filmic tone curve, sRGB."""
    rows = min(rows, env.height)
    return _thumbnail_from(env, _column_sums(env, min(2 * rows, env.width)), rows)


def env_png(env: Any) -> bytes:
    """The map's thumbnail (:func:`env_thumbnail`) as PNG bytes."""
    return encode_png(env_thumbnail(env))


def env_orientation(env: Any) -> str:
    """How the map was oriented into the project frame: the options its source records
    (``[latlong, up=y, flip]`` …), else the project frame itself."""
    found = re.findall(r"\[([^\]]*)\]", env.source or "")
    options = [f for f in found if "up=" in f or f.split(",")[0] in ("cube", "probe") or f.startswith("openexr")]
    return options[0] if options else "project frame (z up, row 0 = zenith)"


def _dynamic_range(env: Any) -> tuple[float, float, float]:
    """(largest luminance, smallest positive luminance's 1st percentile, stops between them)."""
    luma = np.asarray(env.radiance, dtype=np.float32) @ np.asarray(REC709_LUMA, dtype=np.float32)
    top = float(luma.max())
    positive = luma[luma > 0]
    if positive.size == 0:
        return top, 0.0, 0.0
    low = float(np.partition(positive, positive.size // 100)[positive.size // 100])  # the 1st percentile
    return top, low, float(math.log2(top / low)) if low > 0 else 0.0


def env_html(env: Any) -> str:
    """The card of an environment map: thumbnail, size, orientation, dynamic range, ∫L dω."""
    top, low, stops = _dynamic_range(env)
    rows_shown = min(THUMBNAIL_ROWS, env.height)
    sums = _column_sums(env, min(2 * rows_shown, env.width))
    integral = env.solid_angles() @ sums.sum(axis=1)  # = EnvironmentMap.integral(), from the same pass
    rows = [
        ("size", f"{env.height} × {env.width} (lat-long), {env.radiance.dtype}"),
        ("orientation", env_orientation(env)),
        ("source", env.source or "—"),
        ("dynamic range", f"{stops:.1f} stops (max luminance {top:.4g} / 1st percentile {low:.3g})"),
        ("∫ L dω (RGB)", ", ".join(f"{v:.4g}" for v in integral)),
    ]
    png = encode_png(_thumbnail_from(env, sums, rows_shown))
    return card(f"EnvironmentMap {env.name or ''}".strip(), rows,
                image=png_img(png, f"{env.name} (tone-mapped)", width=4 * THUMBNAIL_ROWS))


# ------------------------------------------------------------------------------------------------
# BRDFs
# ------------------------------------------------------------------------------------------------
def lit_sphere_radiance(brdf: Any, size: int = SPHERE_PIXELS, light: Sequence[float] = SPHERE_LIGHT, *,
                        nan_to_zero: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Linear radiance (size, size, 3) of the unit sphere of ``brdf`` under one distant light of
    irradiance π (a white Lambertian surface facing it gives 1), and the hit mask: orthographic view
    along −z (V = +z), pixel centres x = (2j+1)/size − 1, y = 1 − (2i+1)/size, normal
    N = (x, y, √(1 − x² − y²)); ρ evaluated once per lit pixel in the local frame (T = V's part
    across N, B = N × T, N); ``nan_to_zero``: a NaN of ρ (no measurement) drawn as 0. The one
    lit sphere of the package: ``analysis.brdf_views.lit_sphere`` (the report's explorer) calls it
    with ``nan_to_zero=False``."""
    lw = np.asarray(light, dtype=np.float64)
    lw = lw / np.linalg.norm(lw)
    c = (2.0 * np.arange(size) + 1.0) / size - 1.0
    x, y = np.meshgrid(c, -c)
    r2 = x * x + y * y
    hit = r2 < 1.0
    N = np.stack([x[hit], y[hit], np.sqrt(1.0 - r2[hit])], axis=-1)
    nv = N[:, 2]
    T = np.array([0.0, 0.0, 1.0]) - nv[:, None] * N
    tn = np.linalg.norm(T, axis=-1)
    # at the centre V = N: any tangent will do (isotropic BRDF)
    T = np.where(tn[:, None] > 1e-12, T / np.maximum(tn, 1e-300)[:, None], np.array([1.0, 0.0, 0.0]))
    B = np.cross(N, T)
    L = np.stack([T @ lw, B @ lw, N @ lw], axis=-1)
    V = np.stack([T[:, 2], B[:, 2], nv], axis=-1)
    lit = L[:, 2] > 0
    values = np.zeros((len(N), 3))
    if np.any(lit):
        rho = np.asarray(brdf.eval(L[lit], V[lit]), dtype=np.float64)
        values[lit] = (np.nan_to_num(rho, nan=0.0) if nan_to_zero else rho) * (math.pi * L[lit, 2])[:, None]
    radiance = np.zeros((size, size, 3))
    radiance[hit] = values
    return radiance, hit


def lit_sphere_image(brdf: Any, size: int = SPHERE_PIXELS, light: Sequence[float] = SPHERE_LIGHT
                     ) -> np.ndarray:
    """uint8 (size, size, 3): :func:`lit_sphere_radiance` through the filmic tone curve at exposure 0,
    sRGB, on a dark backdrop."""
    radiance, hit = lit_sphere_radiance(brdf, size, light)
    image = np.full((size, size, 3), _BACKDROP, np.uint8)
    image[hit] = to_8bit(radiance[hit], curve="filmic")
    return image


def brdf_png(brdf: Any) -> bytes | None:
    """The BRDF's lit sphere (:func:`lit_sphere_image`) as PNG bytes; None for a BRDF that cannot
    be evaluated everywhere (scattered measurements: fit a model first)."""
    if getattr(brdf, "kind", None) == "scattered":
        return None
    return encode_png(lit_sphere_image(brdf))


def brdf_html(brdf: Any) -> str:
    """The card of a BRDF: its lit sphere (not for scattered data), name, kind, class, source."""
    rows: list[tuple[str, Any]] = [("name", brdf.name), ("kind", brdf.kind), ("class", type(brdf).__name__)]
    source = getattr(brdf, "source", None)
    if source:
        rows.append(("source", str(source)))
    png = brdf_png(brdf)
    if png is None:
        rows.append(("picture", "none: scattered samples are not evaluated between measurements"))
        image = ""
    else:
        rows.append(("picture", "unit sphere, one distant light from the upper left, exposure 0"))
        image = png_img(png, f"{brdf.name} lit sphere", width=2 * SPHERE_PIXELS)
    return card(f"BRDF {brdf.name}", rows, image=image)
