"""The render-mode table: one :class:`RenderMode` record per way of shading a mesh.

Each mode draws one published method of :mod:`shrmkit.analysis.baselines.methods` (``method``,
its key there), whose builder makes the model with the table's settings and limits; the record
adds what the renderer needs: ``build(env, brdf, mesh, *, eps, options) -> BuiltModel`` (the
model, its numbers, the lines ``shrm render`` prints), ``models`` (the types
:meth:`SHRMRenderer.add_object` accepts), ``shading`` and the per-frame ``update``
(``render.glsl``), ``self_shadow`` (per-vertex SH visibility [Green07] eq. 7) and ``uses_orders``
(``RenderOptions(orders=)`` chooses the BRDF's orders once for several environments).

- ``distant`` (method ``shrm``): [RH02] eq. 12, one SHRM map per frame, looked up by R;
- ``perpixel`` (``shrm``): [RH02] eq. 8, Σ B̃_pq(R) Y_pq(V) in the fragment shader;
- ``rsibr`` (``rsibr``): [Cabral99], twelve maps from the SHRM, blended per frame;
- ``kautz-mccool`` (``kautz_mccool``): [KM00], the q = 0 SHRM on the SHRM's (F, P), per pixel;
- ``gaussian-lobes`` (``gaussian_lobes``): [Green07], Gaussian lobes over an SG mip stack.

Adding a mode: its method in the table of methods, its ``shading`` (and ``update``), its
``build``, one :class:`RenderMode` entry in :data:`RENDER_MODES` below, and its one-line help in
``render/defaults.py`` (``RENDER_MODE_HELP``, numpy-free, which ``shrm render --mode`` shows;
``SELF_SHADOW_MODES``/``LOBE_OPTION_MODES`` there too when it has those options: the mirrors are
checked by ``tests/cli/test_cli_startup.py``). Citation keys: ``data_specs/bibliography.md``.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..analysis.baselines.gaussian_lobes import GaussianLobeModel
from ..analysis.baselines.methods import (
    GAUSSIAN_ELEVATIONS,
    GAUSSIAN_LOBES,
    METHODS,
    Method,
    gaussian_lobes_model,
    kautz_mccool_model,
    rsibr_model,
    shrm_model,
)
from ..analysis.baselines.rsibr import RSIBRMaps
from ..analysis.baselines.selfshadow import vertex_visibility_sh
from ..analysis.lights import DEFAULT_LIGHTS, check_lights
from ..analysis.order_rule import OrderRule, RuleView, init_options
from ..analysis.orders import OrderChoice
from ..analysis.pixels import pixel_line
from ..analysis.shrm import DEFAULT_WINDOW, SHRM, check_window
from ..brdf_io.brdf import BRDF
from ..brdf_io.env_rotation import check_env_rotation
from ..brdf_io.envmap import EnvironmentMap
from ..brdf_io.errors import BadInputError
from .brdf_glsl import LightShading
from .gaussian_shader import gaussian_shading
from .glsl import Shading
from .mesh import Mesh
from .shader import (
    cached_light_shading,
    distant_shading,
    distant_update,
    perpixel_shading,
    rsibr_shading,
    rsibr_update,
)

__all__ = [
    "RenderOptions",
    "BuiltModel",
    "RenderMode",
    "RENDER_MODES",
    "DEFAULT_MODE",
    "mode_names",
    "get_mode",
    "self_shadow_modes",
    "lights_info",
]

#: Gaussian lobes per view elevation and fitted elevations allowed: the limits of the table of
#: published methods (``analysis.baselines.methods``), one home.
LOBES_RANGE = (GAUSSIAN_LOBES.lo, GAUSSIAN_LOBES.hi)
ELEVATIONS_RANGE = (GAUSSIAN_ELEVATIONS.lo, GAUSSIAN_ELEVATIONS.hi)


@dataclass(frozen=True, init=False)
class RenderOptions(RuleView):
    """Options of the model builders, keyword-only; a mode uses those it needs.

    Attributes
    ----------
    lobes
        ``gaussian-lobes``: lobes per view elevation K, in [1, 8] (``GAUSSIAN_LOBES`` of
        :mod:`shrmkit.analysis.baselines.methods`).
    elevations
        ``gaussian-lobes``: fitted view elevations, in [1, 64] (``GAUSSIAN_ELEVATIONS``).
    self_shadow
        Per-vertex SH visibility by ray casting (Green et al. 2007 eq. 7); only for the modes
        whose record has ``self_shadow`` (:func:`self_shadow_modes`).
    window
        The SHRM modes' window against Gibbs ringing, one of ``analysis.shrm.WINDOWS``
        (``prefilter(window=)``; default ``"auto"``).
    rule
        The SHRM modes' order rule (:class:`~shrmkit.analysis.order_rule.OrderRule`: criterion, view
        limit, caps; :mod:`shrmkit.analysis.view_bands`; default ``OrderRule()``). Its tolerance is
        replaced by the render's ``eps`` argument: :meth:`rule_at` is the rule the SHRMs are made
        under.
    criterion, max_view_deg
        ``rule.criterion`` and ``rule.max_view_deg``, read back from :attr:`rule`; as keywords they
        set those fields of ``rule`` (over a ``rule=`` given too; ``dataclasses.replace`` works with
        either). An unknown keyword raises ``TypeError``.
    lights
        The SHRM modes' explicit lights (``prefilter(lights=)``: ``"auto"``, ``"none"`` or at most
        N lights; validated by :func:`~shrmkit.analysis.lights.check_lights`): the compact bright
        regions of the map are taken out and shaded exactly per pixel (``render.brdf_glsl``).
        ``rsibr`` reflects them into its twelve maps instead (Cabral et al.'s maps hold everything).
    pixel_rule
        The SHRM modes' pixel rule (``prefilter(pixel_rule=)``, default True: F_B raised until 90 %
        of the directions are within √ε; :mod:`shrmkit.analysis.pixels`).
    env_rotation
        Every mode: the environment rotated at view time (``brdf_io.env_rotation``; nothing is
        prefiltered or fitted again): None; one rotation for every frame, a (3, 3) matrix or Euler
        angles (AZ, EL[, ROLL]) in degrees (AZ in the sense of ``load_env(azimuth=)``); or a
        sequence of (3, 3) matrices, one per camera (a lighting turntable,
        ``pipeline.light_turntable_rotations``). Stored as row-major 9-tuples; :meth:`rotations`
        gives the matrices. The lights and the ``"env"`` background turn with the map.
    orders
        The SHRM modes' (records with ``uses_orders``): the BRDF's
        :class:`~shrmkit.analysis.orders.OrderChoice`, chosen beforehand at the same ε, criterion and
        view limit (``prefilter(orders=)``; a mismatch is refused there), so that a sequence of
        environments chooses them once (:func:`shrmkit.render.api.render_sequence`); None (default):
        each build chooses them. The other modes ignore it.
    """

    lobes: int = GAUSSIAN_LOBES.default
    elevations: int = GAUSSIAN_ELEVATIONS.default
    self_shadow: bool = False
    window: str = DEFAULT_WINDOW
    lights: str | int = DEFAULT_LIGHTS
    pixel_rule: bool = True
    env_rotation: Any = None
    orders: OrderChoice | None = field(default=None, compare=False, repr=False)
    rule: OrderRule = OrderRule()

    def __init__(self, **options: Any) -> None:
        init_options(self, options, {"criterion": "criterion", "max_view_deg": "max_view_deg"})
        self.__post_init__()

    def __post_init__(self) -> None:
        object.__setattr__(self, "env_rotation", _rotation_tuples(self.env_rotation))
        if self.orders is not None and not isinstance(self.orders, OrderChoice):
            raise BadInputError(None, f"orders must be an OrderChoice (analysis.orders.choose_orders) or None, "
                                f"got {type(self.orders).__name__}")
        check_window(self.window)
        if not isinstance(self.pixel_rule, bool):
            raise BadInputError(None, f"pixel_rule must be True or False, got {self.pixel_rule!r}")
        object.__setattr__(self, "lights", check_lights(self.lights))
        for setting in (GAUSSIAN_LOBES, GAUSSIAN_ELEVATIONS):
            setting.check(getattr(self, setting.name))

    def rule_at(self, eps: float | None) -> OrderRule:
        """The SHRM modes' :class:`~shrmkit.analysis.order_rule.OrderRule` at tolerance ``eps``:
        :attr:`rule` with ``eps`` (None: :attr:`rule` as it is).

        Raises
        ------
        BadInputError
            ``eps`` out of range.
        """
        return self.rule if eps is None else self.rule.replace(eps=eps)

    def rotations(self) -> np.ndarray | list[np.ndarray] | None:
        """``env_rotation`` as ``render_frames`` takes it: None, one (3, 3) matrix, or a list of them."""
        if self.env_rotation is None:
            return None
        matrices = [np.array(r, dtype=np.float64).reshape(3, 3) for r in self.env_rotation]
        return matrices[0] if len(matrices) == 1 else matrices


def _rotation_tuples(value: Any) -> tuple[tuple[float, ...], ...] | None:
    """:attr:`RenderOptions.env_rotation` normalized: None, or row-major 9-tuples (one, or one per camera)."""
    if value is None:
        return None
    if isinstance(value, tuple) and value and all(isinstance(r, tuple) and len(r) == 9 for r in value):
        value = [np.reshape(r, (3, 3)) for r in value]  # already normalized (dataclasses.replace)
    try:
        many = np.ndim(value) == 3
    except ValueError:  # ragged
        many = False
    rotations = [check_env_rotation(r) for r in value] if many else [check_env_rotation(value)]
    if not rotations:
        raise BadInputError(None, "env_rotation: an empty sequence of rotations")
    return tuple(tuple(float(x) for x in r.reshape(-1)) for r in rotations if r is not None)  # never None here


@dataclass(frozen=True, eq=False)
class BuiltModel:
    """A mode's model of the scene.

    Attributes
    ----------
    model
        What the renderer draws (``RenderMode.models``).
    info
        Numbers about it: orders, ε, seconds of each stage, fit residual … (keys per mode).
    description
        Lines that describe it, as ``shrm render`` prints them.
    visibility_sh
        (n_vertices, 25) per-vertex SH visibility for self-shadowing, or None.
    """

    model: Any
    info: dict[str, Any] = field(default_factory=dict)
    description: tuple[str, ...] = ()
    visibility_sh: np.ndarray | None = None


@dataclass(frozen=True, eq=False)
class RenderMode:
    """One row of the render-mode table (module docstring)."""

    name: str
    help: str
    build: Callable[..., BuiltModel]
    models: tuple[type, ...]
    shading: Callable[..., Shading]
    update: Callable[[Any, np.ndarray, np.ndarray], None] | None = None
    self_shadow: bool = False
    uses_orders: bool = False
    method: str | None = None
    #: its ``shading`` takes ``views=`` (the SHRM modes' lights: a measured BRDF's table only for them)
    light_views: bool = False

    @property
    def published(self) -> Method | None:
        """The published method the mode draws (its row of the table of methods), or None for a
        mode added outside the table."""
        return None if self.method is None else METHODS[self.method]

    def prepare(
        self, model: Any, mesh: Mesh, visibility_sh: np.ndarray | None = None, normalized_visibility: bool = True,
        *, views: Sequence[tuple[np.ndarray, float]] | None = None,
    ) -> Shading:
        """Check ``model`` and ``visibility_sh`` against the mode and make its :class:`Shading`.

        ``views``: None, or every direction toward the eye the frames will shade, as cones (unit
        axis, half-angle in radians) in the unrotated environment's frame
        (``pipeline.view_cones``): a mode with ``light_views`` then tabulates a measured BRDF's
        table only in the θ_d rows they read (``brdf_glsl.light_shading(views=)``); the Shading
        draws no other views correctly. The other modes ignore it.

        Raises ValueError for a model of another type, or visibility in a mode without
        self-shadowing, or visibility that is not finite (n_vertices, 25).
        """
        if not isinstance(model, self.models):
            names = " or ".join(t.__name__ for t in self.models)
            raise ValueError(f"mode {self.name!r} takes a {names}, got {type(model).__name__}")
        if visibility_sh is None:
            return self.shading(model, mesh, views=views) if self.light_views else self.shading(model, mesh)
        if not self.self_shadow:
            raise ValueError(f"visibility_sh (self-shadowing) is only supported in mode "
                             f"{' or '.join(repr(m) for m in self_shadow_modes())}, not {self.name!r}")
        visibility_sh = np.asarray(visibility_sh, dtype=np.float64)
        if visibility_sh.shape != (mesh.vertices.shape[0], 25) or not np.all(np.isfinite(visibility_sh)):
            raise ValueError(f"visibility_sh must be finite (n_vertices={mesh.vertices.shape[0]}, 25), "
                             f"got shape {visibility_sh.shape}")
        return self.shading(model, mesh, visibility_sh, normalized_visibility)


# ------------------------------------------------------------------------------------------
# Builders
# ------------------------------------------------------------------------------------------


def lights_info(shrm: SHRM, *, per_pixel: bool = True) -> tuple[dict[str, Any], str]:
    """``BuiltModel.info["lights"]`` and the ``lights:`` line of an SHRM's explicit lights: the
    lights (``SHRM.meta["lights"]``), their sample count and how they are shaded: per pixel by the
    BRDF's GLSL (``render.brdf_glsl``; a measured BRDF's table with its measured error), or
    (``per_pixel=False``, rsibr) reflected into the mode's maps."""
    described = shrm.info.lights
    requested = described.requested if described.requested is not None else "none"
    if not shrm.has_lights:
        return ({"requested": requested, "count": 0, "samples": 0, "lights": []},
                f"lights: none ({'none requested' if requested == 'none' else 'no compact bright region'})")
    assert shrm.lights is not None  # has_lights
    lights = list(described.lights)
    share = described.flux_share or 0.0
    info: dict[str, Any] = {
        "requested": requested, "count": len(lights), "samples": len(shrm.lights), "flux_share": share,
        "left_in_map": described.left_in_map, "lights": lights,
    }
    line = f"lights: {len(lights)} ({len(shrm.lights)} samples, {100 * share:.3g} % of the map's flux), "
    if not per_pixel:
        info["shaded"] = "maps"
        return info, line + "reflected into the twelve maps at their resolution"
    shading = cached_light_shading(shrm)
    assert shading is not None  # has_lights
    info.update({"shaded": "per pixel", "brdf_glsl": shading.shader.source})
    if shading.table is not None:
        info["brdf_table"] = _table_info(shading)
    return info, line + shading.describe()


def _table_info(shading: LightShading) -> dict[str, Any]:
    """``info["lights"]["brdf_table"]`` of a shading with a table (``data_specs/render_outputs.md``):
    its ``shape``, ``missing`` (of the samples evaluated), ``seconds``, what it covers —
    ``theta_d_rows`` (inclusive [first, last] θ_d row runs tabulated whole; every row for a whole
    table) and ``texels`` (tabulated, of ``shape``'s product) — and its error dict
    (``choose_table``)."""
    table = shading.table
    assert table is not None  # a shading with a table
    nd = table.shape[1]
    rows = [[0, nd - 1]] if table.rows is None else [list(run) for run in table.rows]
    return {"shape": list(table.shape), "missing": table.missing, "seconds": table.seconds,
            "theta_d_rows": rows, "texels": table.tabulated, **(shading.table_error or {})}


def _shrm_settings(eps: float, options: RenderOptions) -> dict[str, Any]:
    """The SHRM's settings of the table's builders (``analysis.baselines.methods.shrm_model``)."""
    return {"rule": options.rule_at(eps), "window": options.window, "lights": options.lights,
            "pixel_rule": options.pixel_rule, "orders": options.orders}


def _prefiltered(
    env: EnvironmentMap, brdf: BRDF, eps: float, options: RenderOptions, *, azimuth_free: bool = False,
    per_pixel_lights: bool = True,
) -> BuiltModel:
    t0 = time.perf_counter()
    build = kautz_mccool_model if azimuth_free else shrm_model  # [KM00] on the SHRM's (F, P) and rows
    shrm = build(env, brdf, **_shrm_settings(eps, options))
    seconds = time.perf_counter() - t0
    light_info, light_line = lights_info(shrm, per_pixel=per_pixel_lights)
    stated, window = shrm.info, shrm.info.window
    info = {"F": shrm.F, "P": shrm.P, "height": shrm.height, "width": shrm.width, "eps": eps,
            "achieved_eps": dict(shrm.eps), "azimuth_free": azimuth_free, "prefilter_seconds": seconds,
            "criterion": stated.criterion, "max_view_deg": stated.max_view_deg,
            "view_bands": [band.to_json() for band in stated.view_bands],
            "window": window.used, "window_requested": window.requested, "window_strength": window.strength,
            "window_reason": window.reason, "negative_before": window.negative_before,
            "negative_after": window.negative_after,
            "negative_fraction_after": window.negative_fraction_after,
            "pixel_errors": stated.pixel_errors, "pixel_rule": stated.pixel_rule, "lights": light_info}
    lines = (f"SHRM F={shrm.F} P={shrm.P} on {shrm.height}x{shrm.width} ({stated_line(shrm, eps)})",
             f"window: {window.describe()} ({window.reason})", pixel_line(stated),
             light_line, f"prefilter: {seconds:.3f} s")
    return BuiltModel(shrm, info, lines)


def stated_line(shrm: SHRM, eps: float) -> str:
    """The SHRM's stated error as a user reads it: the worst view band inside the rule's view limit,
    predicted and bound, as relative RMS radiance errors (the units of a measured error), beside
    the tolerance and its √ε — not ε_B, an energy fraction over all views that reads like failure."""
    bands = shrm.info.bands_inside()
    if not bands:
        return f"eps {eps:g}, predicted eps_B {shrm.eps['reflected']:.3g} over all views"
    worst = max((b.bound_rel_rms for b in bands if b.bound_rel_rms is not None), default=float("nan"))
    predicted = max((b.predicted_rel_rms for b in bands if b.predicted_rel_rms is not None), default=float("nan"))
    return (f"eps {eps:g}: worst view band to {shrm.info.max_view_deg:g} deg, relative RMS predicted "
            f"{predicted:.3g}, bound {worst:.3g}; sqrt(eps) {eps ** 0.5:.3g}")


def build_shrm(env: EnvironmentMap, brdf: BRDF, mesh: Mesh, *, eps: float, options: RenderOptions) -> BuiltModel:
    """[RH02] The global SHRM of ``env`` and ``brdf`` at tolerance ``eps`` (``methods.shrm_model``)."""
    return _prefiltered(env, brdf, eps, options)


def build_kautz_mccool(
    env: EnvironmentMap, brdf: BRDF, mesh: Mesh, *, eps: float, options: RenderOptions
) -> BuiltModel:
    """[KM00] The azimuth-free (q = 0) SHRM on the SHRM's (F, P) and map rows
    (``methods.kautz_mccool_model``; ``prefilter_seconds`` counts the SHRM too)."""
    return _prefiltered(env, brdf, eps, options, azimuth_free=True)


def build_rsibr(env: EnvironmentMap, brdf: BRDF, mesh: Mesh, *, eps: float, options: RenderOptions) -> BuiltModel:
    """Cabral et al. 1999: the SHRM, then its twelve maps at the icosahedron's vertices; the SHRM's
    explicit lights are reflected into the maps (``rsibr_from_shrm``: the method's maps hold the
    whole radiance, at their own resolution), not shaded per pixel."""
    built = _prefiltered(env, brdf, eps, options, per_pixel_lights=False)
    maps = rsibr_model(env, brdf, shrm=built.model)
    return BuiltModel(maps, {**built.info, "rsibr_seconds": float(maps.meta["seconds"])}, built.description)


def build_gaussian_lobes(
    env: EnvironmentMap, brdf: BRDF, mesh: Mesh, *, eps: float, options: RenderOptions
) -> BuiltModel:
    """[Green07] K lobes fitted at the view elevations over the SG mip stack of ``env``
    (``methods.gaussian_lobes_model``), and (``options.self_shadow``) the per-vertex SH visibility
    of ``mesh``. ``eps`` is not used."""
    model = gaussian_lobes_model(env, brdf, lobes=options.lobes, elevations=options.elevations)
    lobes, stack = model.lobes, model.stack
    residual = float(lobes.residual.max())
    info: dict[str, Any] = {
        "K": lobes.K, "elevations": int(lobes.theta_v.size), "max_fit_residual": residual,
        "fit_seconds": float(lobes.meta["seconds"]), "mip_levels": len(stack.levels),
        "sigma_min": float(stack.sigmas[0]), "sigma_max": float(stack.sigmas[-1]), "mip_seconds": stack.seconds,
    }
    lines = [
        f"Gaussian lobes K={lobes.K} at {lobes.theta_v.size} elevations, max relative fit error {residual:.3g}",
        f"fit: {info['fit_seconds']:.3f} s",
        f"SG mip stack: {len(stack.levels)} levels, sigma {stack.sigmas[0]:.4g}..{stack.sigmas[-1]:.4g} rad, "
        f"{stack.seconds:.3f} s",
    ]
    visibility = None
    if options.self_shadow:
        t0 = time.perf_counter()
        visibility = vertex_visibility_sh(mesh)
        info["visibility_seconds"] = time.perf_counter() - t0
        lines.append(f"self-shadowing: order-4 SH visibility of {len(mesh.vertices)} vertices, "
                     f"{info['visibility_seconds']:.3f} s")
    return BuiltModel(model, info, tuple(lines), visibility)


# ------------------------------------------------------------------------------------------
# The table
# ------------------------------------------------------------------------------------------

_MODES = (
    RenderMode("distant", "distant viewer (RH02 eq. 12): one SHRM map per frame, looked up by R",
               build_shrm, (SHRM,), distant_shading, distant_update, uses_orders=True, method="shrm",
               light_views=True),
    RenderMode("perpixel", "per-pixel view direction (RH02 eq. 8): the SHRM summed in the fragment shader",
               build_shrm, (SHRM,), perpixel_shading, uses_orders=True, method="shrm", light_views=True),
    RenderMode("rsibr", "Cabral et al. 1999: 12 maps at the icosahedron's vertices, blended per frame",
               build_rsibr, (RSIBRMaps, SHRM), rsibr_shading, rsibr_update, uses_orders=True, method="rsibr"),
    RenderMode("kautz-mccool", "Kautz & McCool 2000: the azimuth-free (q = 0) SHRM on the SHRM's (F, P), per pixel",
               build_kautz_mccool, (SHRM,), perpixel_shading, uses_orders=True, method="kautz_mccool",
               light_views=True),
    RenderMode("gaussian-lobes", "Green et al. 2007: K Gaussian lobes per view elevation over an SG mip stack",
               build_gaussian_lobes, (GaussianLobeModel,), gaussian_shading, self_shadow=True,
               method="gaussian_lobes"),
)

#: The render modes by name, in the order the CLI lists them.
RENDER_MODES: dict[str, RenderMode] = {m.name: m for m in _MODES}
DEFAULT_MODE = "distant"


def mode_names() -> tuple[str, ...]:
    """The registered mode names, in table order."""
    return tuple(RENDER_MODES)


def self_shadow_modes() -> tuple[str, ...]:
    """Names of the modes that support self-shadowing."""
    return tuple(m.name for m in RENDER_MODES.values() if m.self_shadow)


def get_mode(name: str) -> RenderMode:
    """The record of mode ``name``; :class:`BadInputError` (a ValueError) naming the known modes otherwise."""
    try:
        return RENDER_MODES[name]
    except (KeyError, TypeError):
        raise BadInputError(None, f"unknown render mode {name!r}; known: {', '.join(RENDER_MODES)}") from None
