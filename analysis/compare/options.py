"""The options of one comparison, in one frozen dataclass passed whole to every stage.

The methods' own settings (K, view elevations, the reference maps' rows) and their limits come
from the table of published methods (:mod:`shrmkit.analysis.baselines.methods`), under its names.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import Any

from ...brdf_io.errors import BadInputError
from ..baselines.methods import GAUSSIAN_ELEVATIONS, GAUSSIAN_LOBES, RSIBR_REFERENCE_HEIGHT
from ..lights import DEFAULT_LIGHTS, check_lights
from ..order_rule import OrderRule, init_options
from ..shrm import DEFAULT_WINDOW, check_window

__all__ = ["CompareOptions", "DEFAULT_ENV_HEIGHT"]

#: Earlier keyword → its name now (accepted with a DeprecationWarning).
_RENAMED = {"n_elevations": "elevations", "cabral_reference_height": "rsibr_reference_height",
            "max_view_deg": "sample_max_view_deg"}
#: Constructor keywords that set a field of :attr:`CompareOptions.rule` → that field.
_RULE_KEYWORDS = {"eps": "eps", "criterion": "criterion", "rule_max_view_deg": "max_view_deg"}

#: Rows the environment is area-resampled to before the comparison (the angular reference
#: costs O(W S_L²) per value).
DEFAULT_ENV_HEIGHT = 64


@dataclass(frozen=True, kw_only=True, init=False)
class CompareOptions:
    """Everything a comparison can be told, keyword-only, validated once on construction.

    ``n_elevations`` and ``cabral_reference_height``, the names before the table of methods, and
    ``max_view_deg``, the sampling range's name before the order rule's limit got its own, are
    still accepted (and readable) with a :class:`DeprecationWarning`; an unknown keyword raises
    ``TypeError``.

    Attributes
    ----------
    rule
        The order rule of every SHRM of the comparison
        (:class:`~shrmkit.analysis.order_rule.OrderRule`; its caps are the prefilter's). The
        keywords ``eps``, ``criterion`` and ``rule_max_view_deg`` set its fields (over a ``rule=``
        given too, so that ``dataclasses.replace`` works) and read them back.
    eps
        SHRM tolerance ε on the uncaptured energy (RH02 §5.1): ``rule.eps``; (F, P) by the order
        rule (:func:`~shrmkit.analysis.shrm.prefilter`). Checked by
        :func:`~shrmkit.analysis.tolerance.check_eps`.
    env_height
        The environment is area-resampled to this many rows first (when it has more);
        None keeps it.
    n_pairs, sample_max_view_deg, seed
        The error sample, :func:`~shrmkit.analysis.compare.pairs.sample_pairs` (n_pairs ≥ 10;
        views up to ``sample_max_view_deg`` in (0, 90), default 88°: the sampling range, not the
        rule's view limit).
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
        ``rule.criterion`` and ``rule.max_view_deg``: the order rule of every SHRM of the
        comparison and its view limit (:mod:`~shrmkit.analysis.view_bands`).
    window
        The window of every SHRM of the comparison (the SHRM rows, Kautz–McCool, Cabral's
        maps from the SHRM) against Gibbs ringing, one of ``analysis.shrm.WINDOWS``
        (:func:`~shrmkit.analysis.shrm.prefilter`; default ``"auto"``).
    lights
        The explicit lights of every SHRM of the comparison (``prefilter(lights=)``: ``"auto"``,
        ``"none"`` or N; :mod:`~shrmkit.analysis.lights`). Cabral's maps from the SHRM hold them too.
    """

    env_height: int | None = DEFAULT_ENV_HEIGHT
    n_pairs: int = 2000
    sample_max_view_deg: float = 88.0
    seed: int = 0
    lower_P: int | None = None
    lobes: tuple[int, ...] = (1, 2, 3, 4)
    elevations: int = GAUSSIAN_ELEVATIONS.default
    rsibr_reference_height: int | None = RSIBR_REFERENCE_HEIGHT.default
    update_view: tuple[float, float, float] = (1.0, 0.0, 0.3)
    window: str = DEFAULT_WINDOW
    lights: str | int = DEFAULT_LIGHTS
    rule: OrderRule = OrderRule()

    def __init__(self, **options: Any) -> None:
        for old, new in _RENAMED.items():
            if old in options:
                warnings.warn(f"CompareOptions({old}=) is deprecated: use {new}=", DeprecationWarning, stacklevel=2)
                if new in options:
                    raise TypeError(f"CompareOptions: give {new}= or {old}=, not both")
                options[new] = options.pop(old)
        init_options(self, options, _RULE_KEYWORDS)
        self.__post_init__()

    @property
    def eps(self) -> float:
        """The SHRMs' tolerance ε: ``rule.eps``."""
        return self.rule.eps

    @property
    def criterion(self) -> str:
        """The SHRMs' order rule: ``rule.criterion``."""
        return self.rule.criterion

    @property
    def rule_max_view_deg(self) -> float:
        """The order rule's view limit, degrees: ``rule.max_view_deg`` (not the sampling range)."""
        return self.rule.max_view_deg

    @property
    def max_view_deg(self) -> float:
        """Deprecated name of :attr:`sample_max_view_deg` (the sampling range)."""
        warnings.warn("CompareOptions.max_view_deg is deprecated: use sample_max_view_deg", DeprecationWarning,
                      stacklevel=2)
        return self.sample_max_view_deg

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
        check_window(self.window)
        set_(self, "lights", check_lights(self.lights))
        set_(self, "lobes", tuple(int(k) for k in self.lobes))
        set_(self, "update_view", tuple(float(x) for x in self.update_view))
        if self.n_pairs < 10:
            raise BadInputError(None, f"n_pairs must be at least 10, got {self.n_pairs}")
        if not 0.0 < self.sample_max_view_deg < 90.0:
            raise BadInputError(None, f"sample_max_view_deg must be in (0, 90), got {self.sample_max_view_deg}")
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
