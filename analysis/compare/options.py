"""The options of one comparison, in one frozen dataclass passed whole to every stage."""

from __future__ import annotations

import math
from dataclasses import dataclass

from ...brdf_io.errors import BadInputError
from ..lights import DEFAULT_LIGHTS, check_lights
from ..shrm import DEFAULT_WINDOW, check_window
from ..tolerance import DEFAULT_EPS, check_eps
from ..view_bands import DEFAULT_CRITERION, DEFAULT_MAX_VIEW_DEG, check_criterion, check_max_view

__all__ = ["CompareOptions", "DEFAULT_ENV_HEIGHT"]

#: Rows the environment is area-resampled to before the comparison (the angular reference
#: costs O(W S_L²) per value).
DEFAULT_ENV_HEIGHT = 64


@dataclass(frozen=True, kw_only=True)
class CompareOptions:
    """Everything a comparison can be told, validated once on construction.

    Attributes
    ----------
    eps
        SHRM tolerance ε on the uncaptured energy (RH02 §5.1); (F, P) by RH02's order rule
        (:func:`~shrmkit.analysis.shrm.prefilter`). Checked by
        :func:`~shrmkit.analysis.tolerance.check_eps`.
    env_height
        The environment is area-resampled to this many rows first (when it has more);
        None keeps it.
    n_pairs, max_view_deg, seed
        The error sample, :func:`~shrmkit.analysis.compare.pairs.sample_pairs` (n_pairs ≥ 10,
        max_view_deg in (0, 90)).
    lower_P
        P of the lower-order SHRM row (default max(P − 2, 0)); no row when it is not below P.
    lobes
        Values of K for the Green et al. 2007 Gaussian-lobe rows, each in [1, 8]; empty
        skips them.
    n_elevations
        View elevations of the Gaussian-lobe fits (at least 2).
    cabral_reference_height
        Rows of the Cabral et al. 1999 maps computed by the angular reference (the original
        method's cost); None or 0 skips that row.
    update_view
        View direction (need not be unit) at which the per-frame update of the distant
        viewer is timed.
    criterion, rule_max_view_deg
        The order rule of every SHRM of the comparison and its view limit
        (:mod:`~shrmkit.analysis.view_bands`; ``max_view_deg`` above is the sampling range).
    window
        The window of every SHRM of the comparison (the SHRM rows, Kautz–McCool, Cabral's
        maps from the SHRM) against Gibbs ringing, one of ``analysis.shrm.WINDOWS``
        (:func:`~shrmkit.analysis.shrm.prefilter`; default ``"auto"``).
    lights
        The explicit lights of every SHRM of the comparison (``prefilter(lights=)``: ``"auto"``,
        ``"none"`` or N; :mod:`~shrmkit.analysis.lights`). Cabral's maps from the SHRM hold them too.
    """

    eps: float = DEFAULT_EPS
    env_height: int | None = DEFAULT_ENV_HEIGHT
    n_pairs: int = 2000
    max_view_deg: float = 88.0
    seed: int = 0
    lower_P: int | None = None
    lobes: tuple[int, ...] = (1, 2, 3, 4)
    n_elevations: int = 15
    cabral_reference_height: int | None = 32
    update_view: tuple[float, float, float] = (1.0, 0.0, 0.3)
    window: str = DEFAULT_WINDOW
    criterion: str = DEFAULT_CRITERION
    rule_max_view_deg: float = DEFAULT_MAX_VIEW_DEG
    lights: str | int = DEFAULT_LIGHTS

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        set_(self, "eps", check_eps(self.eps))
        check_window(self.window)
        set_(self, "lights", check_lights(self.lights))
        check_criterion(self.criterion)
        set_(self, "rule_max_view_deg", check_max_view(self.rule_max_view_deg))
        set_(self, "lobes", tuple(int(k) for k in self.lobes))
        set_(self, "update_view", tuple(float(x) for x in self.update_view))
        if self.n_pairs < 10:
            raise BadInputError(None, f"n_pairs must be at least 10, got {self.n_pairs}")
        if not 0.0 < self.max_view_deg < 90.0:
            raise BadInputError(None, f"max_view_deg must be in (0, 90), got {self.max_view_deg}")
        if self.env_height is not None and self.env_height < 2:
            raise BadInputError(None, f"env_height must be at least 2 (or None), got {self.env_height}")
        if self.lower_P is not None and self.lower_P < 0:
            raise BadInputError(None, f"lower_P must be >= 0, got {self.lower_P}")
        if any(not 1 <= k <= 8 for k in self.lobes):
            raise BadInputError(None, f"lobes values must be in [1, 8], got {self.lobes}")
        if self.n_elevations < 2:
            raise BadInputError(None, f"n_elevations must be at least 2, got {self.n_elevations}")
        if self.cabral_reference_height is not None and self.cabral_reference_height < 0:
            raise BadInputError(None, f"cabral_reference_height must be >= 0, got {self.cabral_reference_height}")
        v = self.update_view
        if len(v) != 3 or not all(math.isfinite(x) for x in v) or not any(v):
            raise BadInputError(None, f"update_view must be a finite nonzero 3-vector, got {v}")
