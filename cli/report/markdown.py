"""``report.md``: a BRDF report as Markdown tables, linking the PNG files beside it.

The text is built from ``report.json`` alone; :func:`report_sections` yields the
(title, Markdown body) pairs that ``html.py`` renders too, so both say the same.

Reference: [RH02] (``data_specs/bibliography.md``).
"""

from __future__ import annotations

import re
from collections.abc import Iterator, Sequence
from typing import Any

from ...analysis.fit.summary import FIT_FAIL_BAND_REL_RMS
from .plot_names import PLOT_TITLES, plots_wanted

__all__ = ["fmt", "md_table", "report_sections", "report_markdown", "LIVE_VIEW_MARK", "live_view_mark"]

#: A line ``<!-- live-view ID -->``: where report.html puts the live preview ID (invisible in report.md).
LIVE_VIEW_MARK = re.compile(r"<!-- live-view ([A-Za-z][A-Za-z0-9_-]{0,63}) -->")


def live_view_mark(element_id: str) -> str:
    """The Markdown line that marks where the live preview ``element_id`` goes."""
    return f"<!-- live-view {element_id} -->"


def fmt(value: Any, digits: int = 3) -> str:
    """A number for a table: ``digits`` significant digits, ``—`` for missing."""
    if value is None:
        return "—"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        return f"{value:.{digits}g}"
    if isinstance(value, list | tuple):
        return "×".join(fmt(v, digits) for v in value)
    return str(value).replace("|", "\\|").replace("\n", " ")


def md_table(header: Sequence[str], rows: Sequence[Sequence[Any]]) -> str:
    """A GitHub-flavoured Markdown table."""
    lines = ["| " + " | ".join(fmt(h) for h in header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(fmt(v) for v in row) + " |" for row in rows]
    return "\n".join(lines)


def _band_note(band: dict) -> str:
    """"stated" beyond the view limit; "extrapolated" where measurements were missing."""
    notes = [] if band.get("inside", True) else ["stated"]
    if band.get("extrapolated_samples"):
        notes.append(f"extrapolated ({band['extrapolated_samples']} samples without data)")
    return ", ".join(notes)


def _window_text(row: dict) -> str:
    """``lanczos ×0.94 (1.6% → 0.096%)``: the window of a speed_vs_error row."""
    before = row.get("negative_before")
    change = f"{row['negative_after']:.2%}" if before is None else f"{before:.2%} → {row['negative_after']:.2%}"
    name = row["window"] if row["window"] == "none" else f"{row['window']} ×{row['window_strength']:.2f}"
    return f"{name} ({change})"


def _params_text(params: Any) -> str:
    if isinstance(params, dict):
        return ", ".join(f"{k}={_params_text(v)}" for k, v in params.items())
    if isinstance(params, list):
        if all(isinstance(v, int | float) for v in params):
            return "/".join(fmt(v, 4) for v in params)
        return "[" + "; ".join(_params_text(v) for v in params) + "]"
    return fmt(params, 4)


def representation_error(rep: dict[str, Any] | None) -> str:
    """``": zernike order 6 (30 terms, ridge 1e-06), held-out worst view band rel. RMS **0.2** (70–80°)"``
    (``FAILED`` above 0.5) for a report's ``brdf.representation``; "" without one."""
    if not rep:
        return ""
    band = rep.get("held_out_worst_band")
    err = (f"**{fmt(band['rel_rms'])}** ({band['lo_deg']:g}–{band['hi_deg']:g}°)" if band
           else f"**{fmt(rep['held_out_rel_rms'])}** (all views)")
    return f": {rep['label']}, held-out worst view band rel. RMS {err}" + ("" if rep["success"] else ", FAILED")


def report_sections(doc: dict[str, Any], image_link: Any = None) -> Iterator[tuple[str, str]]:
    """(section title, Markdown body) pairs of a report.

    ``image_link(key, file, alt)`` returns the Markdown (or HTML) of an image; the default
    links ``file`` beside the report.
    """
    image = image_link or (lambda key, file, alt: f"![{alt}]({file})")
    wanted = plots_wanted(doc)

    def link(key: str, file: str, alt: str) -> str:
        """The image, or nothing for a plot that was not drawn (``plots``, ``explorer_plots``)."""
        return image(key, file, alt) if key in wanted or key not in PLOT_TITLES else ""

    if doc["status"] != "ok":
        yield "Failed", f"The report of `{doc['source']}` could not be made:\n\n```\n{doc.get('error')}\n```"
        return
    yield "Summary", _summary_body(doc)
    # the preview next, on the first screen with the answer (issue 26), before the tables behind it
    yield "Preview", _preview_body(doc, link)
    yield "Data warnings", _warnings_body(doc)
    yield "Orders (RH02 §5.1)", _orders_body(doc, link)
    yield "Environments", _environments_body(doc)
    yield "Speed against error", _speed_body(doc, link)
    yield "Fits", _fits_body(doc, link)
    yield "Data checks", _data_checks_body(doc)
    explorer = doc.get("explorer")
    if explorer:
        yield "BRDF Explorer views", _explorer_body(doc, explorer, link)


def _summary_body(doc: dict[str, Any]) -> str:
    """The answer first: source, main (F, P), each scene's and each fit's headline, the run's profile."""
    drawn = doc.get("options", {}).get("plots", True)
    explorer_drawn = doc.get("options", {}).get("explorer_plots", True)
    b = doc["brdf"]
    head = [f"Source: `{doc['source']}` ({b['kind']}); main tolerance ε = {fmt(doc['main']['tolerance'])}: "
            f"**F = {doc['main']['F']}, P = {doc['main']['P']}** (ε(F, P) = {fmt(doc['main']['eps'])})."]
    if b["analysis_of"] != "brdf":
        head.append(f"Orders, SHRMs and previews use `{b['analysis_of']}` (scattered measurements)"
                    + representation_error(b.get("representation")) + ".")
    head += [_scene_headline(doc, e) for e in doc["environments"]]
    fit_lines = [_fit_headline(f) for f in doc["fits"]]
    if fit_lines:
        head.append("Fits (worst view band first): " + "; ".join(fit_lines) + ".")
    head.append(f"Profile `{doc['options']['profile']}`, seed {doc['options']['seed']}, "
                f"shrmkit {doc['provenance']['shrmkit_version']}; total {fmt(doc.get('total_seconds'))} s."
                + ("" if drawn else " Plots not drawn (--no-plots): every number is in the tables and report.json.")
                + (" The BRDF views' plots (fit slices, BRDF Explorer) were not drawn (quick profile; "
                   "--explorer-plots draws them): their numbers are in report.json." if drawn and not explorer_drawn
                   else ""))
    return "\n\n".join(head)


def _preview_body(doc: dict[str, Any], link: Any) -> str:
    """The live previews (report.html), the still images and the preview's notes."""
    p = doc["preview"]
    parts = _live_parts(doc.get("live_preview"))
    parts += [f"{img['key']} ({img['renderer']}, ε = {fmt(p['tolerance'])}, F = {p['F']}, P = {p['P']}, "
              f"environment {p['env']}):\n\n" + link(f"preview_{img['key']}", img["file"], f"preview {img['key']}")
              for img in p["images"]]
    parts += [f"- {n}" for n in p["notes"]]
    return "\n\n".join(parts) if parts else "No preview."


def _warnings_body(doc: dict[str, Any]) -> str:
    """One bullet per data warning, or the sentence saying the data passed every check."""
    if doc["warnings"]:
        return "\n".join(f"- **{w['code']}**: {w['message']}" for w in doc["warnings"])
    return "None: no missing or clamped data, reciprocal, directional albedo ≤ 1."


def _orders_body(doc: dict[str, Any], link: Any) -> str:
    """The (F, P) table per tolerance, the main tolerance's view bands and the order plots."""
    rows = [[o["tolerance"], o["F"], o["P"], o["eps"], o.get("eps_rh02", o["eps"]), o["capped"], o["converged"],
             o["orders_seconds"]] for o in doc["orders"]]
    body = md_table(["tolerance", "F", "P", "ε(F, P)", "ε RH02", "capped", "converged", "time (s)"], rows)
    main_orders = next((o for o in doc["orders"] if o["tolerance"] == doc["main"]["tolerance"]), None)
    if main_orders and main_orders.get("view_bands"):
        body += _orders_view_bands(main_orders)
    body += "\n\n" + link("energy", "plot_energy.png", PLOT_TITLES["energy"])
    body += "\n\n" + link("accuracy_by_p", "plot_accuracy_by_p.png", PLOT_TITLES["accuracy_by_p"])
    return body


def _orders_view_bands(main_orders: dict[str, Any]) -> str:
    """The order rule in words and ε by view band at the main (F, P), under a point light."""
    text = ("\n\nRule: " + ("every view band θ_v that starts below "
            f"{fmt(main_orders['max_view_deg'])}° meets ε under a point light (ε is the worst band's)"
            if main_orders["criterion"] == "bands" else "RH02 §5.1, energy over all views") + ". By view band "
            f"at (F, P) = ({main_orders['F']}, {main_orders['P']}), under a point light "
            "(the hardest lighting: its relative RMS is √ε; a scene's is stated under Environments):\n\n")
    return text + md_table(["θ_v (°)", "ε", "point-light rel. RMS (√ε)", "note"], [
        [f"{b['theta_v_deg'][0]:g}–{b['theta_v_deg'][1]:g}", b["eps"], b["rel_rms_point_light"],
         _band_note(b)] for b in main_orders["view_bands"]])


def _environments_body(doc: dict[str, Any]) -> str:
    """Each scene's orders (F_L, F_B, P_B), predicted, bound and measured errors, and its view bands."""
    rows = [[e["name"], f"{e['height']}×{e['width']}", f"≥ {e['F_L']}" if e.get("lighting_capped") else e["F_L"],
             e["F_B"], e["P_B"], e["eps_B"], e.get("predicted_rel_rms"), e.get("bound_rel_rms"),
             e.get("measured_worst_band_rel_rms"), e.get("measured_worst_band_stderr"), e["measured_rel_rms"],
             e["n_pairs"]] for e in doc["environments"]]
    body = (f"At ε = {fmt(doc['main']['tolerance'])}: F_L is the lighting's own order; F_B the scene's order "
            "(with the bands rule: the smallest F whose reflected field meets ε in every view band inside the "
            "limit; with RH02's: min(F_ρ, F_L)), P_B = P_ρ; ε_B the predicted relative energy error of the "
            "reflected light field over all views. Predicted and bound are relative RMS errors (the same units as "
            "the measured one) of the worst view band inside the view limit "
            f"({fmt(doc['environments'][0].get('max_view_deg', 80.0)) if doc['environments'] else '80'}°); the "
            "measured errors are the relative RMS of the SHRM against brute-force angular integration: in the worst "
            "band (± its standard error), the measure the bound states, and on random (R, V) pairs inside the limit "
            "pooled over the bands (which can exceed a band's bound where bands differ). Maps are resampled to the "
            "size shown (`--env-height`; "
            "the angular reference costs O(W·S_L²)), so `shrm orders --env` and `shrm prefilter` on the full-size "
            "file can give another F_L and bound; \"≥ F_L\": ε_L stays above the tolerance up to the largest "
            "degree computed.\n\n")
    body += md_table(["environment", "size", "F_L", "F_B", "P_B", "ε_B", "predicted rel. RMS", "bound rel. RMS",
                      "measured rel. RMS (worst band)", "± s.e.", "measured rel. RMS (all pairs)", "pairs"], rows)
    for e in doc["environments"]:
        if e.get("view_bands"):
            body += _environment_view_bands(e)
    return body


def _environment_view_bands(e: dict[str, Any]) -> str:
    """One scene's predicted, bound and measured relative RMS by view band."""
    return (f"\n\n**{e['name']}** by view band (measured: relative RMS ± its standard error on the pairs of "
            "the band; \"stated\": beyond the view limit, errors stated, not promised):\n\n") + md_table(
        ["θ_v (°)", "predicted rel. RMS", "bound rel. RMS", "measured rel. RMS", "± s.e.", "pairs", "note"], [
            [f"{b['theta_v_deg'][0]:g}–{b['theta_v_deg'][1]:g}", b["predicted_rel_rms"], b["bound_rel_rms"],
             b["measured_rel_rms"], b["measured_stderr"], b["n_pairs"], _band_note(b)] for b in e["view_bands"]])


def _speed_up(row: dict[str, Any]) -> float:
    """Brute force's CPU time over the prefilter's for the same map (the wall times' ratio for a
    report written before CPU times were recorded): CPU time does not follow the machine's load."""
    if row.get("prefilter_cpu_seconds") and row.get("reference_map_cpu_seconds") is not None:
        return row["reference_map_cpu_seconds"] / row["prefilter_cpu_seconds"]
    return row["reference_map_seconds"] / max(row["prefilter_seconds"], 1e-12)


def _speed_body(doc: dict[str, Any], link: Any) -> str:
    """Prefilter time against the angular reference's, with each row's error and window."""
    rows = [[r["env"], r["tolerance"], r["F_B"], r["P_B"], r["size"], _window_text(r), r["eps_B"],
             r.get("predicted_rel_rms"), r.get("bound_rel_rms"), r["measured_rel_rms"], r.get("pixel_p90"),
             r["prefilter_seconds"] * 1e3,
             r["reference_map_seconds"], _speed_up(r)]
            for r in doc["speed_vs_error"]]
    body = md_table(["env", "ε", "F_B", "P_B", "SHRM size", "window", "ε_B", "predicted rel. RMS",
                     "bound rel. RMS", "measured rel. RMS", "per-pixel p90 (est.)",
                     "prefilter (ms)", "angular (s, extrapolated)", "speed-up (CPU)"], rows)
    body += ("\n\nPrefilter time = order choice + lighting SHT + SHRM synthesis (+ the window's measurement and "
             "synthesis). The angular-domain time is the reference's time on the random pairs, extrapolated to the "
             "same S×2S output. Speed-up: the ratio of the two CPU times (the prefilter's in every thread), which, "
             "unlike the wall times, does not follow the machine's load. Window: the Lanczos strength the prefilter "
             "applied against Gibbs ringing and the "
             "undershoot (most negative radiance / peak) before → after it; ε_B includes the window's cost, and "
             "what undershoot is left is clamped to 0. Per-pixel p90: the 90th percentile of the relative error "
             "per direction, estimated on a sample against a higher order (the pixel rule keeps it within √ε).")
    body += "\n\n" + link("speed_error", "plot_speed_error.png", PLOT_TITLES["speed_error"])
    return body


def _fit_row(f: dict[str, Any]) -> list[Any]:
    """One fitted model's row: spec, worst view band, overall errors, verdict, nlopt's stop, time."""
    if f.get("error"):
        return [f["model"], "failed: " + f["error"], None, None, None, None, "FAILED", None, f["fit_seconds"]]
    band = f.get("worst_band")
    return [f["model"], f["spec"], band["rel_rms"] if band else None,
            f"{band['lo_deg']:g}–{band['hi_deg']:g}°" if band else None, f["errors"].get("rel_rms"),
            f["errors"].get("log_rms"), "ok" if f["success"] else "FAILED", f["status"], f["fit_seconds"]]


def _fits_body(doc: dict[str, Any], link: Any) -> str:
    """The fits' table and failure rule, their parameters (those at a bound), errors by band and plots."""
    body = md_table(["model", "fitted spec", "worst band rel. RMS", "worst band", "rel. RMS (all)", "log RMS",
                     "verdict", "nlopt stop", "time (s)"], [_fit_row(f) for f in doc["fits"]])
    body += (f"\n\nA fit FAILS when its relative RMS error passes {fmt(FIT_FAIL_BAND_REL_RMS)} in any view band "
             "(of 10 samples or more): the model does not represent the material there, whatever its average. "
             "nlopt's stop reason says how the search ended, not whether the fit is good.")
    params = [f"- {f['model']}: {_params_text(f['params'])}" for f in doc["fits"] if not f.get("error")]
    if params:
        body += "\n\nParameters:\n\n" + "\n".join(params)
    bounds = [f"- {f['model']}: " + "; ".join(f["at_bounds"]) for f in doc["fits"] if f.get("at_bounds")]
    if bounds:
        body += "\n\nParameters at a bound of the search (the best the model allows, not a fit of the data):\n\n"
        body += "\n".join(bounds)
    band_rows = [[f["model"], f"{b['lo_deg']:g}–{b['hi_deg']:g}°", b["n"], b["rel_rms"], b["log_rms"]]
                 for f in doc["fits"] for b in f.get("bands") or []]
    if band_rows:
        body += "\n\nError by view-elevation band:\n\n" + md_table(["model", "θ_o band", "samples", "rel. RMS",
                                                                     "log RMS"], band_rows)
        body += "\n\n" + link("fit_bands", "plot_fit_bands.png", PLOT_TITLES["fit_bands"])
    body += "\n\n" + link("fit_slices", "plot_fit_slices.png", PLOT_TITLES["fit_slices"])
    return body


def _data_checks_body(doc: dict[str, Any]) -> str:
    """Missing and clamped samples, reciprocity and directional albedo per view."""
    c = doc["data_checks"]
    rec = c["reciprocity"]
    a = c["albedo"]
    missing = c["n_missing"] if c["n_missing_above_surface"] is None else (
        f"{c['n_missing']} ({c['n_missing_above_surface']} above the surface)")
    rows = [["missing table samples", missing], ["clamped components", c["n_clamped"]],
            ["reciprocity: max relative difference",
             f"{fmt(rec['max_rel'])} ({rec['method']}, {rec['n_pairs']} pairs)"],
            ["reciprocity: per-pair |ρ(L,V) − ρ(V,L)| / mean, median / 90th percentile",
             f"{fmt(rec.get('median_pair_rel'))} / {fmt(rec.get('p90_pair_rel'))}"],
            ["max directional albedo", f"{fmt(a['max'])} at θ_o = {a['max_view_deg']:g}° (of the {a['of']})"]]
    body = md_table(["check", "result"], rows)
    body += "\n\nDirectional albedo per view (RGB): " + "; ".join(
        f"{v:g}°: {'/'.join(fmt(x) for x in rgb)}" for v, rgb in zip(a["views_deg"], a["rgb"], strict=True))
    return body



def _live_parts(live: dict[str, Any] | None) -> list[str]:
    """The live previews (report.html only): one sentence and the mark per view, and the notes."""
    if not live:
        return []
    parts = []
    for v in live["views"]:
        maps = f"maps {v['maps'][0]}×{v['maps'][1]}"
        if v["maps"] != v["source_maps"] or v["P"] != v["source_P"]:
            maps += (f" (reduced from {v['source_maps'][0]}×{v['source_maps'][1]}, P = {v['source_P']}, to fit "
                     f"{live['budget_bytes'] / 2**20:g} MiB: estimated added error {fmt(100 * v['added_rel_rms'], 2)} "
                     "% relative RMS)")
        parts.append(f"**Live preview** under {v['env']} (WebGL2 in report.html: drag to orbit, wheel to zoom, "
                     f"double-click to reset; F = {v['F']}, P = {v['P']}, {maps}; without WebGL2 the still image "
                     f"`{v['still']}` is shown):")
        parts.append(live_view_mark(v["element_id"]))
    parts += [f"- {n}" for n in live["notes"]]
    return parts


def _explorer_body(doc: dict[str, Any], e: dict[str, Any], link: Any) -> str:
    """The BRDF Explorer section (``explorer.py``): slice or samples, polar plots, albedo, lit spheres."""
    parts = [f"The views could not be made: `{e['error']}`"] if e.get("error") else []
    options = doc.get("options", {})
    if options.get("plots", True) and not options.get("explorer_plots", True):
        parts.append("The plots of these views were not drawn (quick profile; `--explorer-plots` draws them): "
                     "what they show is in report.json's `explorer` block.")
    scattered = e["of"] == "measured samples"
    fits = ", ".join(f["model"] for f in doc["fits"] if not f.get("error")) or "none"
    if e.get("slice"):
        s = e["slice"]
        parts.append(f"Image slice: log10 of ρ's luminance (Rec. 709) on θ_h × θ_d (Rusinkiewicz half/difference "
                     f"angles, {len(s['theta_h_deg'])} × {len(s['theta_d_deg'])} cells) at φ_d = "
                     f"{fmt(s['phi_d_deg'])}°, the BRDF and each fit ({fits}) on one colour scale; magenta: no "
                     f"measurement ({s['n_missing']} cells), grey: L or V below the surface "
                     f"({len(s['below_surface'])} cells).")
        parts.append(link("explorer_slice", "plot_explorer_slice.png", PLOT_TITLES["explorer_slice"]))
    if e.get("samples"):
        s = e["samples"]
        parts.append(f"Scattered measurements, so no slice: the {s['n_in_plane']} samples within "
                     f"{fmt(s['max_off_plane_deg'])}° of the plane of incidence ({s['n_shown']} shown) by θ_i and "
                     "signed θ_o (> 0 on the mirror side).")
        parts.append(link("explorer_samples", "plot_explorer_samples.png", PLOT_TITLES["explorer_samples"]))
    if e.get("polar", {}).get("curves"):
        incidences = ", ".join(f"{fmt(c['theta_i_deg'])}°" for c in e["polar"]["curves"])
        parts.append(f"Polar plots of the plane of incidence at θ_i = {incidences}: angle = signed θ_o from the "
                     "normal (the mirror direction on the right, the light dashed), radius = log10 of ρ's "
                     "luminance; " + ("the measured samples" if scattered else "the BRDF") + " and each fit.")
        parts.append(link("explorer_polar", "plot_explorer_polar.png", PLOT_TITLES["explorer_polar"]))
    a = e.get("albedo")
    if a:
        rows = []
        series = ([("brdf", a["measured_rgb"])] if a["measured_rgb"] is not None else []) + [
            (m, v) for m, v in a["fitted_rgb"].items() if v is not None]
        for label, rgb in series:
            worst = max(range(len(rgb)), key=lambda k: max(rgb[k]))
            rows.append([label, "/".join(fmt(x) for x in rgb[0]), max(rgb[worst]), a["views_deg"][worst],
                         "yes" if max(rgb[worst]) <= 1.0 + 1e-3 else "no"])
        parts.append("Directional albedo a(θ_v) = ∫ ρ(L, V) cos θ_i dω_i against the view angle "
                     f"({a['nodes']} Gauss–Legendre nodes in cos θ_i); energy conservation is a ≤ 1"
                     + (" (measured samples cannot be integrated: the fits only)." if scattered else "."))
        parts.append(md_table(["of", "a(0°) RGB", "max channel", "at θ_v (°)", "≤ 1"], rows))
        parts.append(link("explorer_albedo", "plot_explorer_albedo.png", PLOT_TITLES["explorer_albedo"]))
    sp = e.get("sphere")
    if sp and sp.get("file"):
        light = sp["light"]
        parts.append(f"Lit sphere: one distant light L = ({', '.join(fmt(x) for x in light)}) (45° from the view, "
                     "upper left), orthographic view along −z, radiance ρ(L, V)·cos θ_i·π (a white Lambertian "
                     "surface facing the light is 1), filmic tone map; "
                     + ", ".join(f"{i['label']} (peak luminance {fmt(i['max_lum'])})" for i in sp["images"]) + ".")
        parts.append(link("explorer_sphere", sp["file"], "Lit sphere under one distant light"))
    return "\n\n".join(parts)


def _scene_headline(doc: dict[str, Any], env: dict[str, Any]) -> str:
    """One environment in the summary's first lines: the scene's orders, the worst view band's error
    stated and measured, and the prefilter's time beside brute force's for the same map."""
    tol = doc["main"]["tolerance"]
    row: dict[str, Any] = next(
        (r for r in doc.get("speed_vs_error", []) if r["env"] == env["name"] and r["tolerance"] == tol), {})
    line = (f"Under **{env['name']}** ({env['height']}×{env['width']}), ε = {fmt(tol)}: F_B = {env['F_B']}, "
            f"P_B = {env['P_B']}; worst view band relative RMS predicted {fmt(env.get('predicted_rel_rms'))}, "
            f"bound {fmt(env.get('bound_rel_rms'))}, ")
    if env.get("measured_worst_band_rel_rms") is not None:  # the same measure as the bound: the worst band's
        line += (f"**measured {fmt(env['measured_worst_band_rel_rms'])} ± {fmt(env['measured_worst_band_stderr'])}** "
                 f"(the worst band measured; all {env['n_pairs']} pairs pooled: {fmt(env['measured_rel_rms'])})")
    else:
        line += f"**measured {fmt(env['measured_rel_rms'])}** ({env['n_pairs']} pairs)"
    if row.get("prefilter_cpu_seconds") and row.get("reference_map_cpu_seconds") is not None:
        line += (f"; prefilter {fmt(row['prefilter_cpu_seconds'])} s CPU against ≈ "
                 f"{fmt(row['reference_map_cpu_seconds'])} s CPU for brute-force angular integration of the same "
                 f"map ({fmt(_speed_up(row))}× less CPU)")
    elif row.get("prefilter_seconds") is not None and row.get("reference_map_seconds"):
        line += (f"; prefilter {fmt(row['prefilter_seconds'])} s against ≈ {fmt(row['reference_map_seconds'])} s "
                 f"for brute-force angular integration of the same map ({fmt(_speed_up(row))}× faster)")
    return line + "."


def _fit_headline(f: dict[str, Any]) -> str:
    """One fit in the summary's first lines: its worst view band, its error over all samples, its verdict."""
    if f.get("error"):
        return f"{f['model']} FAILED ({f['error']})"
    band = f.get("worst_band")
    worst = (f"{fmt(band['rel_rms'])} in {band['lo_deg']:g}–{band['hi_deg']:g}°, " if band else "")
    return (f"{f['model']} {'ok' if f['success'] else '**FAILED**'} (rel. RMS {worst}"
            f"{fmt(f['errors'].get('rel_rms'))} over all samples)")


def report_markdown(doc: dict[str, Any]) -> str:
    """The whole ``report.md``."""
    out = [f"# BRDF report: {doc['name']}", ""]
    for title, body in report_sections(doc):
        out += [f"## {title}", "", body, ""]
    return "\n".join(out)
