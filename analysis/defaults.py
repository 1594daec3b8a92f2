"""Numpy-free defaults, choices and limits of analysis, for what must start fast (``shrm VERB
--help`` and usage errors: issue 26).

The one home of: the order caps (:mod:`~shrmkit.analysis.orders`), the window
(:mod:`~shrmkit.analysis.window`), the order rule (:mod:`~shrmkit.analysis.view_bands`), the fits'
models, metrics, folds and candidates (:mod:`~shrmkit.analysis.fit`), the census's orders and caps
(:mod:`~shrmkit.analysis.census`), the published methods' settings
(:mod:`~shrmkit.analysis.baselines.methods`) and the prefiltered cube's largest face
(:mod:`~shrmkit.analysis.prefiltered_cube`) and the explicit lights' constants and validator
(:mod:`~shrmkit.analysis.lights`): those modules import them from here, under their own names.
Mirrored here (``tests/cli/test_cli_startup.py`` checks that both agree): ``CompareOptions()``'s
defaults (:mod:`~shrmkit.analysis.compare`). Internal module.
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
    "FIT_MODELS", "FIT_METRICS", "DEFAULT_FOLDS", "REPRESENTATION_CANDIDATES",
    "CENSUS_F", "CENSUS_P", "CENSUS_THRESHOLD", "CENSUS_MAX_F_LIMIT", "CENSUS_MAX_P_LIMIT", "CENSUS_MAX_WORKERS",
    "COMPARE_DEFAULTS", "GAUSSIAN_LOBES_LIMITS", "GAUSSIAN_ELEVATIONS_LIMITS", "RSIBR_REFERENCE_HEIGHT_LIMITS",
    "MAX_CUBE_FACE_SIZE",
]

#: Caps on the orders F and P of ``choose_orders`` (``orders.DEFAULT_MAX_F``, ``DEFAULT_MAX_P``).
DEFAULT_MAX_F = 512
DEFAULT_MAX_P = 20

#: The windows of ``prefilter`` and of every verb that prefilters (``--window``);
#: ``window.check_window`` is their one validator.
WINDOWS = ("none", "lanczos", "auto")
DEFAULT_WINDOW = "auto"
#: ``auto`` windows when the undershoot (most negative sampled radiance over the largest,
#: worst channel; ``window.undershoot``) exceeds this fraction. Chosen from renders of the Grace
#: probe with Phong s = 32: black blotches are visible (+4 stops) at 0.4 % of the peak, barely
#: at 0.15 %, not at 0.03 % (README, accuracy).
WINDOW_THRESHOLD = 1e-3
#: ``auto``'s window may add at most this many ε of error energy to ε_B (worst channel): with
#: the truncation's own ≲ ε, √ε_B stays inside the tested 2√ε + 1 % relative RMS.
WINDOW_BUDGET_EPS = 2.0

#: ``--lights``: ``auto`` (default), ``none``, or a number N (at most N lights).
LIGHT_MODES = ("auto", "none")
DEFAULT_LIGHTS = "auto"
#: A pixel can belong to a light when its luminance is this many times the map's solid-angle-weighted
#: median (the sky, the room): the sun of ``builtin:sky`` is 10⁴×, Grace's windows 10²–10⁴×.
LIGHT_CONTRAST = 100.0
#: A bright region is a light when it fits in a cap of this angular radius about its centre.
MAX_LIGHT_RADIUS_DEG = 5.0
#: At most this many lights per map (the brightest by flux).
MAX_LIGHTS = 8


def check_lights(value: Any) -> str | int:
    """The one validator of ``lights=``/``--lights`` (:mod:`~shrmkit.analysis.lights`): ``"auto"``,
    ``"none"`` or an integer N in [0, :data:`MAX_LIGHTS`] (0 is ``"none"``; numpy integers count).

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


#: Default view limit (degrees): the order rule meets the tolerance in every band that starts below it.
DEFAULT_MAX_VIEW_DEG = 80.0
#: Order rules: ``"bands"`` (every band inside the view limit meets ε) and ``"rh02"``
#: (RH02 §5.1: the unweighted energy over all views, and F_B = min(F_ρ, F_L) for a scene).
CRITERIA = ("bands", "rh02")
DEFAULT_CRITERION = "bands"

#: The nlopt models of ``fit_brdf`` (``fit.models_param.MODELS``).
FIT_MODELS = ("lafortune", "cook-torrance", "microfacet")
#: The fits' error metrics (``fit.metrics.METRICS``).
FIT_METRICS = ("rel", "log")
#: Folds of the cross-validation (Hastie et al. §7.10: 5 or 10; 5 keeps 80 % of CURET's 205
#: geometries, 164, for each training fit — more than the 91 terms of a Zernike order 10).
DEFAULT_FOLDS = 5
#: The representations tried for scattered measurements, in this order (a tie goes to the earlier
#: one; ``fit.representation.CANDIDATES``).
REPRESENTATION_CANDIDATES = ("lafortune", "cook-torrance", "zernike")

#: RH02 Fig. 8's orders (``census``): lighting order F = 30, view orders P = 0…5.
CENSUS_F = 30
CENSUS_P = 5
#: The caps ``choose_orders`` accepts on the orders needed (checked once, before any row).
CENSUS_MAX_F_LIMIT, CENSUS_MAX_P_LIMIT = 2000, 64
#: Most worker processes ``run_census`` starts.
CENSUS_MAX_WORKERS = 64
#: RH02 Fig. 8's mark: 90 % of the energy captured.
CENSUS_THRESHOLD = 0.9

#: ``CompareOptions()``'s defaults that ``shrm compare`` shows (``compare.options.CompareOptions``).
COMPARE_DEFAULTS: dict[str, Any] = {
    "env_height": 64, "n_pairs": 2000, "sample_max_view_deg": 88.0, "seed": 0, "lobes": (1, 2, 3, 4), "elevations": 15,
}
#: (default, lo, hi) of the published methods' settings (``baselines.methods.GAUSSIAN_LOBES``,
#: ``GAUSSIAN_ELEVATIONS``, ``RSIBR_REFERENCE_HEIGHT``).
GAUSSIAN_LOBES_LIMITS = (3, 1, 8)
GAUSSIAN_ELEVATIONS_LIMITS = (15, 1, 64)
RSIBR_REFERENCE_HEIGHT_LIMITS = (32, 2, 512)

#: Largest face size of a prefiltered cube's mip level 0, texels (``prefiltered_cube.MAX_FACE_SIZE``).
MAX_CUBE_FACE_SIZE = 2048
