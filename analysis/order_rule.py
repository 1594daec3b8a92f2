"""The order rule as one value: :class:`OrderRule` (criterion, view limit, tolerance, caps).

What decides the orders (F, P) of a BRDF ([RH02] §5.1; ``"bands"``: :mod:`~shrmkit.analysis.view_bands`)
travels as this one frozen value from the CLI's options through the options classes to
:func:`~shrmkit.analysis.orders.choose_orders` and :func:`~shrmkit.analysis.shrm.prefilter`, instead of
five loose keywords (issue 27). Those keywords are still accepted: :func:`resolve_rule` builds the rule
from them. ``data_specs/view_bands.md`` (the rule as one value) documents :meth:`OrderRule.to_json`.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import MISSING, dataclass, fields, replace
from typing import Any

from ..brdf_io.errors import BadInputError
from .defaults import CENSUS_MAX_F_LIMIT as MAX_F_LIMIT  # the caps choose_orders accepts (one home)
from .defaults import CENSUS_MAX_P_LIMIT as MAX_P_LIMIT
from .defaults import DEFAULT_CRITERION, DEFAULT_MAX_F, DEFAULT_MAX_P, DEFAULT_MAX_VIEW_DEG
from .tolerance import DEFAULT_EPS, check_eps
from .view_bands import check_criterion, check_max_view

__all__ = ["OrderRule", "resolve_rule", "init_options", "RuleView", "RuleFields", "RULE_FIELDS"]


@dataclass(frozen=True)
class OrderRule:
    """The rule that chooses the orders (F, P) of a BRDF, validated on construction.

    Attributes
    ----------
    criterion
        ``"bands"`` (default): every θ_v band that starts below ``max_view_deg`` meets ``eps``
        under a point light; ``"rh02"``: [RH02] §5.1's energy over all views (F_B = min(F_ρ, F_L)
        for a scene). One of :data:`~shrmkit.analysis.defaults.CRITERIA`.
    max_view_deg
        View limit of the ``"bands"`` rule, degrees of θ_v in (0, 90] (default 80); a float.
    eps
        Tolerance ε on the uncaptured energy fraction, in (0, 1) (default 0.03); a float.
    max_F, max_P
        Caps on the orders, F in [1, 2000] (default 512), P in [0, 64] (default 20); beyond
        them a choice is ``capped``.

    Raises
    ------
    BadInputError
        A field out of range or an unknown criterion (the checks of ``check_criterion``,
        ``check_max_view``, ``check_eps``; the message names the field and the value).

    Examples
    --------
    >>> OrderRule(eps=0.01).to_json()
    {'criterion': 'bands', 'max_view_deg': 80.0, 'eps': 0.01, 'max_F': 512, 'max_P': 20}
    """

    criterion: str = DEFAULT_CRITERION
    max_view_deg: float = DEFAULT_MAX_VIEW_DEG
    eps: float = DEFAULT_EPS
    max_F: int = DEFAULT_MAX_F
    max_P: int = DEFAULT_MAX_P

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        set_(self, "criterion", check_criterion(self.criterion))
        set_(self, "max_view_deg", check_max_view(self.max_view_deg))
        set_(self, "eps", check_eps(self.eps))
        set_(self, "max_F", _cap("max_F", self.max_F, 1, MAX_F_LIMIT))
        set_(self, "max_P", _cap("max_P", self.max_P, 0, MAX_P_LIMIT))

    def replace(self, **changes: Any) -> OrderRule:
        """A copy with some fields changed (validated again)."""
        return replace(self, **changes)

    def to_json(self) -> dict[str, Any]:
        """The rule as JSON: ``criterion``, ``max_view_deg``, ``eps``, ``max_F``, ``max_P``
        (``data_specs/view_bands.md``)."""
        return {f.name: getattr(self, f.name) for f in fields(self)}

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> OrderRule:
        """The rule :meth:`to_json` wrote (missing keys take the defaults; others are ignored)."""
        return cls(**{name: data[name] for name in RULE_FIELDS if name in data})


#: The fields of :class:`OrderRule`, in order: also the loose keywords the library still accepts.
RULE_FIELDS = ("criterion", "max_view_deg", "eps", "max_F", "max_P")


class RuleView:
    """``criterion`` and ``max_view_deg`` read back from the ``rule`` (an :class:`OrderRule`) of a
    class that holds one (a base of options and result dataclasses; no fields of its own)."""

    rule: OrderRule

    @property
    def criterion(self) -> str:
        """``rule.criterion``: ``"bands"`` or ``"rh02"``."""
        return self.rule.criterion

    @property
    def max_view_deg(self) -> float:
        """``rule.max_view_deg``: the rule's view limit, degrees of θ_v."""
        return self.rule.max_view_deg


class RuleFields(RuleView):
    """Every field of the ``rule`` read back: :class:`RuleView`'s and ``eps``, ``max_F``, ``max_P``."""

    @property
    def eps(self) -> float:
        """``rule.eps``: the tolerance ε."""
        return self.rule.eps

    @property
    def max_F(self) -> int:
        """``rule.max_F``: the cap on F."""
        return self.rule.max_F

    @property
    def max_P(self) -> int:
        """``rule.max_P``: the cap on P."""
        return self.rule.max_P


def init_options(obj: Any, options: dict[str, Any], loose: Mapping[str, str]) -> None:
    """Set the fields of a frozen options dataclass written ``init=False`` that holds one ``rule``
    (:class:`OrderRule`) from its constructor's keyword ``options``.

    The keywords named in ``loose`` (keyword → rule field) set those fields of the rule, over a
    ``rule=`` given too; the other keywords set the dataclass' fields (defaults for those not given).
    ``dataclasses.replace`` then works both ways: it passes every field (``rule`` among them) and the
    changed keywords, so a new ``rule=`` or a changed loose keyword each win.

    Raises
    ------
    TypeError
        A keyword that is neither a field nor in ``loose``.
    BadInputError
        A rule field out of range, or ``rule`` not an :class:`OrderRule` (:func:`resolve_rule`).
    """
    given = {field_: options.pop(key) for key, field_ in loose.items() if key in options}
    options["rule"] = resolve_rule(options.get("rule"), override=True, **given)
    known = fields(obj)
    unknown = sorted(set(options) - {f.name for f in known})
    if unknown:
        raise TypeError(f"{type(obj).__name__}() got unexpected keyword argument(s) {', '.join(unknown)}")
    for f in known:
        default = f.default_factory() if f.default is MISSING and f.default_factory is not MISSING else f.default
        object.__setattr__(obj, f.name, options.get(f.name, default))


def _cap(name: str, value: Any, lo: int, hi: int) -> int:
    try:
        cap = int(value)
    except (TypeError, ValueError):
        raise BadInputError(None, f"{name} must be an integer in [{lo}, {hi}], got {value!r}") from None
    if not lo <= cap <= hi:  # the check choose_orders always made (int() of the value)
        raise BadInputError(None, f"{name} must be in [{lo}, {hi}], got {value!r}")
    return cap


def resolve_rule(rule: OrderRule | None = None, *, override: bool = False, **keywords: Any) -> OrderRule:
    """One :class:`OrderRule` from ``rule`` and/or the loose keywords of :data:`RULE_FIELDS`
    (None: not given).

    Without ``rule``: the rule of the given keywords (defaults for the others). With ``rule``: the
    rule itself when every keyword given agrees with it (after validation: ``max_view_deg=80`` agrees
    with 80.0); ``override=True`` (the options classes, so that ``dataclasses.replace`` works)
    lets the keywords replace its fields instead.

    Raises
    ------
    BadInputError
        ``rule`` is not an :class:`OrderRule`; a keyword given with ``rule`` disagrees with it
        (the message names both); a value out of range (:class:`OrderRule`).
    """
    unknown = set(keywords) - set(RULE_FIELDS)
    if unknown:
        raise TypeError(f"not an order rule field: {', '.join(sorted(unknown))}")
    given = {k: v for k, v in keywords.items() if v is not None}
    if rule is None:
        return OrderRule(**given)
    if not isinstance(rule, OrderRule):
        raise BadInputError(None, f"rule must be an OrderRule, got {type(rule).__name__}")
    if not given:
        return rule
    merged = rule.replace(**given)
    if merged == rule:
        return rule
    if override:
        return merged
    clash = [k for k in given if getattr(merged, k) != getattr(rule, k)]
    raise BadInputError(None, "give the order rule once: " + ", ".join(
        f"{k}={given[k]!r} disagrees with rule.{k}={getattr(rule, k)!r}" for k in clash))
