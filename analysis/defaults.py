"""Numpy-free defaults, choices and limits of analysis, for what must start fast (``shrm VERB
--help`` and usage errors: issue 26).

The modules that use them import numpy and scipy; the values here are theirs
(``tests/cli/test_cli_startup.py`` checks that both agree): the order caps
(:mod:`~shrmkit.analysis.orders`), the window (:mod:`~shrmkit.analysis.window`), the explicit
lights and their validator (:mod:`~shrmkit.analysis.lights`), the order rule
(:mod:`~shrmkit.analysis.view_bands`), the fits (:mod:`~shrmkit.analysis.fit`), the census
(:mod:`~shrmkit.analysis.census`), the comparison and the published methods' settings
(:mod:`~shrmkit.analysis.compare`, :mod:`~shrmkit.analysis.baselines.methods`) and the
prefiltered cube (:mod:`~shrmkit.analysis.prefiltered_cube`). Internal module.
"""

from __future__ import annotations

import numbers
from typing import Any

from ..brdf_io.errors import BadInputError

__all__ = [
    "DEFAULT_MAX_F", "DEFAULT_MAX_P",
    "WINDOWS", "DEFAULT_WINDOW", "WINDOW_THRESHOLD", "WINDOW_BUDGET_EPS",
    "LIGHT_MODES", "DEFAULT_LIGHTS", "LIGHT_CONTRAST", "MAX_LIGHT_RADIUS_DEG", "MAX_LIGHTS", "check_lights",
    "CRITERIA", "DEFAULT_CRITERION", "DEFAULT_MAX_VIEW_DEG",
    "FIT_MODELS", "FIT_METRICS", "DEFAULT_FOLDS", "ZERNIKE_MAX_ORDER", "REPRESENTATION_CANDIDATES",
    "CENSUS_F", "CENSUS_P", "CENSUS_THRESHOLD", "CENSUS_MAX_F_LIMIT", "CENSUS_MAX_P_LIMIT", "CENSUS_MAX_WORKERS",
    "COMPARE_DEFAULTS", "GAUSSIAN_LOBES_LIMITS", "GAUSSIAN_ELEVATIONS_LIMITS", "RSIBR_REFERENCE_HEIGHT_LIMITS",
    "MAX_CUBE_FACE_SIZE",
]

#: Caps on the orders F and P of ``choose_orders`` (``orders.DEFAULT_MAX_F``, ``DEFAULT_MAX_P``).
DEFAULT_MAX_F = 512
DEFAULT_MAX_P = 20

#: ``prefilter(window=)``: the windows and the default (``window.WINDOWS``, ``DEFAULT_WINDOW``).
WINDOWS = ("none", "lanczos", "auto")
DEFAULT_WINDOW = "auto"
#: ``auto`` windows when the undershoot exceeds this fraction of the peak (``window.WINDOW_THRESHOLD``).
WINDOW_THRESHOLD = 1e-3
#: ``auto``'s window adds at most this many ε of error energy (``window.WINDOW_BUDGET_EPS``).
WINDOW_BUDGET_EPS = 2.0

#: ``lights=``: the named modes (or a number N) and the default (``lights.LIGHT_MODES``, ``DEFAULT_LIGHTS``).
LIGHT_MODES = ("auto", "none")
DEFAULT_LIGHTS = "auto"
#: A light is this many times brighter than the map's median (``lights.LIGHT_CONTRAST``) ...
LIGHT_CONTRAST = 100.0
#: ... within a cap of this radius in degrees (``lights.MAX_LIGHT_RADIUS_DEG``) ...
MAX_LIGHT_RADIUS_DEG = 5.0
#: ... and at most this many per map (``lights.MAX_LIGHTS``).
MAX_LIGHTS = 8


def check_lights(value: Any) -> str | int:
    """``lights=``/``--lights`` checked as :func:`shrmkit.analysis.lights.check_lights` does it
    (``"auto"``, ``"none"`` or an integer N in [0, :data:`MAX_LIGHTS`], 0 read as ``"none"``),
    without numpy.

    Raises
    ------
    BadInputError
        Any other value; the message names it and the choices.
    """
    if isinstance(value, str):
        text = value.strip().lower()
        if text in LIGHT_MODES:
            return text
        try:
            value = int(text)
        except ValueError:
            raise BadInputError(None, f"lights={value!r}: choose auto, none or a number of lights "
                                      f"0..{MAX_LIGHTS}") from None
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or not 0 <= int(value) <= MAX_LIGHTS:
        raise BadInputError(None, f"lights={value!r}: choose auto, none or a number of lights 0..{MAX_LIGHTS}")
    return "none" if int(value) == 0 else int(value)


#: Order rules and the default (``view_bands.CRITERIA``, ``DEFAULT_CRITERION``).
CRITERIA = ("bands", "rh02")
DEFAULT_CRITERION = "bands"
#: The bands rule's view limit in degrees (``view_bands.DEFAULT_MAX_VIEW_DEG``).
DEFAULT_MAX_VIEW_DEG = 80.0

#: The nlopt models of ``fit_brdf`` (``fit.models_param.MODELS``).
FIT_MODELS = ("lafortune", "cook-torrance", "microfacet")
#: The fits' error metrics (``fit.metrics.METRICS``).
FIT_METRICS = ("rel", "log")
#: Cross-validation folds of the Zernike fit and the representation choice (``fit.crossval.DEFAULT_FOLDS``).
DEFAULT_FOLDS = 5
#: Largest Zernike order of a fit (``fit.zernike.MAX_ORDER``).
ZERNIKE_MAX_ORDER = 20
#: The representations tried for scattered measurements (``fit.representation.CANDIDATES``).
REPRESENTATION_CANDIDATES = ("lafortune", "cook-torrance", "zernike")

#: RH02 Fig. 8's orders and mark: F = 30, P = 0..5, 90 % (``census.DEFAULT_F``, ``DEFAULT_P``,
#: ``DEFAULT_THRESHOLD``).
CENSUS_F, CENSUS_P, CENSUS_THRESHOLD = 30, 5, 0.9
#: The census's caps on the orders needed and on its worker processes (``census.MAX_F_LIMIT``,
#: ``MAX_P_LIMIT``, ``MAX_WORKERS``).
CENSUS_MAX_F_LIMIT, CENSUS_MAX_P_LIMIT, CENSUS_MAX_WORKERS = 2000, 64, 64

#: ``CompareOptions()``'s defaults that ``shrm compare`` shows (``compare.options.CompareOptions``).
COMPARE_DEFAULTS: dict[str, Any] = {
    "env_height": 64, "n_pairs": 2000, "max_view_deg": 88.0, "seed": 0, "lobes": (1, 2, 3, 4), "elevations": 15,
}
#: (default, lo, hi) of the published methods' settings (``baselines.methods.GAUSSIAN_LOBES``,
#: ``GAUSSIAN_ELEVATIONS``, ``RSIBR_REFERENCE_HEIGHT``).
GAUSSIAN_LOBES_LIMITS = (3, 1, 8)
GAUSSIAN_ELEVATIONS_LIMITS = (15, 1, 64)
RSIBR_REFERENCE_HEIGHT_LIMITS = (32, 2, 512)

#: Largest face of a prefiltered cube's mip level 0 (``prefiltered_cube.MAX_FACE_SIZE``).
MAX_CUBE_FACE_SIZE = 2048
