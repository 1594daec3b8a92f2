"""``compare``: every representation against the angular reference, as one JSON-able table.

For each representation of :mod:`.representations` the table holds the relative RMS radiance
error against the brute-force angular integral (:func:`~shrmkit.analysis.reference.reference_radiance`,
RH02 eq. 2) on sampled (R, V) pairs (:func:`.pairs.sample_pairs`, grazing views included),

    rel_rms = sqrt(Σ_pairs,rgb (B − B_ref)² / Σ_pairs,rgb B_ref²),

the same restricted to grazing views (θ_v > 70°) and to views below 45°, storage in bytes,
precompute seconds, per-frame update seconds (distant viewer) and CPU evaluation cost per
(R, V) pair. See ``data_specs/compare_json.md`` for the dictionary's layout.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..._version import __version__
from ...brdf_io.errors import BadInputError
from ..reference import reference_radiance
from .pairs import sample_pairs
from .representations import build_representations

__all__ = ["compare", "relative_rms", "table_markdown", "GRAZING_DEG", "DEFAULT_ENV_HEIGHT"]

GRAZING_DEG = 70.0
DEFAULT_ENV_HEIGHT = 64


def relative_rms(value: np.ndarray, reference: np.ndarray) -> float:
    """sqrt(Σ (value − reference)² / Σ reference²) over all entries (NaN if the reference is 0)."""
    den = float(np.sum(np.asarray(reference, float) ** 2))
    if den == 0.0:
        return float("nan")
    return float(np.sqrt(np.sum((np.asarray(value, float) - reference) ** 2) / den))


def _load_inputs(brdf: Any, env: Any, env_height: int | None) -> tuple[Any, Any]:
    from ...brdf_io.envmap import EnvironmentMap, load_env
    from ...brdf_io.specs import load_brdf

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


def compare(
    brdf: Any,
    env: Any,
    *,
    eps: float = 0.03,
    env_height: int | None = DEFAULT_ENV_HEIGHT,
    n_pairs: int = 2000,
    max_view_deg: float = 88.0,
    seed: int = 0,
    lower_P: int | None = None,
    lobes: Sequence[int] = (1, 2, 3, 4),
    n_elevations: int = 15,
    cabral_reference_height: int | None = 32,
    strip: str | Path | None = None,
    strip_size: int = 64,
    mesh: Any = None,
    progress: Callable[[str], None] | None = None,
) -> dict[str, Any]:
    """Compare the SHRM with Kautz–McCool, Cabral et al. and Green et al. (issue 7).

    Parameters
    ----------
    brdf
        BRDF object, spec string or file (a scattered one must be fitted first).
    env
        EnvironmentMap, spec or file (load y-up files with ``load_env`` yourself).
    eps
        SHRM tolerance (orders chosen by RH02's rule).
    env_height
        The environment is area-resampled to this many rows first (the angular reference
        costs O(W S_L²) per value); None keeps it.
    n_pairs, max_view_deg, seed
        Error sample: :func:`.pairs.sample_pairs`.
    lower_P, lobes, n_elevations, cabral_reference_height
        Passed to :func:`.representations.build_representations`.
    strip
        If given, write the side-by-side image strip (:func:`.strip.write_strip`) there.
    strip_size, mesh
        Panel size in pixels and an optional mesh (default: a sphere) for the strip.
    progress
        ``progress(stage)`` callback.

    Returns
    -------
    dict
        JSON-able: ``brdf``, ``environment``, ``eps``, ``n_pairs``, ``reference`` (timings),
        ``rows`` (one dict per representation), ``markdown`` (a table for reports),
        ``strip`` (path and per-panel errors, when written). Layout: ``data_specs/compare_json.md``.
    """
    if not (np.isfinite(eps) and 0.0 < eps < 1.0):
        raise BadInputError(None, f"eps must be in (0, 1), got {eps}")
    if n_pairs < 10:
        raise BadInputError(None, f"n_pairs must be at least 10, got {n_pairs}")
    brdf, env = _load_inputs(brdf, env, env_height)

    def stage(name: str) -> None:
        if progress is not None:
            progress(name)

    R, V, theta_v = sample_pairs(n_pairs, seed=seed, max_view_deg=max_view_deg)
    stage("angular reference")
    t0 = time.perf_counter()
    ref = reference_radiance(env, brdf, R, V)
    t_ref = time.perf_counter() - t0
    reps = build_representations(env, brdf, eps, lower_P=lower_P, lobes=lobes, n_elevations=n_elevations,
                                 cabral_reference_height=cabral_reference_height, progress=progress)
    grazing = theta_v > np.radians(GRAZING_DEG)
    frontal = theta_v < np.radians(45.0)
    rows = []
    for rep in reps:
        stage(f"error: {rep.label}")
        t0 = time.perf_counter()
        pred = rep.radiance(R, V)
        t_eval = time.perf_counter() - t0
        rows.append({
            "key": rep.key,
            "label": rep.label,
            "rel_rms": relative_rms(pred, ref),
            "rel_rms_grazing": relative_rms(pred[grazing], ref[grazing]),
            "rel_rms_frontal": relative_rms(pred[frontal], ref[frontal]),
            "storage_bytes": rep.storage_bytes,
            "precompute_s": rep.precompute_s,
            "update_s": rep.update_s,
            "eval_us_per_pair": 1e6 * t_eval / n_pairs,
            "params": rep.params,
        })
    result: dict[str, Any] = {
        "brdf": brdf.name,
        "environment": f"{env.name} ({env.height}x{env.width})",
        "eps": float(eps),
        "n_pairs": int(n_pairs),
        "max_view_deg": float(max_view_deg),
        "grazing_deg": GRAZING_DEG,
        "seed": int(seed),
        "reference": {"seconds": t_ref, "us_per_pair": 1e6 * t_ref / n_pairs},
        "rows": rows,
        "shrmkit_version": __version__,
    }
    if strip is not None:
        from ...render.strip import write_strip

        stage("image strip")
        result["strip"] = write_strip(strip, reps, env, brdf, size=strip_size, mesh=mesh)
    result["markdown"] = table_markdown(result)
    return result


def _fmt_bytes(n: int) -> str:
    return f"{n / 1e6:.2f} MB" if n >= 1e5 else f"{n / 1e3:.1f} kB"


def table_markdown(result: dict[str, Any]) -> str:
    """The comparison as a Markdown table (the section ``shrm report`` can include)."""
    lines = [
        f"Comparison for {result['brdf']} under {result['environment']} (eps {result['eps']:g}, "
        f"{result['n_pairs']} (R, V) pairs, views up to {result['max_view_deg']:g} deg; reference "
        f"{result['reference']['seconds']:.2f} s)",
        "",
        "| representation | rel RMS | grazing (>70 deg) | <45 deg | storage | precompute s | update ms | eval us |",
        "|---|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for r in result["rows"]:
        lines.append(
            f"| {r['label']} | {r['rel_rms']:.4f} | {r['rel_rms_grazing']:.4f} | {r['rel_rms_frontal']:.4f} | "
            f"{_fmt_bytes(r['storage_bytes'])} | {r['precompute_s']:.3f} | {1e3 * r['update_s']:.3f} | "
            f"{r['eval_us_per_pair']:.1f} |"
        )
    return "\n".join(lines) + "\n"
