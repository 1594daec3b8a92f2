"""The table of the published methods: one :class:`Method` per method, under one name everywhere.

``shrm render --mode``, :mod:`shrmkit.render.modes`, ``shrm compare`` and
:mod:`shrmkit.analysis.compare` all build their models through this table, so that a method has
one key, one display name, one citation, one set of fit settings with one set of limits, and one
function that builds its plain model:

==================  ====================================  ===========  ===========================
key                 method                                cite         model
==================  ====================================  ===========  ===========================
``shrm``            spherical harmonic reflection map     [RH02]       :class:`~..shrm.SHRM`
``kautz_mccool``    azimuth-free (q = 0) SHRM             [KM00]       :class:`~..shrm.SHRM`
``rsibr``           twelve maps blended per view (RSIBR)  [Cabral99]   :class:`.rsibr.RSIBRMaps`
``gaussian_lobes``  K Gaussian lobes per view elevation   [Green07]    :class:`.gaussian_lobes.GaussianLobeModel`
==================  ====================================  ===========  ===========================

Keys are Python identifiers (the JSON and API spelling); the CLI spells them with hyphens
(``--mode kautz-mccool``), and :func:`get_method` takes either. The names used before this table
(``cabral``, ``cabral_shrm``, ``gaussian``, ``green`` …) still resolve, with a
:class:`DeprecationWarning`.

Where render and compare used to differ, one setting was chosen by measured error and cost
(``data_specs/methods.md``): Kautz–McCool is built on the SHRM's own (F, P) and map rows (its
own order choice let the pixel rule raise F to 63 on Grace without lowering the error), and the
Gaussian-lobe fits take 1 to 64 view elevations (1 and 2 are both poor, neither worse in every
case; the error stops falling at about 8 while the fit's cost grows linearly: 64 elevations cost
87 s CPU for K = 3, 90 cost 116 s for the same error).

Citation keys: ``data_specs/bibliography.md``.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from numbers import Integral
from types import MappingProxyType
from typing import Any

import numpy as np

from ...brdf_io.errors import BadInputError
from ..defaults import (  # (default, lo, hi)
    GAUSSIAN_ELEVATIONS_LIMITS,
    GAUSSIAN_LOBES_LIMITS,
    RSIBR_REFERENCE_HEIGHT_LIMITS,
)
from ..lights import DEFAULT_LIGHTS
from ..order_rule import OrderRule, resolve_rule
from ..orders import OrderChoice
from ..shrm import DEFAULT_WINDOW, SHRM, prefilter
from .gaussian_lobes import GaussianLobeModel, TransferSamples, fit_gaussian_lobes, sg_mip_stack, transfer_samples
from .rsibr import RSIBRMaps, rsibr_from_shrm, rsibr_reference

__all__ = [
    "Setting",
    "Method",
    "METHODS",
    "get_method",
    "method_key",
    "shrm_model",
    "kautz_mccool_model",
    "rsibr_model",
    "gaussian_lobes_model",
    "gaussian_transfer_samples",
    "GAUSSIAN_MAX_VIEW_DEG",
]

#: The largest fitted view elevation θ_v of the Gaussian-lobe fits, degrees (just inside the
#: grazing singularity θ_v = 90°); the elevations are spaced evenly on [0, this].
GAUSSIAN_MAX_VIEW_DEG = 89.0


@dataclass(frozen=True)
class Setting:
    """One integer fit setting of a method, with its default and its limits (inclusive).

    Attributes
    ----------
    name
        The keyword of the method's builder, of ``RenderOptions`` / ``CompareOptions`` and
        (hyphenated) of the CLI option.
    default, lo, hi
        The default and the allowed range [lo, hi].
    help
        What it sets, one line.
    """

    name: str
    default: int
    lo: int
    hi: int
    help: str

    def check(self, value: Any) -> int:
        """``value`` as an int; :class:`BadInputError` (a ValueError) when it is not an integer in [lo, hi]."""
        if isinstance(value, bool) or not isinstance(value, Integral) or not self.lo <= int(value) <= self.hi:
            raise BadInputError(None, f"{self.name} must be an integer in [{self.lo}, {self.hi}], got {value!r}")
        return int(value)


@dataclass(frozen=True, eq=False)
class Method:
    """One row of the table of published methods (module docstring).

    Attributes
    ----------
    key
        The one name of the method (API, JSON, reports; the CLI writes ``_`` as ``-``).
    name
        Display name for tables and help.
    cite
        Key into ``data_specs/bibliography.md`` (without brackets).
    summary
        What the model is, one line.
    settings
        The method's own fit settings with their limits. Every method built from an SHRM
        (``uses_shrm``) also takes the SHRM's settings: ``rule`` (or its loose ``eps``,
        ``criterion``, ``max_view_deg``), ``window``, ``lights``, ``pixel_rule``, ``orders``
        (:func:`shrm_model`).
    build
        ``build(env, brdf, **settings) -> model``: the plain model (``model_type``).
    model_type
        The type ``build`` returns.
    uses_shrm
        Whether the model is made from (or is) the SHRM at ε.
    aliases
        Earlier names that still resolve (:func:`get_method` warns).
    """

    key: str
    name: str
    cite: str
    summary: str
    settings: tuple[Setting, ...]
    build: Callable[..., Any]
    model_type: type
    uses_shrm: bool
    aliases: tuple[str, ...] = ()

    def setting(self, name: str) -> Setting:
        """The setting called ``name``; KeyError when the method has none."""
        for s in self.settings:
            if s.name == name:
                return s
        raise KeyError(f"method {self.key!r} has no setting {name!r}")

    def label(self) -> str:
        """``name [cite]``, as tables and help show it."""
        return f"{self.name} [{self.cite}]"


# ------------------------------------------------------------------------------------------
# Builders: each returns a plain model
# ------------------------------------------------------------------------------------------


def shrm_model(
    env: Any,
    brdf: Any,
    *,
    rule: OrderRule | None = None,
    eps: float | None = None,
    window: str = DEFAULT_WINDOW,
    criterion: str | None = None,
    max_view_deg: float | None = None,
    lights: str | int = DEFAULT_LIGHTS,
    pixel_rule: bool = True,
    orders: OrderChoice | None = None,
) -> SHRM:
    """[RH02] The global SHRM of ``env`` and ``brdf`` under the order ``rule``
    (:class:`~shrmkit.analysis.order_rule.OrderRule`, default ``OrderRule()``: tolerance ε, criterion,
    view limit, caps): :func:`~..shrm.prefilter` with the orders of that rule, the window, the
    explicit lights and the pixel rule. ``eps``, ``criterion``, ``max_view_deg``: the rule's fields as
    loose keywords (None: not given; with ``rule`` they must agree with it, as in ``prefilter``).
    ``orders``: the BRDF's order choice made beforehand (same rule).

    Raises :class:`BadInputError` as ``prefilter`` does (ε outside (0, 1), unknown window, a loose
    keyword that disagrees with ``rule`` …).
    """
    rule = resolve_rule(rule, eps=eps, criterion=criterion, max_view_deg=max_view_deg)
    return prefilter(env, brdf, rule=rule, window=window, lights=lights, pixel_rule=pixel_rule, orders=orders)


def kautz_mccool_model(
    env: Any,
    brdf: Any,
    *,
    shrm: SHRM | None = None,
    rule: OrderRule | None = None,
    eps: float | None = None,
    window: str = DEFAULT_WINDOW,
    criterion: str | None = None,
    max_view_deg: float | None = None,
    lights: str | int = DEFAULT_LIGHTS,
    pixel_rule: bool = True,
    orders: OrderChoice | None = None,
) -> SHRM:
    """[KM00] The azimuth-free SHRM: only the q = 0 terms, B(α, β, θ_o) = Σ_p B_p0(α, β) Y_p0(ω_o')
    (RH02 Fig. 9), on the SHRM's own grid: the (F, P) and map rows of ``shrm``, the SHRM under
    ``rule`` (made with :func:`shrm_model` and the other settings when None), so that it differs
    from the SHRM by the azimuthal truncation alone. Its window is decided for the q = 0 field.
    ``rule`` and the loose keywords ``eps``, ``criterion``, ``max_view_deg``: as in :func:`shrm_model`.

    Raises :class:`BadInputError` as :func:`shrm_model` does.
    """
    rule = resolve_rule(rule, eps=eps, criterion=criterion, max_view_deg=max_view_deg)
    if shrm is None:
        shrm = shrm_model(env, brdf, rule=rule, window=window, lights=lights, pixel_rule=pixel_rule, orders=orders)
    return prefilter(env, brdf, rule=rule, F=shrm.F, P=shrm.P, size=shrm.height, azimuth_free=True, window=window,
                     lights=lights)


#: Rows of the reference maps of ``rsibr_model(source="reference")`` (the original method's cost).
RSIBR_REFERENCE_HEIGHT = Setting("reference_height", *RSIBR_REFERENCE_HEIGHT_LIMITS,
                                 "rows of the twelve maps computed by the angular integral (source 'reference')")


def rsibr_model(
    env: Any,
    brdf: Any,
    *,
    shrm: SHRM | None = None,
    source: str = "shrm",
    reference_height: int = RSIBR_REFERENCE_HEIGHT.default,
    **shrm_settings: Any,
) -> RSIBRMaps:
    """[Cabral99] Twelve radiance maps at the icosahedron's vertices, blended per view.

    ``source="shrm"``: the maps taken from the SHRM (``shrm``, or :func:`shrm_model` with
    ``shrm_settings`` when None), at its map size; its explicit lights are reflected into the maps.
    ``source="reference"``: the maps by the brute-force angular integral at ``reference_height``
    rows (the original method's cost; ``shrm`` and ``shrm_settings`` unused).

    Raises :class:`BadInputError` for another ``source`` or a height outside its limits.
    """
    if source == "reference":
        return rsibr_reference(env, brdf, RSIBR_REFERENCE_HEIGHT.check(reference_height))
    if source != "shrm":
        raise BadInputError(None, f"rsibr source must be 'shrm' or 'reference', got {source!r}")
    return rsibr_from_shrm(shrm_model(env, brdf, **shrm_settings) if shrm is None else shrm)


#: The Gaussian-lobe fit's settings (their limits: ``data_specs/methods.md``).
GAUSSIAN_LOBES = Setting("lobes", *GAUSSIAN_LOBES_LIMITS, "lobes per view elevation K")
GAUSSIAN_ELEVATIONS = Setting("elevations", *GAUSSIAN_ELEVATIONS_LIMITS, f"fitted view elevations, evenly on [0, "
                              f"{GAUSSIAN_MAX_VIEW_DEG:g}] deg")


def gaussian_transfer_samples(brdf: Any, elevations: int = GAUSSIAN_ELEVATIONS.default) -> TransferSamples:
    """The fit's samples of the BRDF's transfer function at ``elevations`` view elevations evenly on
    [0, :data:`GAUSSIAN_MAX_VIEW_DEG`] (:func:`~.gaussian_lobes.transfer_samples`, 120 × 60 grid):
    make them once to fit several K. Raises :class:`BadInputError` for ``elevations`` out of limits."""
    n = GAUSSIAN_ELEVATIONS.check(elevations)
    return transfer_samples(brdf, np.linspace(0.0, np.radians(GAUSSIAN_MAX_VIEW_DEG), n))


def gaussian_lobes_model(
    env: Any,
    brdf: Any,
    *,
    lobes: int = GAUSSIAN_LOBES.default,
    elevations: int = GAUSSIAN_ELEVATIONS.default,
    samples: TransferSamples | None = None,
    stack: Any = None,
) -> GaussianLobeModel:
    """[Green07] K = ``lobes`` isotropic Gaussian lobes fitted at ``elevations`` view elevations
    (:func:`~.gaussian_lobes.fit_gaussian_lobes`) over the spherical-Gaussian mip stack of ``env``
    (:func:`~.gaussian_lobes.sg_mip_stack`). ``samples`` (:func:`gaussian_transfer_samples`, then
    ``elevations`` is theirs) and ``stack`` let several K share them.

    Raises :class:`BadInputError` for settings out of their limits or a BRDF that is zero at a view.
    """
    K = GAUSSIAN_LOBES.check(lobes)
    if samples is None:
        samples = gaussian_transfer_samples(brdf, elevations)
    fit = fit_gaussian_lobes(brdf, K, samples=samples)
    return GaussianLobeModel(fit, sg_mip_stack(env) if stack is None else stack)


# ------------------------------------------------------------------------------------------
# The table
# ------------------------------------------------------------------------------------------

_TABLE = (
    Method("shrm", "SHRM", "RH02", "spherical harmonic reflection map: (P+1)^2 maps B_pq(R), summed per view",
           (), shrm_model, SHRM, True),
    Method("kautz_mccool", "Kautz-McCool", "KM00", "the azimuth-free (q = 0) SHRM on the SHRM's (F, P) and map",
           (), kautz_mccool_model, SHRM, True),
    Method("rsibr", "RSIBR (Cabral et al.)", "Cabral99",
           "twelve maps at the icosahedron's vertices, blended per view with spherical barycentric weights",
           (RSIBR_REFERENCE_HEIGHT,), rsibr_model, RSIBRMaps, True, aliases=("cabral", "cabral_shrm")),
    Method("gaussian_lobes", "Gaussian lobes (Green et al.)", "Green07",
           "K isotropic Gaussian lobes per view elevation over a spherical-Gaussian mip stack",
           (GAUSSIAN_LOBES, GAUSSIAN_ELEVATIONS), gaussian_lobes_model, GaussianLobeModel, False,
           aliases=("gaussian", "green", "green_lobes")),
)

#: The published methods by key, in table order.
METHODS: Mapping[str, Method] = MappingProxyType({m.key: m for m in _TABLE})
_ALIASES = {alias: m.key for m in _TABLE for alias in m.aliases}


def method_key(name: str) -> str:
    """The key of the method called ``name``: a key, its CLI spelling (``-`` for ``_``) or an earlier
    name (with a :class:`DeprecationWarning` naming the key). :class:`BadInputError` naming the keys
    otherwise."""
    if not isinstance(name, str):
        raise BadInputError(None, f"a method name must be a string, got {name!r}")
    key = name.strip().lower().replace("-", "_")
    if key in METHODS:
        return key
    if key in _ALIASES:
        new = _ALIASES[key]
        warnings.warn(f"method name {name!r} is deprecated: use {new!r}", DeprecationWarning, stacklevel=2)
        return new
    raise BadInputError(None, f"unknown method {name!r}; known: {', '.join(METHODS)}")


def get_method(name: str) -> Method:
    """The :class:`Method` called ``name`` (:func:`method_key`: keys, CLI spellings, earlier names)."""
    return METHODS[method_key(name)]
