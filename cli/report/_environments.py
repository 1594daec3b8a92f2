"""The environments' part of a report (stage 4 of ``collect.py``): for each environment map, the
brute-force reference at seeded (R, V) pairs (``analysis.reference``, [RH02] eq. 2), then one
prefilter per tolerance with its measured error overall and per view band beside the stated one,
as the ``environments`` entries and the ``speed_vs_error`` rows of ``report.json``.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable
from typing import Any

from ...analysis.compare import band_error, band_sample, beside_measured, pairs_per_band, relative_rms, sample_pairs
from ...analysis.lighting import lighting_coefficients
from ...analysis.orders import OrderChoice
from ...analysis.records import PrefilterInfo
from ...analysis.reference import reference_radiance
from ...analysis.shrm import SHRM, prefilter
from ...analysis.view_bands import DEFAULT_BAND_EDGES_DEG, worst_inside
from ...brdf_io.brdf import BRDF
from .options import ReportOptions, load_report_env

__all__ = ["unique_names"]

#: ``progress(stage)``: told the name of each stage as it starts
Progress = Callable[[str], None]


def _stage(progress: Progress | None, name: str) -> None:
    if progress is not None:
        progress(name)


def unique_names(names: list[str]) -> list[str]:
    """``names`` with repeats made unique by ``-2``, ``-3``… in order (report folders, and the
    environments of one report, whose names key the summary columns)."""
    out: list[str] = []
    for base in names:
        name, k = base, 2
        while name in out:
            name, k = f"{base}-{k}", k + 1
        out.append(name)
    return out


def _environments(brdf: BRDF, options: ReportOptions, choices: dict[float, OrderChoice], progress: Progress | None,
                  nthreads: int = 0):
    # the headline measured error: pairs inside the view limit (the sampler of `shrm compare`)
    R, V, _ = sample_pairs(options.n_pairs, seed=options.seed, max_view_deg=options.rule.max_view_deg)
    env_entries, main_shrms = [], []
    speed_rows: list[dict[str, Any]] = []
    envs = [load_report_env(spec, options) for spec in options.envs]
    names = unique_names([env.name for env in envs])
    for spec, env, name in zip(options.envs, envs, names, strict=True):
        if name != env.name:
            env = dataclasses.replace(env, name=name)
        _stage(progress, f"reference {env.name}")
        # per view band: pairs drawn per band, R importance-sampled from the map's bright pixels and
        # stratified, so the standard error matches the spread over seeds (analysis.compare.band_error)
        sample = band_sample(env.radiance, pairs_per_band(options.n_pairs, len(DEFAULT_BAND_EDGES_DEG) - 1),
                             DEFAULT_BAND_EDGES_DEG, seed=options.seed)
        t0, c0 = time.perf_counter(), time.thread_time()
        reference = reference_radiance(env, brdf, R, V)
        ref_seconds = time.perf_counter() - t0
        reference_b = reference_radiance(env, brdf, sample.R, sample.V)
        # the brute force's CPU per pair (this thread; both sets: every pair sums every pixel), the
        # speed-up's numerator: CPU time, unlike wall time, does not follow the machine's load
        ref_cpu_per_pair = (time.thread_time() - c0) / (len(R) + len(sample.R))
        lighting = lighting_coefficients(env.radiance, env.height - 1, name=env.name, nthreads=max(nthreads, 1))
        entry: dict[str, Any] = {
            "name": env.name,
            "spec": spec,
            "height": env.height,
            "width": env.width,
            "eps_L_curve": lighting.eps(),
            "reference_seconds": ref_seconds,
        }
        # the main tolerance last: its SHRM is kept (previews), so no other map is made beside it
        order = [t for t in options.all_tolerances if t != options.rule.eps] + [options.rule.eps]
        rows_before = len(speed_rows)
        for tol in order:
            _stage(progress, f"prefilter {env.name} eps={tol:g}")
            c0 = time.process_time()  # every thread of the process: the SHTs' too (an upper bound in a threaded batch)
            shrm = prefilter(env, brdf, rule=options.rule.replace(eps=tol), window=options.window, nthreads=nthreads,
                             orders=choices[tol], lights=options.lights)
            prefilter_cpu = time.process_time() - c0
            err = relative_rms(shrm.radiance(R, V), reference)  # clamped at 0, as rendered
            bands = beside_measured(band_error(shrm.radiance(sample.R, sample.V), reference_b, sample),
                                    [band.to_json() for band in shrm.info.view_bands])
            row = _speed_row(env.name, tol, shrm, bands, err, ref_seconds / options.n_pairs)
            row.update(prefilter_cpu_seconds=prefilter_cpu,
                       reference_map_cpu_seconds=ref_cpu_per_pair * (shrm.height * shrm.width))
            speed_rows.append(row)
            if tol == options.rule.eps:
                entry.update(_main_entry(row, shrm.info, options))
                main_shrms.append((env, shrm))
            del shrm
        speed_rows[rows_before:] = sorted(speed_rows[rows_before:],
                                          key=lambda r: options.all_tolerances.index(r["tolerance"]))
        env_entries.append(entry)
    return env_entries, speed_rows, main_shrms


def _speed_row(env_name: str, tol: float, shrm: SHRM, bands: list[dict], err: float,
               ref_seconds_per_pair: float) -> dict[str, Any]:
    """One row of the speed and accuracy table: the SHRM's orders, errors, window, budgets and stage
    timings (``SHRM.info``), beside the measured error ``err`` and the per-band records ``bands``."""
    info, eps = shrm.info, shrm.eps
    w, t = info.window, info.timings
    assert info.pixel_errors is not None  # a prefilter states them (only an old file's SHRM lacks them)
    return {
        "env": env_name, "tolerance": tol, "F_rho": info.F_rho, "P_rho": info.P_rho, "F_L": info.F_L,
        "F_B": shrm.F, "P_B": shrm.P, "size": [shrm.height, shrm.width],
        "eps_brdf": eps["brdf"], "eps_lighting": eps["lighting"], "eps_B": eps["reflected"], "bound": eps["bound"],
        "sqrt_eps_B": math.sqrt(max(eps["reflected"], 0.0)),
        "predicted_rel_rms": worst_inside(bands, "predicted_rel_rms"),
        "bound_rel_rms": worst_inside(bands, "bound_rel_rms"),
        "measured_rel_rms": err, **_worst_measured(bands), "view_bands": bands, "criterion": info.criterion,
        "window": w.used, "window_strength": w.strength, "window_reason": w.reason,
        "eps_B_unwindowed": w.eps_reflected_unwindowed, "negative_before": w.negative_before,
        "negative_after": w.negative_after, "negative_fraction_after": w.negative_fraction_after,
        "prefilter_seconds": t.total, "orders_seconds": t.orders, "lighting_seconds": t.lighting,
        "synthesis_seconds": t.synthesis, "window_seconds": t.window,
        "lights": len(info.lights), "capped": bool(info.capped), "capped_by": list(info.capped_by),
        "map_budget": info.map_budget,  # uninformative bounds said so (analysis/map_budget.py)
        # per direction (analysis/pixels.py): the estimate, and where the pixel rule took F_B from
        "pixel_median": info.pixel_errors["median"], "pixel_p90": info.pixel_errors["p90"],
        "pixel_F_from": (info.pixel_rule or {}).get("F_from"),
        "pixels_seconds": t.pixels if t.pixels is not None else 0.0,
        # the angular reference for the same S x 2S output, extrapolated from the pairs
        "reference_map_seconds": ref_seconds_per_pair * (shrm.height * shrm.width),
    }


def _worst_measured(bands: list[dict]) -> dict[str, float]:
    """The measured relative RMS of the worst band inside the view limit and its standard error:
    the measure a band's bound states (the all-pairs ``measured_rel_rms`` pools the bands)."""
    inside = [b for b in bands if b["inside"] and b.get("measured_rel_rms") is not None]
    if not inside:
        return {"measured_worst_band_rel_rms": math.nan, "measured_worst_band_stderr": math.nan}
    worst = max(inside, key=lambda b: b["measured_rel_rms"])
    return {"measured_worst_band_rel_rms": float(worst["measured_rel_rms"]),
            "measured_worst_band_stderr": float(worst["measured_stderr"])}


def _main_entry(row: dict[str, Any], info: PrefilterInfo, options: ReportOptions) -> dict[str, Any]:
    """The environment's entry at the main tolerance: ``row`` (:func:`_speed_row`) with the lights and
    the per-direction statement."""
    def pick(*keys: str) -> dict[str, Any]:
        return {key: row[key] for key in keys}

    return {
        **pick("tolerance", "F_L"), "lighting_capped": bool(info.lighting_capped),
        **pick("F_B", "P_B", "bound", "eps_B", "predicted_rel_rms", "bound_rel_rms", "view_bands",
               "measured_rel_rms", "measured_worst_band_rel_rms", "measured_worst_band_stderr", "window",
               "window_strength", "negative_after"),
        "lights": list(info.lights.lights), "lights_flux_share": info.lights.flux_share,
        **pick("capped", "capped_by", "map_budget"), "pixel_errors": info.pixel_errors,
        "pixel_rule": info.pixel_rule, "n_pairs": options.n_pairs, "max_view_deg": options.rule.max_view_deg,
    }


# ----------------------------------------------------------------------------- warnings
