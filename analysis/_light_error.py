"""The error statement of merged lights: per band of θ_v, the energy of the median-cut samples'
error against one sample per pixel, over the signal's (:func:`merge_error_by_band`), estimated on
(R, V) pairs focused on the lights. Public through :mod:`shrmkit.analysis.lights`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..brdf_io.brdf import BRDF
from ._light_set import Extraction, light_radiance
from .pairs import sample_pairs_focused

#: (R, V) pairs per view band on which :func:`merge_error_by_band` measures the signal (the SHRM part).
MERGE_PAIRS_PER_BAND = 48
#: Pairs per view band for the merge error itself (the lights alone: cheap per pair).
MERGE_ERROR_PAIRS_PER_BAND = 128


def merge_error_by_band(
    extraction: Extraction, brdf: BRDF, shrm_part: Any, edges_deg: Any, *, whole: Any = None,
    per_band: int = MERGE_PAIRS_PER_BAND, error_per_band: int = MERGE_ERROR_PAIRS_PER_BAND, seed: int = 0,
) -> tuple[np.ndarray, np.ndarray]:
    """Per band of θ_v: the energy of the merged samples' error (against one sample per pixel) over
    the energy of ``shrm_part`` (the SHRM's reflection of the residual map) and of ``whole`` (that
    plus the lights; callables (R, V) -> (n, 3)): two (n_bands,) arrays, zeros when nothing was
    merged. The same relative measures as the per-band statements they are added to.

    Both energies are uniform-R means over each band, estimated with importance weights on (R, V)
    pairs focused on lights (:func:`~shrmkit.analysis.pairs.sample_pairs_focused`): the error on
    ``error_per_band`` pairs per band about the merged lights (only their samples and pixels are
    evaluated there, the others cancel exactly: cheap per pair), the signal on ``per_band`` other
    pairs about every light (an SHRM evaluation each). Under a sharp lobe the error lives in a small part of
    (R, V) space: with the error on the signal's 48 pairs a band (issue 23's matrix, three lamps at
    128 rows) the stated error was 10⁻²¹ at 60–70° for Phong s = 512 and 0.06–0.5 × a 72 000-pair
    measurement at 70–90° for microfacet σ = 0.05 and GGX α = 0.1 (``tests/analysis/test_lights_matrix.py``)."""
    n_bands = len(edges_deg) - 1
    if not extraction.merged:
        return np.zeros(n_bands), np.zeros(n_bands)
    merged, exact = extraction.lights, extraction.exact
    assert exact is not None  # extraction.merged: the one-sample-per-pixel lights are kept
    which = [k for k, light in enumerate(merged.lights) if light.merge_deg > 0.0]
    edges = np.radians(np.asarray(edges_deg, dtype=np.float64))

    def pairs(count: int, seed_: int, lights: list[int]) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        centres = np.array([merged.lights[k].direction for k in lights])
        weights = np.array([max(float(np.sum(merged.lights[k].power)), 1e-300) for k in lights])
        R, V, theta_v, w = sample_pairs_focused(count, edges_deg, centre=centres, centre_weights=weights, seed=seed_)
        return R, V, w, np.clip(np.searchsorted(edges, theta_v, side="right") - 1, 0, n_bands - 1)

    def mean_by_band(values: np.ndarray, w: np.ndarray, band: np.ndarray) -> np.ndarray:
        return np.bincount(band, weights=w * values, minlength=n_bands) / np.maximum(
            np.bincount(band, minlength=n_bands), 1)

    R, V, w, band = pairs(error_per_band, seed + 1, which)  # where the merge moved flux
    mine_m, mine_e = np.isin(merged.light, which), np.isin(exact.light, which)
    diff = light_radiance(brdf, merged.directions[mine_m], merged.power[mine_m], R, V) - \
        light_radiance(brdf, exact.directions[mine_e], exact.power[mine_e], R, V)
    num = mean_by_band((diff**2).sum(axis=1), w, band)
    R, V, w, band = pairs(per_band, seed, list(range(len(merged.lights))))  # where the signal is

    def ratio(signal_of: Any) -> np.ndarray:
        den = mean_by_band((np.asarray(signal_of(R, V), dtype=np.float64) ** 2).sum(axis=1), w, band)
        return np.where(den > 0, num / np.where(den > 0, den, 1.0), np.where(num > 0, np.inf, 0.0))

    return ratio(shrm_part), ratio(whole if whole is not None else shrm_part)
