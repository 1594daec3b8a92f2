"""Frequency-space analysis ([RH02]): BRDF coefficients ρ̂_lpq, the choice of orders, lighting
coefficients, SHRM prefiltering and synthesis, the stated error per view band, and the
angular-domain reference (DESIGN §4–6). Imports only :mod:`shrmkit.brdf_io`. Public API: the names
in ``__all__``, importable from ``shrmkit.analysis``:

- The SHRM: :func:`prefilter` (environment × BRDF → :class:`SHRM`, [RH02] §4–5), :func:`load_shrm`
  (``data_specs/shrm_file.md``); what a prefilter states, typed (``SHRM.info``): :class:`PrefilterInfo`
  with :class:`WindowInfo`, :class:`LightsInfo`, :class:`Timings`, :class:`ViewBand`.
- Orders: :func:`choose_orders` and :func:`choose_orders_many` ([RH02] §5.1) under an
  :class:`OrderRule` (criterion, view limit, tolerance, caps) returning :class:`OrderChoice`;
  the defaults :data:`DEFAULT_EPS`, :data:`DEFAULT_MAX_VIEW_DEG` and the rules :data:`CRITERIA`;
  :class:`BandStatement`, one view band's stated error (``data_specs/view_bands.md``).
- The pieces of the pipeline: :func:`rho_lpq` ([RH02] eq. 13) → :class:`BRDFCoefficients`;
  :func:`lighting_coefficients` → :class:`LightingCoefficients`; :func:`scene_orders` →
  :class:`SceneOrders` and :func:`residual_bound`; :func:`real_sph_harm` (DESIGN §2's real basis).
- Explicit lights beside the SHRM (DESIGN §5a): :func:`extract_lights`, :class:`LightSet`, :class:`Light`.
- The brute-force reference (the ground truth of the tests): :func:`reference_radiance`,
  :func:`reference_map`; the predicted error of a render's pixels: :func:`predicted_error`; a band's
  statement read over a region of reflection directions: :func:`region_bounds`.
- BRDF checks and views: :func:`directional_albedo`, :func:`reciprocity_check`,
  :func:`halfdiff_slice` [Rus98], :func:`lit_sphere`.

Public sub-packages: :mod:`shrmkit.analysis.fit` (model fits [Laf97], [CT82], [Walter07] and the
Zernike expansion [Koe96]), :mod:`shrmkit.analysis.compare` (the numbers of a comparison against
[KM00], [Cabral99], [Green07]) and :mod:`shrmkit.analysis.baselines` (those published
representations and the angular methods the SHRM's speed is measured against, [Karis13]).

Modules not listed here are internal: their names may change without notice. Citation keys:
``data_specs/bibliography.md``. Names are imported on first use, so importing one analysis
module does not load the others.
"""

from __future__ import annotations

from ..brdf_io.lazy import lazy_exports as _lazy_exports

#: Public name → the module that defines it (imported on first use).
_LAZY = {
    "SHRM": "shrmkit.analysis.shrm",
    "prefilter": "shrmkit.analysis.shrm",
    "load_shrm": "shrmkit.analysis.shrm",
    "region_bounds": "shrmkit.analysis.pixels",
    "PrefilterInfo": "shrmkit.analysis.records",
    "WindowInfo": "shrmkit.analysis.records",
    "LightsInfo": "shrmkit.analysis.records",
    "Timings": "shrmkit.analysis.records",
    "ViewBand": "shrmkit.analysis.records",
    "OrderChoice": "shrmkit.analysis.orders",
    "OrderRule": "shrmkit.analysis.order_rule",
    "choose_orders": "shrmkit.analysis.orders",
    "choose_orders_many": "shrmkit.analysis.orders",
    "DEFAULT_EPS": "shrmkit.analysis.tolerance",
    "DEFAULT_MAX_VIEW_DEG": "shrmkit.analysis.view_bands",
    "CRITERIA": "shrmkit.analysis.view_bands",
    "BandStatement": "shrmkit.analysis.view_bands",
    "rho_lpq": "shrmkit.analysis.brdf_coeffs",
    "BRDFCoefficients": "shrmkit.analysis.brdf_coeffs",
    "lighting_coefficients": "shrmkit.analysis.lighting",
    "LightingCoefficients": "shrmkit.analysis.lighting",
    "scene_orders": "shrmkit.analysis.scene",
    "SceneOrders": "shrmkit.analysis.scene",
    "residual_bound": "shrmkit.analysis.scene",
    "real_sph_harm": "shrmkit.analysis.sh",
    "extract_lights": "shrmkit.analysis.lights",
    "LightSet": "shrmkit.analysis.lights",
    "Light": "shrmkit.analysis.lights",
    "reference_radiance": "shrmkit.analysis.reference",
    "reference_map": "shrmkit.analysis.reference",
    "predicted_error": "shrmkit.analysis.error_image",
    "directional_albedo": "shrmkit.analysis.albedo",
    "reciprocity_check": "shrmkit.analysis.reciprocity",
    "halfdiff_slice": "shrmkit.analysis.brdf_views",
    "lit_sphere": "shrmkit.analysis.brdf_views",
}

__all__ = list(_LAZY)


__getattr__, __dir__ = _lazy_exports(__name__, _LAZY, __all__)
