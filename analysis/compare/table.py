"""``compare``: every representation against the angular reference, as one JSON-able table.

For each representation of :mod:`.registry` the table holds the relative RMS radiance error
(:func:`.metrics.relative_rms`) against the brute-force angular integral
(:func:`~shrmkit.analysis.reference.reference_radiance`, [RH02] eq. 2) on sampled (R, V) pairs
(:func:`.pairs.sample_pairs`, grazing views included), over all pairs, grazing views
(θ_v > 70°) and views below 45°, with storage in bytes, precompute seconds, per-frame update
seconds (distant viewer) and CPU evaluation cost per (R, V) pair. See
``data_specs/compare_json.md`` for the dictionary's layout.

This module computes numbers only. The side-by-side image strip is the render layer's:
:func:`compare_representations` returns the built representations with the table so that
``shrmkit.render.strip.write_strip`` draws them without a second build.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..._version import __version__
from ...brdf_io.brdf import BRDF
from ...brdf_io.envmap import EnvironmentMap, load_env
from ...brdf_io.errors import BadInputError
from ...brdf_io.specs import load_brdf
from ..reference import reference_radiance
from ..view_bands import DEFAULT_BAND_EDGES_DEG
from .band_error import band_error, band_sample, pairs_per_band
from .metrics import beside_measured, relative_rms
from .options import CompareOptions
from .pairs import sample_pairs
from .registry import build_representations, deprecated_row_key
from .representation import Representation

__all__ = ["Comparison", "compare", "compare_representations", "table_markdown", "GRAZING_DEG", "FRONTAL_DEG"]

#: Views with θ_v above this many degrees count as grazing (``rel_rms_grazing``).
GRAZING_DEG = 70.0
#: Views with θ_v below this many degrees count as frontal (``rel_rms_frontal``).
FRONTAL_DEG = 45.0

_MOVED_TO_RENDER = ("strip", "strip_size", "mesh")


@dataclass(frozen=True, eq=False)
class Comparison:
    """The outcome of :func:`compare_representations`.

    Attributes
    ----------
    result
        The JSON-able table (``data_specs/compare_json.md``), without ``strip``.
    representations
        The built :class:`~.representation.Representation` objects, in row order.
    brdf, env
        The inputs as evaluated (loaded; the environment resampled to ``env_height``): pass
        these to ``write_strip`` so that the strip shows what the table measured.
    """

    result: dict[str, Any]
    representations: tuple[Representation, ...]
    brdf: BRDF
    env: EnvironmentMap


def _load_inputs(brdf: Any, env: Any, env_height: int | None) -> tuple[BRDF, EnvironmentMap]:
    if isinstance(brdf, str | Path):
        brdf = load_brdf(brdf)
    if brdf.kind == "scattered":
        raise BadInputError(brdf.name, "scattered measurements cannot be evaluated everywhere: fit a model first "
                                       "(shrm fit) and compare the fit")
    if not isinstance(env, EnvironmentMap):
        env = load_env(env)
    if env_height is not None and env.height > env_height:
        env = env.resized(int(env_height), 2 * int(env_height))
    return brdf, env


def compare_representations(
    brdf: Any,
    env: Any,
    options: CompareOptions | None = None,
    *,
    progress: Callable[[str], None] | None = None,
) -> Comparison:
    """Compare the SHRM with Kautz–McCool, Cabral et al. and Green et al.; keep what was built.

    The numbers-only core of :func:`compare` (``brdf``, ``env``, ``progress`` as there), with
    the options as one :class:`~.options.CompareOptions` (default: all defaults). The caller
    may draw the image strip from the returned representations without a second build:
    ``shrmkit.render.strip.write_comparison_strip(comparison, path)`` returns the table with
    its ``strip`` entry.
    """
    options = CompareOptions() if options is None else options
    brdf, env = _load_inputs(brdf, env, options.env_height)

    def stage(name: str) -> None:
        if progress is not None:
            progress(name)

    n = options.n_pairs
    R, V, theta_v = sample_pairs(n, seed=options.seed, max_view_deg=options.sample_max_view_deg)
    stage("angular reference")
    t0 = time.perf_counter()
    ref = reference_radiance(env, brdf, R, V)
    t_ref = time.perf_counter() - t0
    # per view band: pairs drawn per band, R importance-sampled from the map's bright pixels and
    # stratified, with a standard error that matches the spread over seeds (.band_error, issue 29)
    per_band = pairs_per_band(n, len(DEFAULT_BAND_EDGES_DEG) - 1)
    sample = band_sample(env.radiance, per_band, DEFAULT_BAND_EDGES_DEG, seed=options.seed)
    ref_b = reference_radiance(env, brdf, sample.R, sample.V)
    reps = tuple(build_representations(env, brdf, options, progress=progress))
    grazing = theta_v > np.radians(GRAZING_DEG)
    frontal = theta_v < np.radians(FRONTAL_DEG)
    rows = []
    for rep in reps:
        stage(f"error: {rep.label}")
        t0 = time.perf_counter()
        pred = rep.radiance(R, V)
        t_eval = time.perf_counter() - t0
        measured = band_error(rep.radiance(sample.R, sample.V), ref_b, sample)
        bands = beside_measured(measured, rep.params.get("view_bands"))  # an SHRM's statement too
        rows.append({
            "key": rep.key, **deprecated_row_key(rep.key),  # earlier key, one release (compare_json.md)
            "label": rep.label,
            "rel_rms": relative_rms(pred, ref),
            "rel_rms_grazing": relative_rms(pred[grazing], ref[grazing]),
            "rel_rms_frontal": relative_rms(pred[frontal], ref[frontal]),
            "storage_bytes": int(rep.storage_bytes),
            "precompute_s": float(rep.precompute_s),
            "update_s": float(rep.update_s),
            "eval_us_per_pair": 1e6 * t_eval / n,
            "params": {k: v for k, v in rep.params.items() if k != "view_bands"},
            "view_bands": bands,
        })
    result: dict[str, Any] = {
        "brdf": brdf.name,
        "environment": f"{env.name} ({env.height}x{env.width})",
        "eps": options.eps,
        "window": options.window,
        "criterion": options.criterion,
        "rule_max_view_deg": options.rule_max_view_deg,
        "n_pairs": int(n),
        "band_pairs_per_band": int(per_band),
        "max_view_deg": float(options.sample_max_view_deg),  # the sampling range (compare_json.md)
        "grazing_deg": GRAZING_DEG,
        "seed": int(options.seed),
        "reference": {"seconds": t_ref, "us_per_pair": 1e6 * t_ref / n},
        "rows": rows,
        "shrmkit_version": __version__,
    }
    result["markdown"] = table_markdown(result)
    return Comparison(result, reps, brdf, env)


def compare(brdf: Any, env: Any, *, progress: Callable[[str], None] | None = None, **options: Any) -> dict[str, Any]:
    """Compare the SHRM [RH02] with Kautz–McCool [KM00], RSIBR [Cabral99] and Gaussian lobes
    [Green07] against the angular reference: the JSON-able table only.

    Parameters
    ----------
    brdf
        BRDF object, spec string or file (a scattered one must be fitted first).
    env
        EnvironmentMap, spec or file (load y-up files with ``load_env`` yourself).
    progress
        ``progress(stage)`` callback.
    **options
        Keyword-only fields of :class:`~.options.CompareOptions`: ``eps`` (default
        ``DEFAULT_EPS``, checked by ``check_eps``), ``env_height``, ``n_pairs``,
        ``max_view_deg``, ``seed``, ``lower_P``, ``lobes``, ``elevations``,
        ``rsibr_reference_height``, ``update_view``, ``window`` (``"auto"``, ``"lanczos"`` or
        ``"none"``: the SHRMs' window against Gibbs ringing).

    The image strip is not written here any more (this layer computes numbers only):
    ``strip``, ``strip_size`` and ``mesh`` raise ``TypeError``. To get the strip, call
    :func:`compare_representations` and pass its ``representations``, ``env`` and ``brdf`` to
    ``shrmkit.render.strip.write_strip(path, ..., size=strip_size, mesh=mesh)``, as
    ``shrm compare --strip`` does.

    Returns
    -------
    dict
        JSON-able: ``brdf``, ``environment``, ``eps``, ``window``, ``n_pairs``, ``reference`` (timings),
        ``rows`` (one dict per representation), ``markdown`` (a table for reports). Layout:
        ``data_specs/compare_json.md``.

    Raises
    ------
    BadInputError
        Invalid options (ε outside (0, 1), n_pairs < 10, …), unreadable inputs, scattered
        measurements.
    TypeError
        An unknown option, or one of the strip options that moved to the render layer.
    """
    moved = [name for name in _MOVED_TO_RENDER if name in options]
    if moved:
        raise TypeError(f"compare() no longer draws the image strip ({', '.join(moved)}): call "
                        "compare_representations() and shrmkit.render.strip.write_strip() with its "
                        "representations, env and brdf")
    return compare_representations(brdf, env, CompareOptions(**options), progress=progress).result


def _fmt_bytes(n: int) -> str:
    return f"{n / 1e6:.2f} MB" if n >= 1e5 else f"{n / 1e3:.1f} kB"


def table_markdown(result: dict[str, Any]) -> str:
    """The comparison as a Markdown table (the section ``shrm report`` can include)."""
    lines = [
        f"Comparison for {result['brdf']} under {result['environment']} (eps {result['eps']:g}, "
        f"{result['n_pairs']} (R, V) pairs, views up to {result['max_view_deg']:g} deg; reference "
        f"{result['reference']['seconds']:.2f} s)",
        "",
        f"| representation | rel RMS | grazing (>{GRAZING_DEG:g} deg) | <{FRONTAL_DEG:g} deg | storage | precompute s "
        "| update ms | eval us |",
        "|---|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for r in result["rows"]:
        lines.append(
            f"| {r['label']} | {r['rel_rms']:.4f} | {r['rel_rms_grazing']:.4f} | {r['rel_rms_frontal']:.4f} | "
            f"{_fmt_bytes(r['storage_bytes'])} | {r['precompute_s']:.3f} | {1e3 * r['update_s']:.3f} | "
            f"{r['eval_us_per_pair']:.1f} |"
        )
    for r in result["rows"]:
        if r.get("view_bands") and "predicted_rel_rms" in r["view_bands"][0]:
            lines += ["", f"{r['label']} by view band θ_v (predicted and bound: `SHRM.meta[\"view_bands\"]`; measured "
                      "± its standard error on the pairs of the band; * beyond the order rule's view limit):", "",
                      "| θ_v (deg) | predicted rel RMS | bound rel RMS | measured rel RMS | pairs |",
                      "|---|---:|---:|---:|---:|"]
            for b in r["view_bands"]:
                lo, hi = b["theta_v_deg"]
                star = "" if b["inside"] else " *"
                lines.append(f"| {lo:g}–{hi:g}{star} | {b['predicted_rel_rms']:.4f} | {b['bound_rel_rms']:.4f} | "
                             f"{b['measured_rel_rms']:.4f} ± {b['measured_stderr']:.4f} | {b['n_pairs']} |")
            break
    return "\n".join(lines) + "\n"
