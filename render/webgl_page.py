"""A self-contained HTML page that renders an SHRM [RH02] live in WebGL2: ``shrm view``.

:func:`build_view` gathers the page's data (:class:`ViewPage`): the viewer ``render/webgl/view.js``
and its GLSL ES 3.00 shaders ([WebGL2], [GLSLES3]; package data inlined: no network, it works from
``file://``), the SHRM's coefficient maps as a half-float atlas, the background, the mesh and a
still PNG for browsers without WebGL2; :func:`page_html` writes a whole page, :func:`view_fragment`
one to embed. The shaders draw ``distant`` ([RH02] eq. 12) and ``perpixel`` ([RH02] eq. 8) as
``shrm render`` does (``render.shader``); maps that do not fit the page's budget (:class:`ViewBudget`)
are reduced by :func:`fit_coefficients`, with a note. The page: ``data_specs/view_html.md``.
Here the page and its HTML; the budget rule in ``_page_fit.py``, the payloads in ``_page_payload.py``,
the camera and still image in ``_page_still.py``.
"""

from __future__ import annotations

import base64
import html
import json
import math
import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from .._version import __version__
from ..analysis.shrm import SHRM
from ..brdf_io.atomic import atomic_path
from ..brdf_io.envmap import EnvironmentMap
from ..brdf_io.errors import BadInputError
from ._page_fit import CoefficientFit, ViewBudget, fit_coefficients

# the `NAME as NAME` imports: public here before the split, importable from here still (patch them where read)
from ._page_payload import HALF_TARGET as HALF_TARGET
from ._page_payload import (
    PageEnvironment,
    _b64_len,
    _env_payload,
    _lights_payload,
    _mesh_payload,
    _page_mesh,
    _shrm_payload,
    stored_lights,
)
from ._page_still import CAMERA_DISTANCE, CAMERA_MARGIN, MAX_ELEVATION, _still, page_camera
from .defaults import DEFAULT_VIEW, STILL_RENDERERS, VIEW_MODES  # numpy-free home (CLI parsers)
from .defaults import DEFAULT_VIEW_MESH as DEFAULT_MESH
from .mesh import Mesh, load_mesh
from .output import TONE_MAPS
from .preview import preview_exposure, unit_mesh

__all__ = [
    "VIEW_MODES",
    "DEFAULT_MESH",
    "DEFAULT_VIEW",
    "CAMERA_DISTANCE",
    "CAMERA_MARGIN",
    "STILL_RENDERERS",
    "ViewBudget",
    "CoefficientFit",
    "ViewPage",
    "PageEnvironment",
    "page_camera",
    "fit_coefficients",
    "build_view",
    "view_fragment",
    "page_html",
    "view_html",
    "write_view",
    "webgl_sources",
    "stored_lights",
]

_WEBGL_DIR = "webgl"
_SHADER_SUFFIXES = (".glsl", ".vert", ".frag")



@dataclass(frozen=True, eq=False)
class ViewPage:
    """A page's content: the JSON document the viewer reads and the still image.

    Attributes
    ----------
    data
        The JSON document (``data_specs/view_html.md``), base64 payloads included.
    still_png
        PNG of the initial view shown where WebGL2 is missing (empty when ``still="none"``).
    still_renderer
        Which renderer made it (``cpu-reference``, ``opengl (...)``, ``given``, ``none``).
    notes
        Visible notes: reductions to fit the budget, mesh decimation, still-image limits.
    coeffs
        float32 ((P+1)², h, w, 3): the coefficient maps exactly as the page holds them
        (half-float rounding and scale undone), for comparisons.
    env_radiance
        float32 (h, w, 3): the background exactly as the page holds it, or None.
    mesh
        The mesh the page draws (after decimation).
    fit
        The :class:`CoefficientFit` of the budget rule.
    title
        Page title.
    environments
        Every environment the page switches between (the first is ``coeffs``, ``env_radiance`` and
        ``fit`` above), as :class:`PageEnvironment`; one entry for a page of one environment.
    """

    data: dict[str, Any]
    still_png: bytes
    still_renderer: str
    notes: tuple[str, ...]
    coeffs: np.ndarray
    env_radiance: np.ndarray | None
    mesh: Mesh
    fit: CoefficientFit
    title: str
    sources: dict[str, str] = field(default_factory=dict, repr=False)
    environments: tuple[PageEnvironment, ...] = ()

    @property
    def P(self) -> int:
        return self.fit.P

    def stored_shrm(self, source: SHRM, index: int = 0) -> SHRM:
        """An SHRM of the coefficients as stored (for the CPU reference of the page's image), with
        ``source``'s lights (the page holds their samples exactly, float32); ``index``: which of the
        page's :attr:`environments` (``source`` is the SHRM it was made from)."""
        stored = self.environments[index] if self.environments else PageEnvironment(
            "", self.coeffs, self.env_radiance, self.fit)
        return SHRM(F=source.F, P=stored.fit.P, coeffs=stored.coeffs, tolerance=source.tolerance,
                    eps=dict(source.eps), meta=dict(source.meta), lights=source.lights if source.has_lights else None,
                    brdf=source.lights_brdf() if source.has_lights else None)



# ------------------------------------------------------------------------------------------
# the page
# ------------------------------------------------------------------------------------------


def webgl_sources() -> dict[str, str]:
    """The package data of ``render/webgl``: file name → text (the viewer, shaders, style, template)."""
    folder = resources.files(__package__).joinpath(_WEBGL_DIR)
    return {entry.name: entry.read_text(encoding="utf-8") for entry in folder.iterdir()
            if entry.is_file() and entry.name.endswith((".js", ".css", ".html", *_SHADER_SUFFIXES))}


def _check_view(mode: str, tone: str, azimuth: float, elevation: float, zoom: float, exposure: float | None) -> None:
    if mode not in VIEW_MODES:
        raise BadInputError(None, f"view mode must be one of {', '.join(VIEW_MODES)}, got {mode!r}")
    if tone not in TONE_MAPS:
        raise BadInputError(None, f"tone map must be one of {', '.join(TONE_MAPS)}, got {tone!r}")
    for name, value in (("azimuth", azimuth), ("elevation", elevation), ("zoom", zoom)):
        if not isinstance(value, int | float) or not math.isfinite(value):
            raise BadInputError(None, f"{name} must be a finite number, got {value!r}")
    if not 0.25 <= zoom <= 10.0:
        raise BadInputError(None, f"zoom must be in [0.25, 10], got {zoom}")
    if not -MAX_ELEVATION <= elevation <= MAX_ELEVATION:
        raise BadInputError(None, f"elevation must be in [-{MAX_ELEVATION:g}, {MAX_ELEVATION:g}] degrees, "
                            f"got {elevation}")
    if exposure is not None and (not isinstance(exposure, int | float) or not -30.0 <= exposure <= 30.0):
        raise BadInputError(None, f"exposure must be a number of stops in [-30, 30], got {exposure!r}")


def build_view(
    shrm: SHRM,
    env: EnvironmentMap | None = None,
    *,
    mesh: Mesh | str | Path | None = None,
    mode: str = "distant",
    exposure: float | None = None,
    tone: str = "filmic",
    azimuth: float = DEFAULT_VIEW["azimuth"],
    elevation: float = DEFAULT_VIEW["elevation"],
    zoom: float = DEFAULT_VIEW["zoom"],
    background: bool = True,
    budget: ViewBudget | None = None,
    still: str = "auto",
    still_png: bytes | None = None,
    title: str | None = None,
    env_rotation: tuple[float, ...] = (0.0, 0.0, 0.0),
    more: Sequence[tuple[SHRM, EnvironmentMap | None]] = (),
) -> ViewPage:
    """Everything a view page holds, within the size budget.

    Parameters
    ----------
    shrm
        The global SHRM (``analysis.shrm.prefilter``).
    env
        The environment it was prefiltered from, for the background (None: black, no toggle).
    mesh
        A :class:`Mesh`, a path or a built-in spec (default :data:`DEFAULT_MESH`); moved into
        the unit sphere, decimated to ``budget.mesh_bytes``.
    mode, tone, exposure, azimuth, elevation, zoom, background
        The initial view (the URL hash of the page overrides it): render mode (``distant`` or
        ``perpixel``), tone map (``filmic`` or ``srgb``), exposure in stops (None: the
        preview rule, ``render.preview.preview_exposure`` — 0 without ``env``), camera
        (:func:`page_camera`) and whether the environment is drawn behind the object.
    env_rotation
        The lighting's initial rotation, degrees (AZ, EL[, ROLL]) as
        :func:`~shrmkit.brdf_io.env_rotation.env_rotation_matrix` (the page's ``env_azimuth``,
        ``env_elevation``, ``env_roll``; EL in [−90, 90]); the still image shows it too.
    more
        Further (SHRM, environment) pairs the page switches between without reloading (an
        ``environment`` menu and ``env_index`` in the URL); prefiltered from the same BRDF.
        The coefficient budget is shared equally, the backgrounds get at most a quarter of the
        page together (rows halved until they fit). The still image shows the first.
    budget
        Size limits (:class:`ViewBudget`).
    still, still_png
        The still image for browsers without WebGL2: ``still_png`` when given (e.g. a report's
        preview), else rendered by ``still`` — ``"cpu"`` (the CPU reference renderer on the
        analytic sphere), ``"gl"`` (VTK offscreen, the page's mesh), ``"auto"`` (cpu for the
        default sphere, gl for a mesh when an offscreen context exists, else the sphere with a
        note) or ``"none"``.
    title
        Page title (default: "BRDF under ENV" from the SHRM's :attr:`~shrmkit.analysis.shrm.SHRM.info`).

    Raises
    ------
    BadInputError
        Bad view values or rotation, a mesh that cannot be loaded or decimated, a budget that
        cannot hold even one small map per environment, an entry of ``more`` that is not an SHRM.
    """
    pairs = _check_pairs(shrm, env, more)
    budget = ViewBudget() if budget is None else budget
    if still not in STILL_RENDERERS:
        raise BadInputError(None, f"still must be one of {', '.join(STILL_RENDERERS)}, got {still!r}")
    view = _initial_view(env, mode, tone, exposure, azimuth, elevation, zoom, background, env_rotation, len(pairs))
    is_sphere = mesh is None
    source_mesh = load_mesh(DEFAULT_MESH if mesh is None else mesh) if not isinstance(mesh, Mesh) else mesh
    notes: list[str] = []
    page_mesh, mesh_note = _page_mesh(source_mesh, budget.mesh_bytes)
    if mesh_note:
        notes.append(mesh_note)
    png, renderer, still_note, still_mode = (
        (bytes(still_png), "given", None, mode) if still_png is not None
        else _still(shrm, env, unit_mesh(source_mesh), is_sphere, view, budget.still_size, still))
    if still_note:
        notes.append(still_note)
    brdf_name = _named(shrm.info.brdf, "BRDF")
    names = [_named(s_k.info.environment, e_k.name if e_k is not None else "environment") for s_k, e_k in pairs]
    title = title or f"{brdf_name} under {names[0]}"
    env_rows = _background_rows(budget, len(pairs))
    entries, stored_envs = _environment_entries(pairs, names, env_rows, budget, notes)
    data = _page_data(title, brdf_name, view, entries, _mesh_payload(page_mesh), renderer, still_mode, notes, budget,
                      env_rows)
    sources = webgl_sources()
    max_bytes = _coefficient_bytes(data, entries, pairs, png, sources, budget)
    stored_pages: list[PageEnvironment] = []
    for entry, (s_k, _), name, env_stored in zip(entries, pairs, names, stored_envs, strict=True):
        entry["shrm"], page = _shrm_payload(s_k, name, env_stored, max_bytes, budget)
        if page.fit.reduced:
            notes.append(("" if len(pairs) == 1 else f"{name}: ") + _reduction_note(s_k, page.fit, budget))
        stored_pages.append(page)
    data["shrm"] = entries[0]["shrm"]
    data["notes"] = notes
    first = stored_pages[0]
    return ViewPage(data, png, renderer, tuple(notes), first.coeffs, first.env_radiance, page_mesh, first.fit, title,
                    sources, tuple(stored_pages))


def _named(name: str | None, fallback: str) -> str:
    """A name of the SHRM's record (:attr:`~shrmkit.analysis.shrm.SHRM.info`), or ``fallback``
    when the SHRM does not state it."""
    return str(fallback if name is None else name)


def _initial_view(env: EnvironmentMap | None, mode: str, tone: str, exposure: float | None, azimuth: float,
                  elevation: float, zoom: float, background: bool, env_rotation: tuple[float, ...], n_envs: int
                  ) -> dict[str, Any]:
    """The page's initial view (checked): camera, exposure in stops (None: the preview rule, 0
    without an environment), mode, tone map, background and the lighting's rotation in degrees."""
    _check_view(mode, tone, azimuth, elevation, zoom, exposure)
    rotation = _check_env_angles(env_rotation)
    if exposure is None:
        exposure = preview_exposure(env) if env is not None else 0.0
    view = {"azimuth": float(azimuth), "elevation": float(elevation), "zoom": float(zoom),
            "exposure": round(float(exposure), 3), "mode": mode, "background": bool(background and env is not None),
            "tone": tone, "env_azimuth": rotation[0], "env_elevation": rotation[1], "env_roll": rotation[2]}
    if n_envs > 1:
        view["env_index"] = 0
    return view


def _page_data(title: str, brdf_name: str, view: dict[str, Any], entries: list[dict[str, Any]],
               mesh: dict[str, Any], renderer: str, still_mode: str, notes: list[str], budget: ViewBudget,
               env_rows: int) -> dict[str, Any]:
    """The page's data document (shrmkit-view version 1, ``data_specs/view_html.md``) before the coefficients:
    the first environment's payloads at the top, every environment's under ``environments``."""
    data: dict[str, Any] = {
        "format": "shrmkit-view",
        "version": 1,
        "title": title,
        "brdf": brdf_name,
        "environment": entries[0]["name"],
        "camera": {"distance": CAMERA_DISTANCE, "margin": CAMERA_MARGIN},
        "view": view,
        "shrm": None,
        "env": entries[0]["env"],
        "mesh": mesh,
        "lights": entries[0]["lights"],
        "still": {"renderer": renderer, "width": budget.still_size, "height": budget.still_size,
                  "view": {**view, "mode": still_mode}},
        "notes": notes,
        "budget": {"page_bytes": budget.page_bytes, "mesh_bytes": budget.mesh_bytes, "env_rows": env_rows},
    }
    if len(entries) > 1:
        data["environments"] = entries  # entries[0]'s payloads are data's own (the first environment)
    return data


def _check_pairs(shrm: SHRM, env: EnvironmentMap | None, more: Sequence[tuple[SHRM, EnvironmentMap | None]]
                 ) -> list[tuple[SHRM, EnvironmentMap | None]]:
    """The page's (SHRM, environment) pairs, the first one first; each must hold an SHRM."""
    pairs = [(shrm, env), *[(s_k, e_k) for s_k, e_k in more]]
    for k, (s_k, _) in enumerate(pairs):
        if not isinstance(s_k, SHRM):
            raise BadInputError(None, f"build_view needs an SHRM (environment {k}), got {type(s_k).__name__}")
    return pairs


def _background_rows(budget: ViewBudget, n_envs: int) -> int:
    """Rows of each background map: ``budget.env_rows``, halved (down to 8) while several
    backgrounds together pass a quarter of the page."""
    env_rows = budget.env_rows
    if n_envs > 1:
        while env_rows > 8 and n_envs * _b64_len(env_rows * 2 * env_rows * 6) > budget.page_bytes // 4:
            env_rows //= 2
    return env_rows


def _environment_entries(pairs: Sequence[tuple[SHRM, EnvironmentMap | None]], names: Sequence[str], env_rows: int,
                         budget: ViewBudget, notes: list[str]) -> tuple[list[dict[str, Any]], list[np.ndarray | None]]:
    """Each environment's page entry (name, background, lights; the SHRM comes later) and the
    background radiance the page stores (None without one); lights' notes go to ``notes``."""
    entries: list[dict[str, Any]] = []
    stored_envs: list[np.ndarray | None] = []
    for (s_k, e_k), name in zip(pairs, names, strict=True):
        env_data, env_stored = (None, None) if e_k is None else _env_payload(e_k, env_rows)
        lights_data, lights_note = _lights_payload(s_k, budget)
        if lights_note:
            notes.append(lights_note if len(pairs) == 1 else f"{name}: {lights_note}")
        entries.append({"name": name, "shrm": None, "env": env_data, "lights": lights_data})
        stored_envs.append(env_stored)
    return entries, stored_envs


def _shrm_placeholder(s_k: SHRM) -> dict[str, Any]:
    """An SHRM entry without texels: what the page holds besides the coefficients is measured with it."""
    return {"F": s_k.F, "P": s_k.P, "source": {"P": s_k.P, "height": s_k.height, "width": s_k.width},
            "height": s_k.height, "width": s_k.width, "cols": 0, "rows": 0, "scale": 1.0,
            "added_rel_rms": 0.0, "texels": ""}


def _coefficient_bytes(data: dict[str, Any], entries: list[dict[str, Any]],
                       pairs: Sequence[tuple[SHRM, EnvironmentMap | None]], png: bytes, sources: dict[str, str],
                       budget: ViewBudget) -> int:
    """Raw bytes each environment's coefficients may take: what the page costs without them is
    measured, the budget rule gets the rest, shared equally (the reduction notes and the numbers of
    the shrm entries are covered by the margin; base64 makes 4 bytes of 3)."""
    for entry, (s_k, _) in zip(entries, pairs, strict=True):
        entry["shrm"] = _shrm_placeholder(s_k)
    data["shrm"] = entries[0]["shrm"]
    fixed = len(_render_page(data["title"], data, png, sources).encode("utf-8"))
    margin = 2048 * len(pairs)
    room = (budget.page_bytes - fixed - margin) // len(pairs)
    max_bytes = (room // 4) * 3
    if max_bytes <= 0:
        raise BadInputError(None, f"the page budget of {budget.page_bytes} bytes is used up before the SHRM "
                            f"({fixed} bytes for the viewer, mesh, background and still image)")
    return max_bytes



def _reduction_note(s_k: SHRM, fit: CoefficientFit, budget: ViewBudget) -> str:
    """What the budget cut from an SHRM (texels, view order P) and the estimated added error."""
    H, W = fit.source_shape[1], fit.source_shape[2]
    h, w = fit.coeffs.shape[1:3]
    parts = []
    if (h, w) != (H, W):
        parts.append(f"coefficient maps {H}x{W} -> {h}x{w} texels")
    if fit.P != s_k.P:
        parts.append(f"view order P {s_k.P} -> {fit.P} ({(fit.P + 1) ** 2} of {(s_k.P + 1) ** 2} maps)")
    return (f"reduced to fit the {budget.page_bytes / 2**20:.3g} MiB page budget: " + ", ".join(parts)
            + f"; estimated added error {100 * fit.added_rel_rms:.2g} % relative RMS over all (R, V)")


def _check_env_angles(angles: Any) -> tuple[float, float, float]:
    """The page's lighting rotation (AZ, EL[, ROLL]) in degrees: finite, EL in [−90, 90]."""
    try:
        values = [float(a) for a in angles]
    except (TypeError, ValueError):
        values = []
    if len(values) not in (2, 3) or not all(math.isfinite(v) for v in values):
        raise BadInputError(None, f"env_rotation must be two or three finite angles AZ, EL[, ROLL] in degrees, "
                            f"got {angles!r}")
    if not -90.0 <= values[1] <= 90.0:
        raise BadInputError(None, f"env_rotation: the elevation must be in [-90, 90] degrees, got {values[1]:g}")
    return values[0], values[1], values[2] if len(values) == 3 else 0.0


def _page_document(data: dict[str, Any]) -> dict[str, Any]:
    """The JSON document as the page holds it: with several environments, the first one's payloads
    are not repeated in ``environments[0]`` (the viewer reads them from the document's own keys)."""
    if "environments" not in data:
        return data
    return {**data, "environments": [{"name": data["environments"][0]["name"]}, *data["environments"][1:]]}


def _json_script(doc: Any) -> str:
    """JSON that is safe inside a <script> element."""
    text = json.dumps(doc, separators=(",", ":"), allow_nan=False)
    return text.replace("</", "<\\/").replace("<!--", "<\\!--")


_ID = re.compile(r"^[A-Za-z][A-Za-z0-9_-]{0,63}$")


def _fragment(title: str, data: dict[str, Any], png: bytes, sources: dict[str, str], element_id: str,
              use_hash: bool) -> str:
    if not _ID.match(element_id):
        raise BadInputError(None, f"element_id must be a letter then letters, digits, '-' or '_', got {element_id!r}")
    shaders = {name: text for name, text in sorted(sources.items()) if name.endswith(_SHADER_SUFFIXES)}
    s = data["shrm"]
    lights = data.get("lights")
    info = (f"F = {s['F']}, P = {s['P']}, maps {s['height']}x{s['width']}, mesh {data['mesh']['triangles']} "
            f"triangles" + (f", {lights['count']} light samples shaded per pixel" if lights else ""))
    notes = "".join(f'<div class="shrm-view-note">{html.escape(n)}</div>' for n in data["notes"])
    still = (f'<img class="shrm-view-fallback" alt="still image of {html.escape(title)}" '
             f'src="data:image/png;base64,{base64.b64encode(png).decode("ascii")}">') if png else ""
    return "\n".join([
        f'<style>{sources["view.css"]}</style>',
        f'<div class="shrm-view" id="{element_id}" data-state="loading">',
        f'<canvas class="shrm-view-canvas" aria-label="live view of {html.escape(title)}"></canvas>',
        '<div class="shrm-view-still"><div class="shrm-view-fallback-note"></div>' + still + "</div>",
        f'<div class="shrm-view-info"><span class="shrm-view-title">{html.escape(title)}</span>'
        f'<span class="shrm-view-numbers"> — {html.escape(info)}</span>'
        ' <span class="shrm-view-help">· drag: orbit · Shift+drag: lighting · wheel: zoom · double-click: reset · '
        'click here: fold</span>'
        + notes + "</div>",
        '<div class="shrm-view-ui"></div>',
        "</div>",
        f"<script>window.ShrmViewShaders = window.ShrmViewShaders || {_json_script(shaders)};</script>",
        f"<script>{sources['view.js']}</script>",
        f'<script type="application/json" id="{element_id}-data">{_json_script(_page_document(data))}</script>',
        "<script>(function () { var root = document.getElementById(" + json.dumps(element_id) + ");"
        " var data = JSON.parse(document.getElementById(" + json.dumps(element_id + "-data") + ").textContent);"
        f" window.ShrmView.mount(root, data, {{hash: {'true' if use_hash else 'false'}}}); }})();</script>",
    ])


#: The page template's placeholders, filled in one pass (:func:`_render_page`).
_PLACEHOLDER = re.compile(r"\{\{(VERSION|TITLE|FRAGMENT)\}\}")


def _render_page(title: str, data: dict[str, Any], png: bytes, sources: dict[str, str]) -> str:
    """The page: the template's placeholders replaced in a single pass over the template, so text
    that came from a user (a file named ``{{FRAGMENT}}.hdr``, a title) is never read again as a
    placeholder (successive ``str.replace`` calls pasted the fragment into itself; issue 28)."""
    fragment = _fragment(title, data, png, sources, "shrm-view", True)
    values = {"VERSION": html.escape(__version__), "TITLE": html.escape(title), "FRAGMENT": fragment}
    return _PLACEHOLDER.sub(lambda match: values[match.group(1)], sources["page.html"])


def view_fragment(page: ViewPage, *, element_id: str = "shrm-view", use_hash: bool = False) -> str:
    """The viewer as an HTML fragment to embed in another page (a report): a ``<div
    class="shrm-view" id=element_id>`` (size it with CSS, e.g. ``#id {width: 480px; height:
    480px}``), its style and scripts. Several fragments may share a page (distinct ids);
    ``use_hash`` lets the page's URL hash set this viewer's view (one per page)."""
    return _fragment(page.title, page.data, page.still_png, page.sources or webgl_sources(), element_id, use_hash)


def page_html(page: ViewPage) -> str:
    """The whole self-contained HTML page (the view follows the URL hash).

    Raises ValueError if it exceeds the page budget it was built for (never, by construction).
    """
    text = _render_page(page.title, page.data, page.still_png, page.sources or webgl_sources())
    limit = page.data.get("budget", {}).get("page_bytes")
    size = len(text.encode("utf-8"))
    if limit is not None and size > limit:
        raise ValueError(f"the view page has {size} bytes, over its budget of {limit}")
    return text


def view_html(shrm: SHRM, env: EnvironmentMap | None = None, **kwargs: Any) -> str:
    """``page_html(build_view(shrm, env, **kwargs))``: the page as a string."""
    return page_html(build_view(shrm, env, **kwargs))


def write_view(path: str | Path, text: str) -> Path:
    """Write a page atomically (UTF-8); returns the path."""
    target = Path(path)
    with atomic_path(target) as tmp:
        Path(tmp).write_text(text, encoding="utf-8")
    return target
