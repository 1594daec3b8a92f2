"""Options of a BRDF accuracy report, with a ``quick`` and a ``full`` profile.

Everything that changes the numbers of a report is an option here and is recorded in
``report.json`` (``data_specs/report_json.md``), so a report can be reproduced.
"""

from __future__ import annotations

import copy
import inspect
import math
from dataclasses import dataclass, field, fields, replace
from typing import Any

from ...analysis.fit.models_param import MODELS
from ...analysis.lights import DEFAULT_LIGHTS, check_lights
from ...analysis.order_rule import RULE_FIELDS, OrderRule, RuleFields, init_options
from ...analysis.shrm import DEFAULT_WINDOW, check_window
from ...analysis.tolerance import check_eps
from ...brdf_io.errors import BadInputError
from ..common import load_oriented_env

__all__ = ["ReportOptions", "DEFAULT_TOLERANCES", "DEFAULT_MODELS", "PREVIEW_MODES", "profile"]

DEFAULT_TOLERANCES = (0.1, 0.03, 0.01)
DEFAULT_MODELS = ("lafortune", "cook-torrance")
#: ``auto``: OpenGL when an offscreen context works, else the CPU reference renderer;
#: ``gl``, ``cpu``: force one; ``none``: no preview.
PREVIEW_MODES = ("auto", "gl", "cpu", "none")


@dataclass(frozen=True, init=False)
class ReportOptions(RuleFields):
    """What a report computes and at which cost.

    The order rule is one value, :attr:`rule` (:class:`~shrmkit.analysis.order_rule.OrderRule`);
    the keywords ``eps``, ``max_F``, ``max_P``, ``criterion`` and ``max_view_deg`` set its fields
    (over a ``rule=`` given too: :meth:`with_changes` and ``dataclasses.replace`` take either, a new
    ``rule=`` or a changed keyword) and read them back; an unknown keyword raises ``TypeError``.
    :meth:`as_dict` writes them under their own names, as before the rule.

    Attributes
    ----------
    rule
        The order rule of every choice of orders and SHRM of the report.
    eps
        Main tolerance ε (``rule.eps``): the scene orders, residual bound and preview use it.
    tolerances
        Tolerances of the order table and the speed-against-error rows (``eps`` is added).
    envs
        Environment specs or files (``shrmkit.load_env``).
    env_up, env_flip, env_azimuth
        Orientation of environment *files* (``load_env``'s ``up``, ``flip``, ``azimuth``);
        built-in environments only take the azimuth.
    env_layer, env_part
        The layer / part of OpenEXR environment files (``load_env``'s ``layer``, ``part``).
    env_height
        Environments are area-resampled to ``env_height`` × 2·``env_height``: the angular
        reference sums every pixel for every (R, V) pair, so keep it small.
    models
        Models fitted (``shrmkit.fit_brdf``): ``lafortune``, ``cook-torrance``, ``microfacet``.
    lobes
        Lafortune lobes.
    fit_samples, fit_starts
        ``n_samples`` and ``starts`` of ``fit_brdf``.
    n_pairs
        Random (R, V) pairs on which the SHRM is compared with the angular reference.
    seed
        Seed of every random choice (pairs, fit samples, fit starts).
    max_F, max_P
        Caps of ``choose_orders`` (``rule.max_F``, ``rule.max_P``): those of ``shrm orders`` (512,
        20), so the two choose the same orders (the quick profile caps F at 96 and says so).
    preview, preview_size, mesh
        Preview renderer (:data:`PREVIEW_MODES`), image size in pixels, and an optional mesh
        (file or ``builtin:``) rendered besides the sphere.
    albedo_nodes
        Gauss–Legendre nodes in cos θ_i of the directional-albedo quadrature (2× as many in φ).
    window
        The prefilter's window against Gibbs ringing (``analysis.shrm.WINDOWS``, default
        ``"auto"``) of every SHRM of the report (errors and preview).
    criterion, max_view_deg
        The order rule and its view limit (``rule.criterion``, ``rule.max_view_deg``;
        ``analysis.view_bands``); the measured errors are sampled up to the same view limit.
    lights
        The explicit lights of every SHRM of the report (``prefilter(lights=)``; ``"auto"``,
        ``"none"`` or N): the report lists them per environment.
    plots
        Draw the matplotlib plots (``plots.py``): True by default; False (``--no-plots``) leaves
        them out of the folder and the pages — every number stays in ``report.json`` and the
        tables. The plots are most of a quick report's time (1.5–2 s of ~2.3 s on 2 cores), so a
        census of a large library runs ~3× faster without them.
    explorer_plots
        Also draw the BRDF views' plots (``plots.EXPLORER_PLOTS``: the fit slices and BRDF
        Explorer's slice, samples, polar and albedo plots; ~1 s CPU of a quick report): True by
        default, False in the ``quick`` profile (``--explorer-plots`` draws them there). Their
        numbers are in ``report.json`` either way; the RH02 plots (energy, ε by P, speed against
        error) and the fits' band errors are drawn whenever ``plots`` is.
    """

    tolerances: tuple[float, ...] = DEFAULT_TOLERANCES
    envs: tuple[str, ...] = ("builtin:sky",)
    env_height: int = 64
    env_up: str | None = None
    env_flip: bool = False
    env_azimuth: float = 0.0
    env_layer: str | None = None
    env_part: str | int | None = None
    models: tuple[str, ...] = DEFAULT_MODELS
    lobes: int = 1
    fit_samples: int = 16384
    fit_starts: int = 4
    n_pairs: int = 300
    seed: int = 0
    # the caps of `shrm orders` (analysis.orders), so that both choose the same (F, P): the search
    # starts from ε(min(F0, max_F), p), so a lower cap moves P, and F with it, even when F stays
    # below it (microfacet σ = 0.03 at ε = 0.01: (241, 18) under 256, (274, 17) under 512; issue 29)
    preview: str = "auto"
    preview_size: int = 192
    mesh: str | None = None
    albedo_nodes: int = 64
    window: str = DEFAULT_WINDOW
    lights: str | int = DEFAULT_LIGHTS
    plots: bool = True
    explorer_plots: bool = True
    profile: str = field(default="full")
    rule: OrderRule = OrderRule()

    def __init__(self, *args: Any, **options: Any) -> None:
        if len(args) > len(_KEYWORDS):
            raise TypeError(f"ReportOptions() takes at most {len(_KEYWORDS)} positional arguments")
        for name, value in zip(_KEYWORDS[: len(args)], args, strict=True):  # eps first, as before the rule
            if name in options:
                raise TypeError(f"ReportOptions() got multiple values for argument {name!r}")
            options[name] = value
        init_options(self, options, {name: name for name in RULE_FIELDS})
        self.__post_init__()

    def __post_init__(self) -> None:
        check_window(self.window)
        object.__setattr__(self, "lights", check_lights(self.lights))
        for tol in self.tolerances:
            check_eps(tol, "every tolerance")
        if not 4 <= self.env_height <= 2048:
            raise BadInputError(None, f"env_height must be in [4, 2048], got {self.env_height!r}")
        if self.n_pairs < 1:
            raise BadInputError(None, f"n_pairs must be >= 1, got {self.n_pairs!r}")
        if self.preview not in PREVIEW_MODES:
            raise BadInputError(None, f"preview must be one of {', '.join(PREVIEW_MODES)}, got {self.preview!r}")
        if not 16 <= self.preview_size <= 2048:
            raise BadInputError(None, f"preview_size must be in [16, 2048], got {self.preview_size!r}")
        if not self.envs:
            raise BadInputError(None, "at least one environment is needed")
        if self.env_up not in (None, "z", "y"):
            raise BadInputError(None, f"env_up must be 'z', 'y' or None, got {self.env_up!r}")
        if not math.isfinite(self.env_azimuth):
            raise BadInputError(None, f"env_azimuth must be finite, got {self.env_azimuth!r}")
        if self.albedo_nodes < 8:
            raise BadInputError(None, f"albedo_nodes must be >= 8, got {self.albedo_nodes!r}")

        for model in self.models:
            if model not in MODELS:
                raise BadInputError(None, f"unknown model {model!r}; choose from {', '.join(MODELS)}")

    @property
    def all_tolerances(self) -> tuple[float, ...]:
        """``tolerances`` and ``eps``, without repeats, loosest first."""
        return tuple(sorted({float(t) for t in (*self.tolerances, self.rule.eps)}, reverse=True))

    def with_changes(self, **changes: Any) -> ReportOptions:
        """A copy with some options changed (validated again)."""
        return replace(self, **changes)

    def as_dict(self) -> dict[str, Any]:
        """JSON-able record of the options (``report.json`` ``options``): every constructor keyword
        in declaration order, the rule's fields under their own names (no ``rule`` key)."""
        d = {name: copy.deepcopy(getattr(self, name)) for name in _KEYWORDS}
        d["tolerances"] = list(self.all_tolerances)
        d["envs"] = list(self.envs)
        d["models"] = list(self.models)
        return d


#: the constructor's keywords in the order of ``report.json``'s ``options`` (the rule's fields where
#: they stood when they were keywords of their own)
_KEYWORDS = ("eps", "tolerances", "envs", "env_height", "env_up", "env_flip", "env_azimuth", "env_layer", "env_part",
             "models", "lobes", "fit_samples", "fit_starts", "n_pairs", "seed", "max_F", "max_P", "preview",
             "preview_size", "mesh", "albedo_nodes", "window", "criterion", "max_view_deg", "lights", "plots",
             "explorer_plots", "profile")
assert set(_KEYWORDS) == {f.name for f in fields(ReportOptions) if f.name != "rule"} | set(RULE_FIELDS)
# what help() and editors show: every keyword with its default (the rule's fields: None, the rule's own)
ReportOptions.__signature__ = inspect.Signature(  # type: ignore[attr-defined]
    [inspect.Parameter(name, inspect.Parameter.POSITIONAL_OR_KEYWORD,
                       default=None if name in RULE_FIELDS else ReportOptions.__dataclass_fields__[name].default)
     for name in _KEYWORDS]
    + [inspect.Parameter("rule", inspect.Parameter.KEYWORD_ONLY, default=OrderRule())])


def profile(name: str = "full", **changes: Any) -> ReportOptions:
    """The ``full`` (default options) or ``quick`` profile, with ``changes`` applied.

    ``quick`` (tests and ``shrm demo``): environments of 32 rows, 150 (R, V) pairs, fits on
    4096 samples from one start, orders capped at F <= 96, a 128-pixel preview, and the RH02
    plots without the BRDF views' plots (``explorer_plots=False``).
    """
    if name == "full":
        return ReportOptions(**changes)
    if name == "quick":
        base: dict[str, Any] = dict(
            env_height=32, n_pairs=150, fit_samples=4096, fit_starts=1, max_F=96, preview_size=128,
            albedo_nodes=48, explorer_plots=False, profile="quick",
        )
        base.update(changes)
        return ReportOptions(**base)
    raise BadInputError(None, f"unknown report profile {name!r}; choose 'quick' or 'full'")


def load_report_env(spec: str, options: ReportOptions):  # -> EnvironmentMap
    """Load one of ``options.envs`` at ``env_height`` rows with the orientation options
    (the CLI's one rule, :func:`~shrmkit.cli.common.load_oriented_env`)."""
    return load_oriented_env(spec, up=options.env_up, flip=options.env_flip, azimuth=options.env_azimuth,
                             layer=options.env_layer, part=options.env_part, height=options.env_height)
