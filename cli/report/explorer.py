"""BRDF Explorer's views of a BRDF for its report, and the live WebGL2 previews.

:func:`explore` builds the ``explorer`` block of ``report.json`` (``data_specs/report_json.md``;
``plots.py`` draws it) from the views of Disney's BRDF Explorer (Burley 2012), computed by
``analysis.brdf_views`` and ``analysis.albedo``, for the BRDF and each fitted model:

- the half/difference **image slice** (tabulated and analytic BRDFs; missing cells and cells
  below the surface marked), or the **measured samples near the plane of incidence**
  (scattered measurements);
- **polar plots** of the plane of incidence at θ_i = :data:`POLAR_INCIDENCE_DEG` (scattered:
  the nearest measured θ_i);
- the **directional albedo** at :data:`ALBEDO_CURVE_VIEWS_DEG` (not of scattered measurements);
- the **lit sphere**, tone mapped by ``render.output.to_8bit`` (filmic, exposure 0) into
  :data:`SPHERE_FILE`.

Luminance is Rec. 709 (``brdf_io.colour.REC709_LUMA``).

:func:`live_views` builds the live WebGL2 preview of each environment's SHRM at the main
tolerance (``render.webgl_page``) for ``report.html``, within :data:`LIVE_VIEW_BUDGET_BYTES`
per view, with the report's sphere preview as the still image for browsers without WebGL2.

References
----------
B. Burley, "Physically-Based Shading at Disney", SIGGRAPH 2012 course notes (BRDF Explorer).
"""

from __future__ import annotations

import math
import re
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from ...analysis.albedo import directional_albedo
from ...analysis.brdf_views import (
    PLANE_TOLERANCE_DEG,
    SLICE_PHI_D_DEG,
    SPHERE_LIGHT,
    SPHERE_SIZE,
    halfdiff_slice,
    lit_sphere,
    plane_directions,
    plane_samples,
)
from ...brdf_io.brdf import BRDF
from ...brdf_io.colour import REC709_LUMA
from ...brdf_io.masked_grid import eval_with_mask
from ...render.output import to_8bit
from ...render.preview import PREVIEW_VIEW, PreviewImage
from ...render.webgl_page import ViewBudget, build_view, view_fragment
from .images import image_row_plot

if TYPE_CHECKING:
    from ...brdf_io.cornell import ScatteredBRDF

__all__ = [
    "POLAR_INCIDENCE_DEG", "POLAR_THETA_DEG", "ALBEDO_CURVE_VIEWS_DEG", "MAX_SAMPLES", "SPHERE_FILE",
    "LIVE_VIEW_BUDGET_BYTES", "ReportImage", "LiveView", "explore", "live_views", "preview_view_angles",
]

#: θ_i of the polar plots.
POLAR_INCIDENCE_DEG = (0.0, 30.0, 60.0, 75.0)
#: Signed θ_o of the polar curves.
POLAR_THETA_DEG = np.arange(-87.5, 87.5 + 1e-9, 2.5)
#: θ_v of the directional-albedo curves (denser than the energy check's ``analysis.albedo.ALBEDO_CHECK_VIEWS_DEG``).
ALBEDO_CURVE_VIEWS_DEG = (*range(0, 90, 5), 88)
#: At most this many in-plane samples are stored (every k-th beyond it).
MAX_SAMPLES = 4000
#: File of the lit-sphere images (size and light: ``analysis.brdf_views.SPHERE_SIZE``, ``SPHERE_LIGHT``).
SPHERE_FILE = "explorer_sphere.png"
#: 8-bit grey behind the sphere (so that its unlit side is seen against it).
SPHERE_BACKGROUND = 48
#: Size budget of one live view in report.html (the coefficient maps are reduced to fit;
#: ``render.webgl_page.fit_coefficients``).
LIVE_VIEW_BUDGET_BYTES = 3 << 20


@dataclass(frozen=True)
class ReportImage:
    """A PNG of the report folder that is not a plot of report.json (the lit sphere)."""

    file: str
    png: bytes


@dataclass(frozen=True)
class LiveView:
    """The HTML fragment of one live preview (``render.webgl_page.view_fragment``) for report.html."""

    element_id: str
    env: str
    html: str


# ------------------------------------------------------------------------------ json


def _luma(rgb: np.ndarray) -> np.ndarray:
    return np.asarray(rgb, dtype=np.float64) @ REC709_LUMA


def _grid_json(lum: np.ndarray, blank: np.ndarray) -> list[list[float | None]]:
    return [[None if b else float(v) for v, b in zip(row, brow, strict=True)] for row, brow in zip(lum, blank,
                                                                                                   strict=True)]


def _rgb_json(rgb: np.ndarray, has: np.ndarray | None = None) -> list[list[float] | None]:
    out: list[list[float] | None] = [list(map(float, v)) for v in np.asarray(rgb, dtype=np.float64)]
    if has is not None:
        out = [v if h else None for v, h in zip(out, has, strict=True)]
    return out


# ------------------------------------------------------------------------------ explorer


def explore(brdf: BRDF, fit_results: Sequence[Any], models: Sequence[str], *, albedo_nodes: int = 48
            ) -> tuple[dict[str, Any], list[ReportImage]]:
    """The ``explorer`` block of report.json and the lit-sphere PNG.

    ``fit_results`` are the ``fit_brdf`` results (None for a fit that could not run), in
    the order of ``models``. An error is reported in the block (``error``), not raised: the
    views must not lose the report.
    """
    t0 = time.perf_counter()
    try:
        block, files = _explore(brdf, fit_results, models, albedo_nodes)
    except Exception as err:  # any failure of the views is reported in the block, not raised
        block = {"of": "measured samples" if brdf.kind == "scattered" else "brdf", "error": f"{err}",
                 "slice": None, "samples": None, "polar": None, "albedo": None, "sphere": None}
        files = []
    block["explorer_seconds"] = time.perf_counter() - t0
    return block, files


def _explore(brdf: BRDF, fit_results: Sequence[Any], models: Sequence[str], albedo_nodes: int
             ) -> tuple[dict[str, Any], list[ReportImage]]:
    scattered = brdf.kind == "scattered"
    fits = [(m, None if f is None else f.brdf) for m, f in zip(models, fit_results, strict=True)]
    block: dict[str, Any] = {"of": "measured samples" if scattered else "brdf", "error": None,
                             "luminance": "Rec. 709"}
    # the slice, or the measured samples near the plane of incidence
    plane = None
    if scattered:
        plane = plane_samples(brdf)
        block["slice"] = None
        block["samples"] = _samples_block(*plane)
    else:
        block["slice"] = _slice_block(brdf, fits)
        block["samples"] = None
    block["polar"] = _polar_block(brdf, fits, plane)
    block["albedo"] = _albedo_block(brdf, fits, scattered, albedo_nodes)
    block["sphere"], files = _sphere_block(brdf, fits, scattered)
    return block, files


def _samples_block(ti: np.ndarray, so: np.ndarray, rgb: np.ndarray) -> dict[str, Any]:
    """The measured samples near the plane of incidence (θ_i, θ_o in degrees, RGB in 1/sr), sorted
    by (θ_i, θ_o) and thinned to at most :data:`MAX_SAMPLES`."""
    order = np.lexsort((so, ti))
    ti, so, rgb = ti[order], so[order], rgb[order]
    n_total = len(ti)
    if n_total > MAX_SAMPLES:
        keep = np.arange(0, n_total, math.ceil(n_total / MAX_SAMPLES))
        ti, so, rgb = ti[keep], so[keep], rgb[keep]
    return {"max_off_plane_deg": PLANE_TOLERANCE_DEG, "n_in_plane": int(n_total),
            "n_shown": int(len(ti)), "theta_i_deg": ti.tolist(), "theta_o_deg": so.tolist(),
            "rgb": rgb.tolist()}


def _slice_block(brdf: BRDF, fits: Sequence[tuple[str, BRDF | None]]) -> dict[str, Any]:
    """The (θ_h, θ_d) slice at φ_d = :data:`SLICE_PHI_D_DEG`: the BRDF's and each fit's luminance."""
    s = halfdiff_slice(brdf)
    blank = s["missing"] | s["below_surface"]
    fitted: dict[str, Any] = {}
    for model, fb in fits:
        if fb is None:
            fitted[model] = None
        else:
            f = halfdiff_slice(fb)
            fitted[model] = _grid_json(_luma(f["rgb"]), f["below_surface"])
    return {
        "phi_d_deg": SLICE_PHI_D_DEG, "theta_h_deg": s["theta_h_deg"].tolist(),
        "theta_d_deg": s["theta_d_deg"].tolist(), "lum": _grid_json(_luma(s["rgb"]), blank),
        "missing": np.argwhere(s["missing"]).tolist(), "below_surface": np.argwhere(s["below_surface"]).tolist(),
        "n_missing": int(s["missing"].sum()), "fitted_lum": fitted,
    }


def _polar_incidence(brdf: BRDF, scattered: bool) -> list[float]:
    """θ_i of the polar curves (degrees): :data:`POLAR_INCIDENCE_DEG`, or for measured samples the
    nearest measured incidence (whole degrees) to each."""
    if not scattered:
        return list(POLAR_INCIDENCE_DEG)
    samples = cast("ScatteredBRDF", brdf)  # the BRDFs of kind "scattered" (duck-typed by kind)
    theta_all = np.degrees(np.arccos(np.clip(np.asarray(samples.L, float)[:, 2], -1.0, 1.0)))
    levels = np.unique(np.round(theta_all))
    return sorted({float(levels[np.argmin(np.abs(levels - v))]) for v in POLAR_INCIDENCE_DEG})


def _polar_block(brdf: BRDF, fits: Sequence[tuple[str, BRDF | None]],
                 plane: tuple[np.ndarray, np.ndarray, np.ndarray] | None) -> dict[str, Any]:
    """Polar curves of the plane of incidence: measured (the samples within 0.5° of θ_i when
    ``plane`` holds them) and fitted RGB against θ_o, per θ_i."""
    curves = []
    for theta_i in _polar_incidence(brdf, plane is not None):
        L, V = plane_directions(theta_i, POLAR_THETA_DEG)
        curve: dict[str, Any] = {"theta_i_deg": theta_i}
        if plane is not None:
            ti_all, so_all, rgb_all = plane
            sel = np.abs(ti_all - theta_i) < 0.5
            order = np.argsort(so_all[sel], kind="stable")
            curve["measured_theta_o_deg"] = so_all[sel][order].tolist()
            curve["measured_rgb"] = rgb_all[sel][order].tolist()
        else:
            rho, has = eval_with_mask(brdf, L, V)
            curve["measured_theta_o_deg"] = POLAR_THETA_DEG.tolist()
            curve["measured_rgb"] = _rgb_json(rho, has)
        curve["fitted_rgb"] = {m: (None if fb is None else _rgb_json(fb.eval(L, V))) for m, fb in fits}
        curves.append(curve)
    return {"theta_o_deg": POLAR_THETA_DEG.tolist(), "curves": curves}


def _albedo_block(brdf: BRDF, fits: Sequence[tuple[str, BRDF | None]], scattered: bool,
                  albedo_nodes: int) -> dict[str, Any]:
    """Directional albedo (RGB) against θ_v at :data:`ALBEDO_CURVE_VIEWS_DEG`, the BRDF's and each fit's."""
    views = tuple(float(v) for v in ALBEDO_CURVE_VIEWS_DEG)
    return {
        "views_deg": list(views), "nodes": int(albedo_nodes),
        "measured_rgb": None if scattered else directional_albedo(brdf, views, nodes=albedo_nodes).tolist(),
        "fitted_rgb": {m: (None if fb is None else directional_albedo(fb, views, nodes=albedo_nodes).tolist())
                       for m, fb in fits},
    }


def _sphere_block(brdf: BRDF, fits: Sequence[tuple[str, BRDF | None]], scattered: bool
                  ) -> tuple[dict[str, Any], list[ReportImage]]:
    """Lit spheres of the BRDF (not of scattered samples) and of each fit: the block and the PNG."""
    panels = ([] if scattered else [("brdf", brdf)]) + [(m, fb) for m, fb in fits if fb is not None]
    images, entries = [], []
    for label, b in panels:
        radiance, hit = lit_sphere(b)
        lum = _luma(radiance[hit])
        image = to_8bit(radiance.astype(np.float32))
        image[~hit] = SPHERE_BACKGROUND
        images.append(image)
        entries.append({"label": label, "max_lum": float(lum.max()), "mean_lum": float(lum.mean())})
    files = []
    if images:
        files.append(ReportImage(SPHERE_FILE, image_row_plot(images, [str(e["label"]) for e in entries])))
    block = {"file": SPHERE_FILE if images else None, "size": SPHERE_SIZE,
             "light": list(map(float, np.asarray(SPHERE_LIGHT) / np.linalg.norm(SPHERE_LIGHT))),
             "view": [0.0, 0.0, 1.0], "irradiance": math.pi, "tone": "filmic", "exposure": 0.0,
             "images": entries}
    return block, files


# ---------------------------------------------------------------------------- live views


def preview_view_angles() -> tuple[float, float]:
    """(azimuth, elevation) in degrees of ``render.preview.PREVIEW_VIEW``: the live view's
    initial camera is then the preview camera (same eye, field of view and up)."""
    x, y, z = PREVIEW_VIEW
    return math.degrees(math.atan2(y, x)), math.degrees(math.atan2(z, math.hypot(x, y)))


def _element_id(k: int, name: str) -> str:
    slug = re.sub(r"[^A-Za-z0-9_-]+", "-", name).strip("-")[:40]
    return f"live-view-{k}" + (f"-{slug}" if slug else "")


def live_views(main_shrms: Sequence[tuple[Any, Any]], previews: Sequence[Any], *, preview_mode: str,
               preview_size: int) -> tuple[dict[str, Any], list[LiveView]]:
    """The ``live_preview`` block of report.json and one :class:`LiveView` per environment.

    ``main_shrms`` are the (environment, SHRM) pairs at the main tolerance; the first
    environment's sphere preview (``previews``) is its still image, the others get a CPU
    reference still of ``preview_size`` pixels. With ``preview_mode == "none"`` no view is made.
    """
    t0 = time.perf_counter()
    azimuth, elevation = preview_view_angles()
    block: dict[str, Any] = {"budget_bytes": LIVE_VIEW_BUDGET_BYTES, "view": None, "views": [], "notes": []}
    if preview_mode == "none":
        block["notes"].append("live preview disabled with the preview")
        block["live_preview_seconds"] = time.perf_counter() - t0
        return block, []
    sphere = next((p for p in previews if isinstance(p, PreviewImage) and p.key == "sphere"), None)
    budget = ViewBudget(page_bytes=LIVE_VIEW_BUDGET_BYTES, still_size=max(16, int(preview_size)))
    out: list[LiveView] = []
    for k, (env, shrm) in enumerate(main_shrms):
        element_id = _element_id(k, env.name)
        try:
            still = sphere.png if (k == 0 and sphere is not None) else None
            page = build_view(shrm, env, budget=budget, azimuth=azimuth, elevation=elevation,
                              still="cpu", still_png=still)
            fragment = view_fragment(page, element_id=element_id)
        except Exception as err:  # a failed live view must not lose the report
            block["notes"].append(f"live preview under {env.name} failed: {err}")
            continue
        if block["view"] is None:
            block["view"] = dict(page.data["view"])
        s = page.data["shrm"]
        block["views"].append({
            "env": env.name, "element_id": element_id, "F": s["F"], "P": s["P"], "source_P": s["source"]["P"],
            "maps": [s["height"], s["width"]], "source_maps": [s["source"]["height"], s["source"]["width"]],
            "added_rel_rms": s["added_rel_rms"], "still": ("preview_sphere.png" if still is not None
                                                           else page.still_renderer),
            "html_bytes": len(fragment.encode("utf-8")), "notes": list(page.notes),
        })
        out.append(LiveView(element_id, env.name, fragment))
    block["live_preview_seconds"] = time.perf_counter() - t0
    return block, out
