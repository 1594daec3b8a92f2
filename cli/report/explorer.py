"""BRDF Explorer's views of a BRDF for its report, and the live WebGL2 previews.

The views of Disney's BRDF Explorer (Burley 2012), computed from the BRDF objects at report
time; the numbers go into ``report.json`` (``explorer``, ``data_specs/report_json.md``) and
``plots.py`` draws them from there. Luminance is Rec. 709, 0.2126 R + 0.7152 G + 0.0722 B.

- **Image slice** (tabulated and analytic BRDFs): ρ on a θ_h × θ_d grid (cell centres every
  :data:`SLICE_STEP_DEG`) at φ_d = :data:`SLICE_PHI_D_DEG`, the directions from the
  half/difference angles (Rusinkiewicz 1998, ``brdf_io.halfdiff.halfdiff_to_directions``,
  φ_h = 0), for the BRDF and each fitted model. A cell is *missing* where the table has no
  present sample in its interpolation cell (``eval_masked``; MERL stores missing samples as
  negative numbers, read as NaN), *below the surface* where L or V is (ρ = 0 by definition;
  none at φ_d = 90°).
- **Measured samples near the plane of incidence** (scattered measurements, instead of the
  slice): the samples within :data:`PLANE_TOLERANCE_DEG` of the plane, by θ_i and signed θ_o.
- **Polar plots** of the plane of incidence at θ_i = :data:`POLAR_INCIDENCE_DEG`
  (scattered: the nearest measured θ_i): L = (−sin θ_i, 0, cos θ_i), V = (sin θ_o, 0, cos θ_o)
  with signed θ_o (the mirror direction at θ_o = +θ_i); the BRDF (or the measured samples)
  and each fitted model.
- **Directional albedo** a(θ_v) = ∫ ρ(L, V) cos θ_i dω_i against θ_v (``checks.directional_albedo``:
  Gauss–Legendre in cos θ_i × midpoint in φ_i), of the BRDF (not of scattered measurements)
  and of each fit; energy conservation is a ≤ 1.
- **Lit sphere**: a unit sphere seen orthographically along −z (V = +z at every pixel) under
  one distant light L = :data:`SPHERE_LIGHT` of irradiance π at normal incidence, radiance
  ρ(L, V)·max(N·L, 0)·π in each pixel's tangent frame (so a white Lambertian surface facing
  the light has radiance 1), tone mapped by ``render.output.to_8bit`` (filmic, exposure 0).

:func:`live_views` builds the live WebGL2 preview of each environment's SHRM at the main
tolerance (``render.webgl_page``) for ``report.html``, within :data:`LIVE_VIEW_BUDGET_BYTES`
per view, with the report's sphere preview as the still image for browsers without WebGL2.

References
----------
B. Burley, "Physically-Based Shading at Disney", SIGGRAPH 2012 course notes (BRDF Explorer).
S. Rusinkiewicz, "A New Change of Variables for Efficient BRDF Representation", EGWR 1998,
doi:10.1007/978-3-7091-6453-2_2.
"""

from __future__ import annotations

import math
import re
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ...brdf_io.brdf import BRDF
from ...brdf_io.halfdiff import halfdiff_to_directions
from ...brdf_io.masked_grid import eval_with_mask
from ...render.output import to_8bit
from ...render.preview import PREVIEW_VIEW, PreviewImage
from ...render.webgl_page import ViewBudget, build_view, view_fragment
from .checks import directional_albedo
from .plots import image_row_plot

__all__ = [
    "SLICE_PHI_D_DEG", "SLICE_STEP_DEG", "POLAR_INCIDENCE_DEG", "POLAR_THETA_DEG", "ALBEDO_VIEWS_DEG",
    "PLANE_TOLERANCE_DEG", "MAX_SAMPLES", "SPHERE_SIZE", "SPHERE_LIGHT", "SPHERE_FILE", "LUMA",
    "LIVE_VIEW_BUDGET_BYTES", "ReportImage", "LiveView", "plane_directions", "halfdiff_slice",
    "lit_sphere", "explore", "live_views", "preview_view_angles",
]

#: φ_d of the image slice (BRDF Explorer's default: no cell below the surface).
SLICE_PHI_D_DEG = 90.0
#: Cell size of the θ_h × θ_d slice: 45 × 45 cells, centres at 1°, 3°, …, 89°.
SLICE_STEP_DEG = 2.0
#: θ_i of the polar plots.
POLAR_INCIDENCE_DEG = (0.0, 30.0, 60.0, 75.0)
#: Signed θ_o of the polar curves.
POLAR_THETA_DEG = np.arange(-87.5, 87.5 + 1e-9, 2.5)
#: θ_v of the directional-albedo curves.
ALBEDO_VIEWS_DEG = (*range(0, 90, 5), 88)
#: Scattered samples this close to the plane of incidence (azimuth) count as in the plane.
PLANE_TOLERANCE_DEG = 3.0
#: At most this many in-plane samples are stored (every k-th beyond it).
MAX_SAMPLES = 4000
#: Lit-sphere image size (pixels) and light direction (45° from the view, from the upper left).
SPHERE_SIZE = 128
SPHERE_LIGHT = (-0.5, 0.5, math.sqrt(0.5))
SPHERE_FILE = "explorer_sphere.png"
#: 8-bit grey behind the sphere (so that its unlit side is seen against it).
SPHERE_BACKGROUND = 48
#: Rec. 709 luminance weights.
LUMA = np.array([0.2126, 0.7152, 0.0722])
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


# ------------------------------------------------------------------------------ geometry


def plane_directions(theta_i_deg: float, theta_o_deg: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(L, V) in the plane of incidence: L = (−sin θ_i, 0, cos θ_i), V = (sin θ_o, 0, cos θ_o)."""
    ti = math.radians(theta_i_deg)
    to = np.radians(np.asarray(theta_o_deg, dtype=np.float64))
    V = np.stack([np.sin(to), np.zeros_like(to), np.cos(to)], axis=-1)
    L = np.broadcast_to(np.array([-math.sin(ti), 0.0, math.cos(ti)]), V.shape)
    return L, V


def _luma(rgb: np.ndarray) -> np.ndarray:
    return np.asarray(rgb, dtype=np.float64) @ LUMA


def _cell_centres(step: float) -> np.ndarray:
    n = int(round(90.0 / step))
    return (np.arange(n) + 0.5) * (90.0 / n)


def halfdiff_slice(brdf: BRDF, phi_d_deg: float = SLICE_PHI_D_DEG, step_deg: float = SLICE_STEP_DEG
                   ) -> dict[str, Any]:
    """ρ on the θ_h × θ_d grid at φ_d: ``theta_h_deg``, ``theta_d_deg`` (cell centres),
    ``rgb`` (n_h, n_d, 3), ``missing`` and ``below_surface`` (bool (n_h, n_d))."""
    th = _cell_centres(step_deg)
    td = _cell_centres(step_deg)
    L, V = halfdiff_to_directions(np.radians(th)[:, None], np.radians(td)[None, :], math.radians(phi_d_deg))
    rgb, has = eval_with_mask(brdf, L, V)
    below = (L[..., 2] <= 0) | (V[..., 2] <= 0)
    return {"theta_h_deg": th, "theta_d_deg": td, "rgb": np.asarray(rgb, dtype=np.float64),
            "missing": ~has & ~below, "below_surface": below}


def _grid_json(lum: np.ndarray, blank: np.ndarray) -> list[list[float | None]]:
    return [[None if b else float(v) for v, b in zip(row, brow, strict=True)] for row, brow in zip(lum, blank,
                                                                                                   strict=True)]


def _rgb_json(rgb: np.ndarray, has: np.ndarray | None = None) -> list[list[float] | None]:
    out: list[list[float] | None] = [list(map(float, v)) for v in np.asarray(rgb, dtype=np.float64)]
    if has is not None:
        out = [v if h else None for v, h in zip(out, has, strict=True)]
    return out


def lit_sphere(brdf: BRDF, size: int = SPHERE_SIZE, light: Sequence[float] = SPHERE_LIGHT
               ) -> tuple[np.ndarray, np.ndarray]:
    """Linear radiance (size, size, 3) of the unit sphere under one distant light, and the
    hit mask: orthographic view along −z (V = +z), pixel centres x = (2j+1)/size − 1,
    y = 1 − (2i+1)/size, N = (x, y, √(1 − x² − y²)); radiance = ρ(L, V)·max(N·L, 0)·π with
    L and V in the tangent frame (T = the part of V across N, B = N × T, N)."""
    Lw = np.asarray(light, dtype=np.float64)
    Lw = Lw / np.linalg.norm(Lw)
    c = (2.0 * np.arange(size) + 1.0) / size - 1.0
    x, y = np.meshgrid(c, -c)
    r2 = x * x + y * y
    hit = r2 < 1.0
    N = np.stack([x[hit], y[hit], np.sqrt(1.0 - r2[hit])], axis=-1)
    Vw = np.array([0.0, 0.0, 1.0])
    nv = N @ Vw
    T = Vw[None, :] - nv[:, None] * N
    tn = np.linalg.norm(T, axis=-1)
    # at the centre V = N: any tangent will do (isotropic BRDF)
    T = np.where(tn[:, None] > 1e-12, T / np.maximum(tn, 1e-300)[:, None], np.array([1.0, 0.0, 0.0]))
    B = np.cross(N, T)
    L = np.stack([T @ Lw, B @ Lw, N @ Lw], axis=-1)
    V = np.stack([T @ Vw, B @ Vw, nv], axis=-1)
    cos_i = np.maximum(L[:, 2], 0.0)
    radiance = np.zeros((size, size, 3))
    lit = cos_i > 0
    values = np.zeros((len(N), 3))
    if np.any(lit):
        values[lit] = np.asarray(brdf.eval(L[lit], V[lit]), dtype=np.float64) * (np.pi * cos_i[lit])[:, None]
    radiance[hit] = values
    return radiance, hit


# ------------------------------------------------------------------------------ explorer


def _scattered_plane(brdf: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(θ_i°, signed θ_o°, rgb) of the samples within PLANE_TOLERANCE_DEG of the plane of incidence
    (signed θ_o > 0 on the side of the mirror direction)."""
    L, V, rgb = np.asarray(brdf.L, float), np.asarray(brdf.V, float), np.asarray(brdf.rgb, float)
    dphi = np.arctan2(V[:, 1], V[:, 0]) - np.arctan2(L[:, 1], L[:, 0])
    theta_i = np.degrees(np.arccos(np.clip(L[:, 2], -1.0, 1.0)))
    theta_o = np.degrees(np.arccos(np.clip(V[:, 2], -1.0, 1.0)))
    # in the plane: Δφ near 0 (back towards the light) or near π (forward); at θ_o ≈ 0 the
    # azimuth does not matter
    in_plane = (np.abs(np.sin(dphi)) < math.sin(math.radians(PLANE_TOLERANCE_DEG))) | (theta_o < 0.5)
    signed = np.where(np.cos(dphi) < 0, theta_o, -theta_o)
    return theta_i[in_plane], signed[in_plane], rgb[in_plane]


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
    if scattered:
        ti_all, so_all, rgb_all = _scattered_plane(brdf)
        ti, so, rgb = ti_all, so_all, rgb_all
        order = np.lexsort((so, ti))
        ti, so, rgb = ti[order], so[order], rgb[order]
        n_total = len(ti)
        if n_total > MAX_SAMPLES:
            keep = np.arange(0, n_total, math.ceil(n_total / MAX_SAMPLES))
            ti, so, rgb = ti[keep], so[keep], rgb[keep]
        block["slice"] = None
        block["samples"] = {"max_off_plane_deg": PLANE_TOLERANCE_DEG, "n_in_plane": int(n_total),
                            "n_shown": int(len(ti)), "theta_i_deg": ti.tolist(), "theta_o_deg": so.tolist(),
                            "rgb": rgb.tolist()}
    else:
        s = halfdiff_slice(brdf)
        blank = s["missing"] | s["below_surface"]
        fitted: dict[str, Any] = {}
        for model, fb in fits:
            if fb is None:
                fitted[model] = None
            else:
                f = halfdiff_slice(fb)
                fitted[model] = _grid_json(_luma(f["rgb"]), f["below_surface"])
        block["slice"] = {
            "phi_d_deg": SLICE_PHI_D_DEG, "theta_h_deg": s["theta_h_deg"].tolist(),
            "theta_d_deg": s["theta_d_deg"].tolist(), "lum": _grid_json(_luma(s["rgb"]), blank),
            "missing": np.argwhere(s["missing"]).tolist(), "below_surface": np.argwhere(s["below_surface"]).tolist(),
            "n_missing": int(s["missing"].sum()), "fitted_lum": fitted,
        }
        block["samples"] = None

    # polar plots of the plane of incidence
    curves = []
    if scattered:
        theta_all = np.degrees(np.arccos(np.clip(np.asarray(brdf.L, float)[:, 2], -1.0, 1.0)))
        levels = np.unique(np.round(theta_all))
        incidence = sorted({float(levels[np.argmin(np.abs(levels - v))]) for v in POLAR_INCIDENCE_DEG})
    else:
        incidence = list(POLAR_INCIDENCE_DEG)
    for theta_i in incidence:
        L, V = plane_directions(theta_i, POLAR_THETA_DEG)
        curve: dict[str, Any] = {"theta_i_deg": theta_i}
        if scattered:
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
    block["polar"] = {"theta_o_deg": POLAR_THETA_DEG.tolist(), "curves": curves}

    # directional albedo against θ_v
    views = tuple(float(v) for v in ALBEDO_VIEWS_DEG)
    block["albedo"] = {
        "views_deg": list(views), "nodes": int(albedo_nodes),
        "measured_rgb": None if scattered else directional_albedo(brdf, views, nodes=albedo_nodes).tolist(),
        "fitted_rgb": {m: (None if fb is None else directional_albedo(fb, views, nodes=albedo_nodes).tolist())
                       for m, fb in fits},
    }

    # lit sphere: the BRDF (not scattered samples) and each fit
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
        files.append(ReportImage(SPHERE_FILE, image_row_plot(images, [e["label"] for e in entries])))
    block["sphere"] = {"file": SPHERE_FILE if images else None, "size": SPHERE_SIZE,
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
