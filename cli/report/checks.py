"""The ``data_checks`` block of a BRDF's report: missing data, clamped values, reciprocity, energy.

- *Missing measurements*: table samples marked missing (MERL negative values; those above the
  surface, ``brdf_io.merl.merl_missing_above_surface``), and the reparameterized / fit samples that
  had no data to interpolate.
- *Clamped values*: components clipped on input (Cornell spectral → sRGB gives negative
  out-of-gamut components, clipped to 0 by ``brdf_io.cornell``).
- *Reciprocity*: ``analysis.reciprocity`` (seeded random pairs, or swapped measured configurations).
- *Energy*: the directional albedo (``analysis.albedo``) at :data:`ALBEDO_CHECK_VIEWS_DEG` must not
  exceed 1.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, cast

import numpy as np

from ...analysis.albedo import ALBEDO_CHECK_VIEWS_DEG, directional_albedo
from ...analysis.reciprocity import reciprocity_check, scattered_reciprocity
from ...brdf_io.brdf import BRDF
from ...brdf_io.merl import merl_missing_above_surface

if TYPE_CHECKING:
    from ...brdf_io.cornell import ScatteredBRDF

__all__ = ["data_checks"]


def data_checks(brdf: BRDF, analysis_brdf: BRDF, *, seed: int = 0, albedo_nodes: int = 64) -> dict[str, Any]:
    """The ``data_checks`` block of a report (``data_specs/report_json.md``).

    ``analysis_brdf`` is the BRDF the frequency analysis uses (the BRDF itself, or for
    scattered data the fitted model); its albedo is reported.
    """
    scattered = brdf.kind == "scattered"
    if scattered:
        samples = cast("ScatteredBRDF", brdf)  # the BRDFs of kind "scattered" (duck-typed by kind)
        reciprocity = scattered_reciprocity(samples.L, samples.V, samples.rgb)
    else:
        reciprocity = reciprocity_check(brdf, seed=seed)
    albedo = directional_albedo(analysis_brdf, ALBEDO_CHECK_VIEWS_DEG, nodes=albedo_nodes)
    k = int(np.argmax(albedo.max(axis=1)))
    return {
        "n_measurements": int(len(cast("ScatteredBRDF", brdf))) if scattered else None,
        "n_missing": int(getattr(brdf, "n_missing", 0)),
        "n_missing_above_surface": merl_missing_above_surface(brdf),
        "n_clamped": int(getattr(brdf, "n_clipped", 0)),
        "reciprocity": reciprocity,
        "albedo": {
            "of": "fitted model" if scattered else "brdf",
            "views_deg": list(ALBEDO_CHECK_VIEWS_DEG),
            "rgb": albedo.tolist(),
            "max": float(albedo.max()),
            "max_view_deg": float(ALBEDO_CHECK_VIEWS_DEG[k]),
            "nodes": int(albedo_nodes),
        },
    }
