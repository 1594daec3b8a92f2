"""Fitting analytic models (Lafortune, Cook–Torrance, RH02's simplified microfacet) to
measured BRDFs with nlopt; see :func:`fit_brdf` and ``data_specs/fit_json.md``."""

from .optimize import FitResult, fit_brdf
from .report import BandError, band_errors

__all__ = ["fit_brdf", "FitResult", "BandError", "band_errors"]
