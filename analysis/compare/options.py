"""The options of one comparison, in one frozen dataclass passed whole to every stage.

The methods' own settings (K, view elevations, the reference maps' rows) and their limits come
from the table of published methods (:mod:`shrmkit.analysis.baselines.methods`), under its names.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, fields
from typing import Any

from ...brdf_io.errors import BadInputError
from ..baselines.methods import GAUSSIAN_ELEVATIONS, GAUSSIAN_LOBES, RSIBR_REFERENCE_HEIGHT
from ..lights import DEFAULT_LIGHTS, check_lights
from ..shrm import DEFAULT_WINDOW, check_window
from ..tolerance import DEFAULT_EPS, check_eps
from ..view_bands import DEFAULT_CRITERION, DEFAULT_MAX_VIEW_DEG, check_criterion, check_max_view

__all__ = ["CompareOptions", "DEFAULT_ENV_HEIGHT"]

#: Earlier keyword → its name now (accepted with a DeprecationWarning).
_RENAMED = {"n_elevations": "elevations", "cabral_reference_height": "rsibr_reference_height"}

#: Rows the environment is area-resampled to before the comparison (the angular reference
#: costs O(W S_L²) per value).
DEFAULT_ENV_HEIGHT = 64


@dataclass(frozen=True, kw_only=True, init=False)
class CompareOptions:
    """Everything a comparison can be told, keyword-only, validated once on construction.

    ``n_elevations`` and ``cabral_reference_height``, the names before the table of methods, are
    still accepted (and readable) with a :class:`DeprecationWarning`; an unknown keyword raises
    ``TypeError``.

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
        Values of K for the [Green07] Gaussian-lobe rows, each within the method's ``lobes``
        limits ([1, 8]); empty skips them.
    elevations
        View elevations of the Gaussian-lobe fits, within the method's limits ([1, 64]).
    rsibr_reference_height
        Rows of the [Cabral99] maps computed by the angular reference (the original method's
        cost), within the method's ``reference_height`` limits ([2, 512]); None or 0 skips that row.
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
    elevations: int = GAUSSIAN_ELEVATIONS.default
    rsibr_reference_height: int | None = RSIBR_REFERENCE_HEIGHT.default
    update_view: tuple[float, float, float] = (1.0, 0.0, 0.3)
    window: str = DEFAULT_WINDOW
    criterion: str = DEFAULT_CRITERION
    rule_max_view_deg: float = DEFAULT_MAX_VIEW_DEG
    lights: str | int = DEFAULT_LIGHTS

    def __init__(self, **options: Any) -> None:
        for old, new in _RENAMED.items():
            if old in options:
                warnings.warn(f"CompareOptions({old}=) is deprecated: use {new}=", DeprecationWarning, stacklevel=2)
                if new in options:
                    raise TypeError(f"CompareOptions: give {new}= or {old}=, not both")
                options[new] = options.pop(old)
        known = fields(self)
        unknown = sorted(set(options) - {f.name for f in known})
        if unknown:
            raise TypeError(f"CompareOptions() got unexpected keyword argument(s) {', '.join(unknown)}")
        for f in known:
            object.__setattr__(self, f.name, options.get(f.name, f.default))
        self.__post_init__()

    @property
    def n_elevations(self) -> int:
        """Deprecated name of :attr:`elevations`."""
        warnings.warn("CompareOptions.n_elevations is deprecated: use elevations", DeprecationWarning, stacklevel=2)
        return self.elevations

    @property
    def cabral_reference_height(self) -> int | None:
        """Deprecated name of :attr:`rsibr_reference_height`."""
        warnings.warn("CompareOptions.cabral_reference_height is deprecated: use rsibr_reference_height",
                      DeprecationWarning, stacklevel=2)
        return self.rsibr_reference_height

    def shrm_settings(self) -> dict[str, Any]:
        """The settings of every SHRM of the comparison, as the table's builders take them
        (``analysis.baselines.methods.shrm_model``; the rule's view limit, not the sampling range)."""
        return {"eps": self.eps, "window": self.window, "criterion": self.criterion,
                "max_view_deg": self.rule_max_view_deg, "lights": self.lights}

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
        lo, hi = GAUSSIAN_LOBES.lo, GAUSSIAN_LOBES.hi
        if any(isinstance(k, bool) or not lo <= k <= hi for k in self.lobes):
            raise BadInputError(None, f"lobes values must be in [{lo}, {hi}], got {self.lobes}")
        set_(self, "elevations", GAUSSIAN_ELEVATIONS.check(self.elevations))
        if self.rsibr_reference_height:  # None or 0: no reference row
            set_(self, "rsibr_reference_height", RSIBR_REFERENCE_HEIGHT.check(self.rsibr_reference_height))
        v = self.update_view
        if len(v) != 3 or not all(math.isfinite(x) for x in v) or not any(v):
            raise BadInputError(None, f"update_view must be a finite nonzero 3-vector, got {v}")
