"""Fitting analytic models (Lafortune, Cook–Torrance, [RH02]'s simplified microfacet) to
measured BRDFs with nlopt, Koenderink's Zernike expansion by cross-validated least squares, and
the choice of one representation for scattered measurements.

Modules: ``sampling`` (fit samples and quadrature weights), ``models_param`` (shape /
colour parameterizations and physical bounds), ``objective`` (variable projection),
``metrics`` (error metrics), ``optimize`` (:func:`fit_brdf`, :class:`FitResult`),
``summary`` (errors per view-elevation band, the worst band and the verdict), ``fit_file`` (the
JSON document, ``data_specs/fit_json.md``), ``zernike`` (the Zernike fit, held-out order and
ridge: ``fit_zernike_cv``), ``crossval`` (k-fold held-out predictions), ``isotropy`` (how far
scattered measurements are from isotropic), ``representation`` (``choose_representation``: the
candidate with the smallest held-out worst-band error, ``data_specs/representation_json.md``).

Reference: [RH02] (``data_specs/bibliography.md``).
"""

from .fit_file import fit_document, write_fit_json
from .optimize import FitResult, fit_brdf
from .summary import BandError, band_errors

__all__ = ["fit_brdf", "FitResult", "BandError", "band_errors", "fit_document", "write_fit_json"]
