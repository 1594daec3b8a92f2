"""The cost estimate of a report task, cheap and rough, only used to start the costly BRDFs of
a batch first (:func:`largest_first`, every engine).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ...brdf_io.specs import load_brdf
from ._task import ReportTask


def _lobe_sharpness(brdf: Any) -> list[float]:
    """Peak over mean of the cosine-weighted transfer ρ̂(·, V) over the incident hemisphere at
    the views θ_v = 0°, 35°, 70° (about s + 2 at every view for a Phong lobe cos^s, 2 for
    Lambert; growing with θ_v for a microfacet lobe, which stretches at grazing views)."""
    n = 30
    theta = (np.arange(n) + 0.5) * (np.pi / 2) / n
    phi = (np.arange(4 * n) + 0.5) * (2 * np.pi) / (4 * n)
    t, p = np.meshgrid(theta, phi, indexing="ij")
    L = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], axis=-1)
    weight = np.sin(t) * (np.pi / 2 / n) * (2 * np.pi / (4 * n)) / (2 * np.pi)
    out = []
    for view in np.radians([0.0, 35.0, 70.0]):
        V = np.array([np.sin(view), 0.0, np.cos(view)])
        mirror = np.array([[-V[0], 0.0, V[2]]])
        grid = brdf.rho_hat(L, np.broadcast_to(V, L.shape)).mean(axis=-1)
        peak = max(float(grid.max()), float(brdf.rho_hat(mirror, V[None]).mean()))
        mean = float((grid * weight).sum())
        out.append(max(2.0, peak / mean) if mean > 0.0 and math.isfinite(peak) else 2.0)
    return out


#: estimated seconds per MB of a table file (a MERL table of 35 MB: 5 + 10.5 s)
_TABLE_SECONDS_PER_MB = 0.3


def estimate_cost(source: str) -> float:
    """A rough, cheap estimate of a report's cost (about the seconds of a quick report on one
    core), only used to start the costly BRDFs first.

    A table file (``.binary``, ``.npz``, ``.brdf``; not read): 5 + 0.3 s per MB (a MERL table
    ≈ 15.5). An analytic BRDF (a spec, or a fitted model's ``.json``): the orders P grow with
    the change of the lobe with the view and F with the square root of its sharpness
    (:func:`_lobe_sharpness`), so 5 + 2.5·sqrt(max sharpness)·max(0, ln(s70/s0) − 0.1): a
    Phong or Lafortune lobe, the same at every view, costs about 5 whatever its exponent, a
    microfacet lobe more the sharper it is (on 32 BRDFs the rank correlation with the
    measured time was 0.81–0.87, ``benchmarks/batch_scaling.py``). A source that cannot be read
    costs 0 (its report fails at once).
    """
    path = Path(source)
    try:
        if path.suffix.lower() in (".binary", ".npz", ".brdf") and path.is_file():
            return 5.0 + _TABLE_SECONDS_PER_MB * path.stat().st_size / 1e6
        brdf = load_brdf(source)
        if brdf.kind != "analytic":  # pragma: no cover - every table suffix is handled above
            return 5.0 + _TABLE_SECONDS_PER_MB * path.stat().st_size / 1e6
        s = _lobe_sharpness(brdf)
        return 5.0 + 2.5 * math.sqrt(max(s)) * max(0.0, math.log(s[-1] / s[0]) - 0.1)
    except Exception:  # a bad BRDF: its report fails fast, whatever its place
        return 0.0


def largest_first(tasks: Sequence[ReportTask]) -> list[ReportTask]:
    """``tasks`` by decreasing :func:`estimate_cost` (input order among equals)."""
    costs = [estimate_cost(t.source) for t in tasks]
    order = sorted(range(len(tasks)), key=lambda i: -costs[i])
    return [tasks[i] for i in order]

