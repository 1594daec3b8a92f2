"""Compute one BRDF's accuracy report as a JSON-able dict (``data_specs/report_json.md``).

Stages (each reported to the optional ``progress(stage)`` callback):

1. ``load``: ``shrmkit.load_brdf``.
2. ``fits``: ``shrmkit.fit_brdf`` for each model; errors per view-elevation band and
   measured-vs-fitted slices in the plane of incidence.
3. ``orders``: ``choose_orders`` at each tolerance ([RH02] §5.1) and the ε(F, P) table.
   Scattered measurements cannot be evaluated everywhere: the orders, SHRMs and previews
   of a scattered BRDF use its best successful fit (the report says which).
4. ``prefilter``: for each environment and tolerance, ``prefilter`` (orders, lighting SHT,
   SHRM synthesis, the window ``options.window`` against Gibbs ringing) and the relative RMS
   error of :meth:`SHRM.radiance` (clamped at 0, as rendered) against the
   angular-domain reference (``analysis.reference``, [RH02] eq. 2) on seeded random (R, V)
   pairs; the environment's F_L, the scene orders F_B, P_B and the residual bound
   (``analysis.scene``).
5. ``checks``: missing and clamped data, reciprocity, directional albedo (``checks.py``).
6. ``preview``: sphere (and mesh) thumbnails (``preview.py``).

Reproducibility: every random choice is seeded by ``options.seed``, floats are rounded
to 10 significant digits, and every field that depends on the machine's speed has a key
ending in ``_seconds`` (:func:`strip_timings` removes them), so the same inputs give the
same ``report.json`` apart from those keys.

Reference: [RH02] (``data_specs/bibliography.md``).
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from ..._version import __version__
from ...analysis.fit import FitResult, fit_brdf
from ...analysis.fit.representation import choose_representation
from ...analysis.orders import OrderChoice, choose_orders_many
from ...analysis.reciprocity import RECIPROCITY_TOLERANCE
from ...brdf_io.brdf import BRDF
from ...brdf_io.errors import BadInputError
from ...brdf_io.jsonutil import to_jsonable
from ...brdf_io.specs import load_brdf
from ...render.preview import PREVIEW_DISABLED, PreviewImage, render_previews, resolve_preview_mode
from ._environments import Progress, _environments, _stage, unique_names
from .checks import data_checks
from .explorer import LiveView, ReportImage, explore, live_views
from .options import ReportOptions
from .shared_state import OPENGL_LOCK

if TYPE_CHECKING:
    from ...brdf_io.cornell import ScatteredBRDF

__all__ = [
    "REPORT_FORMAT",
    "REPORT_FORMAT_VERSION",
    "SLICE_VIEWS_DEG",
    "collect_report",
    "unique_names",
    "failed_report",
    "REPORT_DIGITS",
    "strip_timings",
]

REPORT_FORMAT = "shrmkit-report"
REPORT_FORMAT_VERSION = 1
SLICE_VIEWS_DEG = (0.0, 30.0, 60.0, 75.0)
_SLICE_THETA_DEG = np.arange(-85.0, 85.0 + 1e-9, 2.5)
#: Significant digits of every float in report.json (``to_jsonable(..., digits=)``).
REPORT_DIGITS = 10

def strip_timings(doc: Any) -> Any:
    """A copy of ``doc`` without the timing fields (keys ending in ``_seconds``)."""
    if isinstance(doc, dict):
        return {k: strip_timings(v) for k, v in doc.items() if not str(k).endswith("_seconds")}
    if isinstance(doc, list):
        return [strip_timings(v) for v in doc]
    return doc


# ------------------------------------------------------------------------------- fits


def _fit_entry(result: Any) -> dict[str, Any]:
    return {
        "model": result.model,
        "spec": result.brdf.to_spec(),
        "params": result.params,
        "errors": dict(result.errors),
        "bands": [b.as_dict() for b in result.bands],
        "status": result.status,
        "success": bool(result.success),
        "converged": bool(result.converged),
        "usable": bool(result.usable),
        "worst_band": None if result.worst is None else result.worst.as_dict(),
        "at_bounds": list(result.at_bounds),
        "message": result.message,
        "evaluations": int(result.evaluations),
        "n_samples": int(result.n_samples),
        "n_dropped": int(result.n_dropped),
        "error": None,
        "fit_seconds": float(result.seconds),
    }


def _fits(brdf: BRDF, options: ReportOptions) -> tuple[list[dict[str, Any]], list[Any]]:
    entries: list[dict[str, Any]] = []
    results: list[FitResult | None] = []
    for model in options.models:
        t0 = time.perf_counter()
        try:
            result = fit_brdf(
                brdf, model, lobes=options.lobes, seed=options.seed, n_samples=options.fit_samples,
                starts=options.fit_starts,
            )
        except BadInputError as err:
            entries.append({"model": model, "success": False, "error": str(err),
                            "fit_seconds": time.perf_counter() - t0})
            results.append(None)
            continue
        entries.append(_fit_entry(result))
        results.append(result)
    return entries, results


def _plane_directions(theta_deg: np.ndarray) -> np.ndarray:
    t = np.radians(theta_deg)
    return np.stack([np.sin(t), np.zeros_like(t), np.cos(t)], axis=-1)


def _slices(brdf: BRDF, fitted: list[Any], models: tuple[str, ...]) -> dict[str, Any]:
    """ρ in the plane of incidence at a few view elevations: measured and each fitted model.

    V = (sin θ_o, 0, cos θ_o); L = (sin θ_i, 0, cos θ_i) with signed θ_i (the mirror
    direction is θ_i = −θ_o). For scattered data the "view" is the file's incident
    direction (reciprocity) and the measured points are those within 3° of the plane.
    """
    views = []
    if brdf.kind == "scattered":
        samples = cast("ScatteredBRDF", brdf)  # the BRDFs of kind "scattered" (duck-typed by kind)
        theta_i = np.degrees(np.arccos(np.clip(samples.L[:, 2], -1, 1)))
        levels = np.unique(np.round(theta_i))
        chosen = sorted({float(levels[np.argmin(np.abs(levels - v))]) for v in SLICE_VIEWS_DEG})
        for view in chosen:
            sel = np.abs(theta_i - view) < 0.5
            L, V, rgb = samples.L[sel], samples.V[sel], samples.rgb[sel]
            dphi = np.arctan2(V[:, 1], V[:, 0]) - np.arctan2(L[:, 1], L[:, 0])
            in_plane = np.abs(np.sin(dphi)) < np.sin(np.radians(3.0))
            signed = np.degrees(np.arccos(np.clip(V[in_plane, 2], -1, 1))) * np.sign(np.cos(dphi[in_plane]))
            order = np.argsort(signed, kind="stable")
            views.append({
                "view_deg": view,
                "measured_theta_deg": signed[order].tolist(),
                "measured_rgb": rgb[in_plane][order].tolist(),
                "fitted_rgb": {m: (None if f is None else f.brdf.eval(
                    _plane_directions(_SLICE_THETA_DEG), _plane_directions(np.full_like(_SLICE_THETA_DEG, view))
                ).tolist()) for m, f in zip(models, fitted, strict=True)},
            })
        return {"theta_deg": _SLICE_THETA_DEG.tolist(), "views": views,
                "measured": "scattered samples within 3 deg of the plane"}
    L = _plane_directions(_SLICE_THETA_DEG)
    for view in SLICE_VIEWS_DEG:
        V = np.broadcast_to(_plane_directions(np.array([view]))[0], L.shape)
        views.append({
            "view_deg": view,
            "measured_theta_deg": _SLICE_THETA_DEG.tolist(),
            "measured_rgb": brdf.eval(L, V).tolist(),
            "fitted_rgb": {m: (None if f is None else f.brdf.eval(L, V).tolist())
                           for m, f in zip(models, fitted, strict=True)},
        })
    return {"theta_deg": _SLICE_THETA_DEG.tolist(), "views": views, "measured": "brdf evaluated on the slice"}


# ------------------------------------------------------------------------------ orders


def _orders(brdf: BRDF, options: ReportOptions) -> tuple[list[dict[str, Any]], dict[str, Any], list[OrderChoice]]:
    rows = []
    # one search per tolerance on shared quadrature grids; prefilter reuses each choice
    choices = choose_orders_many(brdf, options.all_tolerances, rule=options.rule)
    for tol, choice in zip(options.all_tolerances, choices, strict=True):
        rows.append({
            "tolerance": tol,
            "F": choice.F,
            "P": choice.P,
            "eps": choice.eps,
            "eps_rh02": choice.eps_rh02,
            "criterion": choice.criterion,
            "max_view_deg": choice.max_view_deg,
            "view_bands": choice.view_bands(),
            "capped": bool(choice.capped),
            "converged": bool(choice.converged),
            "n_without_data": int(choice.n_without_data),
            "message": choice.message,
            "orders_seconds": choice.seconds,
        })
    # the tightest tolerance has the largest grid; keep F up to a little beyond the largest choice, and
    # P up to four beyond it (each column of the bands rule is a view fit: the rest are not computed)
    finest = choices[-1]
    F_keep = int(min(finest.F0, max(2 * max(c.F for c in choices) + 8, 32)))
    P_keep = int(min(finest.P0, max(c.P for c in choices) + 4))
    source = finest.source
    assert source is not None  # choose_orders keeps its grid data
    table = np.stack([finest.searched_table[: F_keep + 1, p] if not np.isnan(finest.searched_table[0, p])
                      else source.column(p)[: F_keep + 1] for p in range(P_keep + 1)], axis=1)
    eps_table = {"tolerance": finest.tolerance, "F0": finest.F0, "P0": finest.P0, "eps": table}
    return rows, eps_table, choices


# --------------------------------------------------------------------------- prefilter


def _warnings(checks: dict[str, Any], orders: list[dict[str, Any]], fits: list[dict[str, Any]],
              preview_notes: list[str], analysis_note: str) -> list[dict[str, str]]:
    out = []

    def add(code: str, message: str) -> None:
        out.append({"code": code, "message": message})

    reachable = checks["n_missing_above_surface"]
    if reachable if reachable is not None else checks["n_missing"]:
        n = reachable if reachable is not None else checks["n_missing"]
        add("missing_measurements", f"{n} table samples above the surface are missing (no measurement)")
    without = max((o["n_without_data"] for o in orders), default=0)
    if without:
        add("missing_measurements", f"{without} reparameterized samples had no measurement to interpolate (set to 0)")
    dropped = max((f.get("n_dropped", 0) or 0 for f in fits), default=0)
    if dropped:
        add("missing_measurements", f"{dropped} fit samples dropped for lack of data")
    if checks["n_clamped"]:
        add("clamped_values", f"{checks['n_clamped']} RGB components were negative (out of gamut) and clamped to 0")
    rec = checks["reciprocity"]
    if rec["max_rel"] is not None and rec["max_rel"] > RECIPROCITY_TOLERANCE:
        add("non_reciprocal", f"rho(L,V) != rho(V,L): max relative difference {rec['max_rel']:.3g} "
            f"({rec['method']}, {rec['n_pairs']} pairs)")
    albedo = checks["albedo"]
    if albedo["max"] > 1.0 + 1e-3:
        add("energy_gain", f"directional albedo {albedo['max']:.3g} > 1 at view {albedo['max_view_deg']:g} deg "
            f"(of the {albedo['of']})")
    for o in orders:
        if o["capped"]:
            add("orders_capped", f"eps {o['tolerance']:g}: not met within the caps F<={o['F']}, P<={o['P']} "
                f"(eps(F, P) = {o['eps']:.3g}); raise max_F/max_P")
        elif not o["converged"]:
            add("orders_not_converged", f"eps {o['tolerance']:g}: {o['message']}")
    for f in fits:
        if f.get("error"):
            add("fit_failed", f"{f['model']}: {f['error']}")
        elif not f["success"]:
            add("fit_failed", f"{f['model']}: {f['message']}")
    for note in preview_notes:
        add("preview", note)
    if analysis_note:
        add("analysis_on_fit", analysis_note)
    return out


# ------------------------------------------------------------------------------ report


def _analysis_brdf(brdf: BRDF, fit_entries: list[dict[str, Any]],
                   fit_results: list[Any]) -> tuple[BRDF, str, str, dict[str, Any] | None]:
    if brdf.kind != "scattered":
        return brdf, "brdf", "", None
    # the representation with the smallest held-out worst-band error (Lafortune, Cook–Torrance or the
    # cross-validated Zernike expansion; analysis.fit.representation), reusing the report's one-lobe fits
    reuse = {r.model: r for r in fit_results if r is not None and r.options.get("lobes") in (None, 1)
             and r.options.get("metric") == "rel"}
    choice = choose_representation(brdf, fits=reuse)
    record = {k: v for k, v in choice.as_dict().items() if k != "seconds"} | {"choice_seconds": choice.seconds}
    note = f"scattered measurements: orders, SHRMs and previews are {choice.line()}"
    return choice.brdf, f"fit:{choice.model}", note, record


def _preview(main: tuple[Any, Any], options: ReportOptions,
             preview_mode: str | None) -> tuple[list[PreviewImage], dict[str, Any]]:
    """The previews of the main tolerance's first SHRM and the report's ``preview`` block; a failed
    preview is noted there (the report is kept)."""
    mode, mode_note = (preview_mode, "") if preview_mode else resolve_preview_mode(options.preview)
    env0, shrm0 = main
    t0 = time.perf_counter()
    try:
        with OPENGL_LOCK:  # one offscreen context at a time per process (shared_state module)
            previews, notes = render_previews(shrm0, env0, mode=mode, size=options.preview_size, mesh=options.mesh)
        preview_error = None
    except Exception as err:  # a failed preview must not lose the report
        previews, notes, preview_error = [], [f"preview failed: {err}"], str(err)
    return previews, {
        "mode": mode,
        "env": env0.name,
        "tolerance": options.rule.eps,
        "F": shrm0.F,
        "P": shrm0.P,
        "images": [{"key": p.key, "file": f"preview_{p.key}.png", "renderer": p.renderer} for p in previews],
        "notes": ([mode_note] if mode_note else []) + notes,
        "error": preview_error,
        "preview_seconds": time.perf_counter() - t0,
    }


def collect_report(
    source: str | Path,
    options: ReportOptions,
    *,
    name: str | None = None,
    preview_mode: str | None = None,
    progress: Progress | None = None,
    nthreads: int = 0,
) -> tuple[dict[str, Any], list[PreviewImage | ReportImage | LiveView]]:
    """Compute the report of one BRDF.

    Parameters
    ----------
    source
        BRDF file or spec string (``shrmkit.load_brdf``).
    options
        :class:`~shrmkit.cli.report.options.ReportOptions`.
    name
        Report name (default: the BRDF's name).
    preview_mode
        ``gl``, ``cpu`` or ``none``; default ``options.preview`` resolved by probing
        (``preview.resolve_preview_mode``) — pass it resolved when running many reports.
    progress
        Optional ``progress(stage: str)``.
    nthreads
        ducc0 threads of the SHTs (``prefilter``'s ``nthreads``; 0: every core). A worker of a
        batch passes its share of the cores (``threads.py``); the numbers do not depend on it.

    Returns
    -------
    (doc, previews)
        The ``report.json`` document (JSON types) and the preview images.

    Raises
    ------
    BadInputError
        Unreadable BRDF, or nothing to analyse.
    """

    t_start = time.perf_counter()
    _stage(progress, "load")
    brdf = load_brdf(source)
    _stage(progress, "fits")
    fit_entries, fit_results = _fits(brdf, options)
    slices = _slices(brdf, fit_results, options.models)
    explorer, explorer_images = explore(brdf, fit_results, options.models, albedo_nodes=options.albedo_nodes)
    analysed, analysis_of, analysis_note, representation = _analysis_brdf(brdf, fit_entries, fit_results)
    _stage(progress, "orders")
    order_rows, eps_table, choices = _orders(analysed, options)
    by_tolerance = dict(zip(options.all_tolerances, choices, strict=True))
    main_choice = by_tolerance[options.rule.eps]
    env_entries, speed_rows, main_shrms = _environments(analysed, options, by_tolerance, progress, nthreads)
    main_orders = {"tolerance": options.rule.eps, "F": main_choice.F, "P": main_choice.P, "eps": main_choice.eps}
    # the order searches' quadrature grids (their view profiles) are not read after this: let them go before
    # the preview's OpenGL context (~190 MB) is made (RGL iris: 16 MB less at the preview, measured)
    del choices, by_tolerance, main_choice
    _stage(progress, "checks")
    checks = data_checks(brdf, analysed, seed=options.seed, albedo_nodes=options.albedo_nodes)
    _stage(progress, "preview")
    previews, preview_block = _preview(main_shrms[0], options, preview_mode)
    live, views = live_views(main_shrms, previews, preview_mode=preview_block["mode"],
                             preview_size=options.preview_size)
    doc = {
        "format": REPORT_FORMAT,
        "format_version": REPORT_FORMAT_VERSION,
        "status": "ok",
        "name": name or brdf.name,
        "source": str(source),
        "brdf": {"name": brdf.name, "kind": brdf.kind, "analysis_of": analysis_of, "representation": representation},
        "options": options.as_dict(),
        "orders": order_rows,
        "main": main_orders,
        "eps_table": eps_table,
        "environments": env_entries,
        "speed_vs_error": speed_rows,
        "fits": fit_entries,
        "fit_slices": slices,
        "explorer": explorer,
        "data_checks": checks,
        "warnings": _warnings(checks, order_rows, fit_entries,
                              [n for n in preview_block["notes"] if n != PREVIEW_DISABLED], analysis_note),
        "preview": preview_block,
        "live_preview": live,
        "error": None,
        "provenance": {"shrmkit_version": __version__, "numpy_version": np.__version__},
        "total_seconds": time.perf_counter() - t_start,
    }
    return to_jsonable(doc, digits=REPORT_DIGITS), [*previews, *explorer_images, *views]


def failed_report(source: str | Path, name: str, options: ReportOptions, error: str,
                  seconds: float = 0.0) -> dict[str, Any]:
    """The ``report.json`` of a BRDF whose report could not be made (``status: failed``)."""
    return to_jsonable({
        "format": REPORT_FORMAT,
        "format_version": REPORT_FORMAT_VERSION,
        "status": "failed",
        "name": name,
        "source": str(source),
        "options": options.as_dict(),
        "error": error,
        "provenance": {"shrmkit_version": __version__, "numpy_version": np.__version__},
        "total_seconds": seconds,
    }, digits=REPORT_DIGITS)
