"""The Spherical Harmonic Reflection Map ([RH02] §4, eqs. 8, 12) and its prefiltering.

An :class:`SHRM` stores the *global* SHRM B̃_pq(α, β): for each reflection direction
(α, β) on a lat-long grid, the real-basis coefficients of the reflected radiance as a
function of the global view direction V,

    B(R, V) = Σ_{p≤P, |q|≤p} B̃_pq(R) Y^r_pq(V)                ([RH02] eq. 8)

with the real basis of ``analysis.sh`` at flat index p² + p + q.

Reference: [RH02] (``data_specs/bibliography.md``).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np

from ..brdf_io.cubemap import cube_map_directions
from ..brdf_io.env_rotation import check_env_rotation, to_map_frame
from ..brdf_io.envmap import EnvironmentMap, load_env
from ..brdf_io.errors import BadInputError
from ..brdf_io.latlong import bilinear_lookup
from ..brdf_io.specs import load_brdf
from . import _prefilter as stage
from .lights import DEFAULT_LIGHTS, LightSet, check_lights, extract_lights
from .map_size import DEFAULT_MAP_BUDGET_BYTES, default_size
from .notebook import shrm_html, shrm_png
from .order_rule import OrderRule, resolve_rule
from .orders import OrderChoice
from .records import PrefilterInfo
from .scene import scene_for
from .sh import real_sph_harm
from .shrm_file import read_shrm_fields, save_shrm
from .synthesis import (
    global_from_local,
    global_shrm_latlong,
    local_shrm_at,
    local_shrm_direct,
    local_shrm_fast,
    windowed,
)
from .threads import with_single_threaded_blas
from .window import (
    DEFAULT_WINDOW,
    UNDERSHOOT_MAX_VIEW_DEG,
    WINDOW_BUDGET_EPS,
    WINDOW_THRESHOLD,
    WINDOWS,
    check_window,
    gibbs_negative,
    undershoot,
    undershoot_samples,
    undershoot_views,
)

__all__ = [
    "SHRM",
    "load_shrm",
    "prefilter",
    "local_shrm_fast",
    "local_shrm_at",
    "global_shrm_latlong",
    "local_shrm_direct",
    "global_from_local",
    "default_size",
    "cube_directions",
    "gibbs_negative",
    "WINDOWS",
    "DEFAULT_WINDOW",
    "WINDOW_THRESHOLD",
    "WINDOW_BUDGET_EPS",
    "UNDERSHOOT_MAX_VIEW_DEG",
    "check_window",
    "undershoot_views",
    "undershoot_samples",
    "undershoot",
]

def _unit_rows(vectors: np.ndarray, name: str) -> np.ndarray:
    """(n, 3) float64 unit vectors; BadInputError for a wrong shape, zero or non-finite rows."""
    v = np.atleast_2d(np.asarray(vectors, dtype=np.float64))
    if v.ndim != 2 or v.shape[1] != 3:
        raise BadInputError(None, f"{name} must have shape (n, 3), got {np.shape(vectors)}")
    norm = np.linalg.norm(v, axis=1, keepdims=True)
    bad = ~np.isfinite(norm[:, 0]) | (norm[:, 0] == 0)
    if np.any(bad):
        raise BadInputError(None, f"{name} has {int(bad.sum())} zero or non-finite direction(s)")
    return v / norm


@dataclass(frozen=True, eq=False)
class SHRM:
    """A global SHRM on a lat-long grid.

    Attributes
    ----------
    F, P
        Orders in the reflection direction and in the view direction.
    cube
        Optional float32 ((P+1)², 6, S, S, 3): the same global SHRM on a cube map (faces
        +X, −X, +Y, −Y, +Z, −Z of the z-up frame, OpenGL texel axes: see
        :func:`cube_directions` and ``data_specs/shrm_file.md``).
    coeffs
        float32 array ((P+1)², H, W, 3): B̃_pq(α, β) at the pixel centres
        α = (i+½)π/H, β = 2π(j+½)/W (z-up frame), real basis index p² + p + q.
    tolerance
        The requested ε; ``eps`` holds the achieved error estimates.
    eps
        Dict of achieved error estimates (``"brdf"``, ``"lighting"``, ``"bound"``).
    meta
        Provenance: BRDF and environment names, timings, tool version, the window and the stated
        errors, as JSON (``data_specs/shrm_file.md``); :attr:`info` is the same as a typed record.
    lights
        The explicit lights taken out of the environment before prefiltering
        (:class:`~shrmkit.analysis.lights.LightSet`; None or empty: none): the maps hold the
        reflection of the rest of the map, and :meth:`radiance` adds the lights' exact reflection.
    brdf
        The BRDF the lights are shaded with (loaded from ``meta["lights_brdf"]`` — its spec, or
        the file it came from — when first needed if not given).
    """

    F: int
    P: int
    coeffs: np.ndarray
    tolerance: float = float("nan")
    eps: dict[str, float] = field(default_factory=dict)
    meta: dict[str, Any] = field(default_factory=dict)
    cube: np.ndarray | None = None
    lights: LightSet | None = field(default=None, repr=False)
    brdf: Any = field(default=None, repr=False, compare=False)

    def __post_init__(self) -> None:
        n = (self.P + 1) ** 2
        if self.coeffs.ndim != 4 or self.coeffs.shape[0] != n or self.coeffs.shape[3] != 3:
            raise ValueError(f"coeffs must have shape ({n}, H, W, 3), got {self.coeffs.shape}")
        if self.cube is not None and (
            self.cube.ndim != 5 or self.cube.shape[:2] != (n, 6) or self.cube.shape[2] != self.cube.shape[3]
        ):
            raise ValueError(f"cube must have shape ({n}, 6, S, S, 3), got {self.cube.shape}")

    _repr_html_ = shrm_html  # notebook card and picture (analysis.notebook)
    _repr_png_ = shrm_png

    @property
    def height(self) -> int:
        return int(self.coeffs.shape[1])

    @property
    def width(self) -> int:
        return int(self.coeffs.shape[2])

    @cached_property
    def info(self) -> PrefilterInfo:
        """``meta`` as a typed record (:class:`~shrmkit.analysis.records.PrefilterInfo`): what
        ``prefilter`` did and states. Built from ``meta`` on first use, so an SHRM read from a file
        has it too; keys a file written before them lacks read as None. ``meta`` stays the
        serialized form (``data_specs/shrm_file.md``): do not change it after the first use."""
        return PrefilterInfo.from_meta(self.meta)

    @property
    def has_lights(self) -> bool:
        """True when the scene has explicit lights beside the maps."""
        return self.lights is not None and len(self.lights) > 0

    def radiance(self, R: np.ndarray, V: np.ndarray, *, clamp: bool = True, lights: bool = True,
                 env_rotation: Any = None) -> np.ndarray:
        """Predicted reflected radiance B(R, V), shape (n, 3): the SHRM (RH02 eq. 8) plus the
        explicit lights' exact reflection Σ_k ρ̂(ω_k; V, N) E_k (DESIGN §5a).

        Parameters
        ----------
        R, V
            Reflection and view directions (n, 3) in the global z-up frame, normalized
            here (zero or non-finite rows are refused); the surface normal is
            normalize(R + V).
        clamp
            Set negative values of the SHRM part to 0 (default): the Gibbs undershoot the
            window left (``meta["negative_after"]`` of the peak on ``meta["negative_fraction_after"]``
            of the sampled (R, V); ``data_specs/shrm_file.md``). False returns the truncated
            expansion itself.
        lights
            Add the lights (default). ``lights=False`` gives the SHRM part alone;
            :meth:`light_radiance` gives the lights alone.
        env_rotation
            The environment rotated by Q at view time (``brdf_io.env_rotation``): a (3, 3)
            rotation, Euler angles (AZ, EL[, ROLL]) in degrees, or None. The radiance under the
            rotated map (and lights moved to Q ω_k) is this SHRM's at (Qᵀ R, Qᵀ V); nothing is
            prefiltered again.

        Raises
        ------
        BadInputError
            Bad directions or rotation; lights whose BRDF cannot be loaded (``meta["lights_brdf"]``).
        """
        rotation = check_env_rotation(env_rotation)
        R = to_map_frame(_unit_rows(R, "R"), rotation)
        V = to_map_frame(_unit_rows(V, "V"), rotation)
        if R.shape != V.shape:
            raise BadInputError(None, f"R and V must have the same shape (n, 3), got {R.shape} and {V.shape}")
        maps = np.moveaxis(self.coeffs, 0, 2)  # (H, W, n_coef, 3)
        at_r = bilinear_lookup(maps, R)  # (n, n_coef, 3)
        basis = real_sph_harm(self.P, V)  # (n, n_coef)
        out = np.einsum("nc,nck->nk", basis, at_r)
        if clamp:
            out = np.maximum(out, 0.0)
        if lights and self.has_lights:
            assert self.lights is not None  # has_lights
            out += self.lights.radiance(self.lights_brdf(), R, V)
        return out

    def light_radiance(self, R: np.ndarray, V: np.ndarray, *, env_rotation: Any = None) -> np.ndarray:
        """The explicit lights' reflection alone, (n, 3) (zeros without lights); ``env_rotation`` as
        in :meth:`radiance` (the lights move with their map)."""
        rotation = check_env_rotation(env_rotation)
        R = to_map_frame(_unit_rows(R, "R"), rotation)
        V = to_map_frame(_unit_rows(V, "V"), rotation)
        if not self.has_lights:
            return np.zeros(R.shape)
        assert self.lights is not None  # has_lights
        return self.lights.radiance(self.lights_brdf(), R, V)

    def lights_brdf(self) -> Any:
        """The BRDF the lights are shaded with: ``brdf`` as given, else loaded (once) from
        ``meta["lights_brdf"]`` (a spec string or the file the BRDF came from)."""
        if self.brdf is None:
            source = self.info.lights.brdf
            if not source:
                raise BadInputError(self.info.brdf, "this SHRM has lights but names no BRDF to shade them")
            object.__setattr__(self, "brdf", load_brdf(source))
        return self.brdf

    def save(self, path: str | Path) -> Path:
        """Write the SHRM to a ``.shrm.npz`` file (atomic; see ``data_specs/shrm_file.md``)."""
        return save_shrm(path, self)

    def view_map(self, view: np.ndarray, *, clamp: bool = True, env_rotation: Any = None) -> np.ndarray:
        """Distant-viewer map Σ B̃_pq(α, β) Y^r_pq(V) for one view direction (RH02 eq. 12): the SHRM
        part only — a light's highlight is sharper than the map resolves, so renderers shade the
        lights per pixel (:meth:`light_radiance`).

        Returns float32 (H, W, 3); ``clamp`` as in :meth:`radiance`. With ``env_rotation`` Q (as in
        :meth:`radiance`) the map is that of the view Qᵀ V, in the unrotated map's frame: look it up
        at Qᵀ R (``brdf_io.env_rotation.to_map_frame``), as the renderers do.
        """
        view = to_map_frame(np.asarray(view, dtype=np.float64).reshape(3), check_env_rotation(env_rotation))
        basis = real_sph_harm(self.P, view).astype(np.float32)
        out = np.tensordot(basis, self.coeffs, axes=(0, 0))
        return np.maximum(out, 0.0, out=out) if clamp else out


# ----------------------------------------------------------------------------------------
# Prefiltering: local SHRM by spin-weighted SHT, rotation to the global SHRM (DESIGN §5–6)
# ----------------------------------------------------------------------------------------


def load_shrm(path: str | Path) -> SHRM:
    """Read an SHRM written by :meth:`SHRM.save` (``data_specs/shrm_file.md``).

    Raises
    ------
    BadInputError
        Missing or unreadable file, wrong format or version, inconsistent shapes,
        non-finite coefficients.
    """
    return SHRM(**read_shrm_fields(path))


def cube_directions(size: int) -> np.ndarray:
    """Unit texel-centre directions (6, S, S, 3) of the SHRM cube map, faces +x, −x, +y, −y,
    +z, −z of the z-up frame with OpenGL texel axes (the one table: ``brdf_io.cubemap``)."""
    return cube_map_directions(size)


@with_single_threaded_blas
def prefilter(
    env: Any,
    brdf: Any,
    *,
    eps: float | None = None,
    size: int | None = None,
    budget_bytes: int = DEFAULT_MAP_BUDGET_BYTES,
    F: int | None = None,
    P: int | None = None,
    max_F: int | None = None,
    max_P: int | None = None,
    nthreads: int = 0,
    azimuth_free: bool = False,
    window: str = DEFAULT_WINDOW,
    cube: bool = False,
    cube_size: int | None = None,
    progress: Any = None,
    criterion: str | None = None,
    max_view_deg: float | None = None,
    orders: OrderChoice | None = None,
    lights: str | int = DEFAULT_LIGHTS,
    pixel_rule: bool = True,
    rule: OrderRule | None = None,
) -> SHRM:
    """Prefilter an environment into a global SHRM (RH02 §4–5, Appendix C).

    Parameters
    ----------
    env
        An :class:`~shrmkit.brdf_io.envmap.EnvironmentMap`, or a spec/path for ``load_env``.
    brdf
        A BRDF, or a spec/path for ``load_brdf``.
    rule
        The order rule (:class:`~shrmkit.analysis.order_rule.OrderRule`: criterion, view limit,
        tolerance ε, caps on F and P; default ``OrderRule()``): orders come from
        :func:`~shrmkit.analysis.orders.choose_orders` and the scene's F_B, P_B = P_ρ from
        :func:`~shrmkit.analysis.scene.scene_orders`. ``"bands"``: every view band θ_v below
        ``max_view_deg`` meets ε, the default; ``"rh02"``: RH02's energy rule and
        F_B = min(F_ρ, F_L); see :mod:`~shrmkit.analysis.view_bands`. ``meta["view_bands"]``
        states the predicted and bounded relative RMS per band for either.
    eps, max_F, max_P, criterion, max_view_deg
        The rule's fields as loose keywords (None: not given), as in
        :func:`~shrmkit.analysis.orders.choose_orders`: with ``rule`` they must agree with it.
    size
        Rows S_B of the S_B × 2S_B output (default :func:`default_size`: 10 F_B, within
        [32, 1024] rows and a 256 MiB map budget; the meta says when the budget applied).
    budget_bytes
        The memory budget of the default size (``size=`` overrides it). ``meta["map_budget"]``
        (:mod:`~shrmkit.analysis.map_budget`) says when the map's size makes a band's bound
        uninformative, what the lookup costs, and the rows and bytes that would meet ε.
    F, P
        Force the orders instead of choosing them.
    orders
        The BRDF's :class:`~shrmkit.analysis.orders.OrderChoice` when the caller already has it
        (:func:`~shrmkit.analysis.orders.choose_orders` of this ``brdf`` with the same ``eps``,
        ``criterion`` and ``max_view_deg``; a report chooses them once for its tables): used
        instead of choosing again. Ignored when both ``F`` and ``P`` are given.
    azimuth_free
        Keep only the q = 0 terms of the local SHRM (Kautz & McCool 2000; RH02 Fig. 9):
        B(α, β, θ_o) = Σ_p B_p0(α, β) Y_p0(ω_o'). Exact for radially symmetric lobes.
    nthreads
        Threads for the SHTs (0: all available cores).
    window
        Damping of the negative lobes (Gibbs ringing) a sharp truncation creates (DESIGN §7),
        one of :data:`WINDOWS`; the orders (F, P) are chosen first and never change.
        ``"lanczos"``: multiply ρ̂_lpq by the Lanczos σ-factors
        σ_lp = sinc(l/(F+1)) sinc(p/(P+1)) (:func:`~shrmkit.analysis.scene.lanczos_sigma`).
        ``"auto"`` (default): synthesize without a window and measure the undershoot
        (:func:`undershoot` on :func:`undershoot_samples`: every pixel's normal view and, for
        P > 0, two oblique views per pixel up to θ_v = 85°); when it exceeds
        :data:`WINDOW_THRESHOLD` (0.1 % of the peak), synthesize again with the Lanczos
        σ-factors at the smallest strength t (σ(t) = 1 − t(1 − σ)) that brings it under the
        threshold, but at most the strength whose cost stays within
        :data:`WINDOW_BUDGET_EPS`·ε of added ε_B (when none reaches it: the strength of least
        undershoot, possibly 0; :func:`_strength_for`). With the ``"bands"`` rule, F_B is first
        raised to the smallest F whose field with the full Lanczos window in l is predicted to
        meet ε in every view band inside the limit, and the budget is WINDOW_BUDGET_EPS·ε of
        added predicted error energy in every such band (``data_specs/view_bands.md``).
        ``"none"``: no window. The window's cost is
        included in ``eps["reflected"]`` and ``eps["bound"]``; ``meta`` records the window
        used, its strength and why, and the undershoot before and after
        (``data_specs/shrm_file.md``). What undershoot is left, :meth:`SHRM.radiance`,
        :meth:`SHRM.view_map` and the renderer clamp to 0.
    cube, cube_size
        Also synthesize the SHRM on a 6 × S × S cube map (default S = rows // 2) through
        ducc0's general synthesis at the texel centres.
    lights
        ``"auto"`` (default), ``"none"`` or N: the compact bright regions of the map (sun, lamps,
        windows) taken out as explicit lights before prefiltering
        (:func:`~shrmkit.analysis.lights.extract_lights`). The maps then hold the reflection of the
        rest of the map — orders, window and every stated error are those of that residual,
        relative to its own reflection (a conservative statement for the whole: the lights only add
        signal) — and :meth:`SHRM.radiance` adds the lights' exact reflection. Lights merged from
        more pixels than :data:`~shrmkit.analysis.lights.MAX_SAMPLES_PER_LIGHT` add their merge
        error, measured against their pixels, to the per-band statement.
    pixel_rule
        ``"bands"`` rule only (default True): F_B is then raised to the smallest order whose reflected
        field has its per-direction relative error at most √ε at 90 % of the sampled directions and
        views (:func:`~shrmkit.analysis.pixels.pixel_orders`; the energy rules bound an average that
        a high dynamic range map lets dark regions miss by 100 %). Either rule states the per-direction
        errors of the map as made in ``meta["pixel_errors"]`` (median, 90th percentile, against a
        higher reference order).
    progress
        Optional callable ``progress(stage: str)`` told when each stage starts.

    Returns
    -------
    SHRM
        float32 global SHRM with orders and achieved errors; what the run did and states (window,
        lights, budgets, per-band statement, timings) in ``meta``, typed as ``info``
        (:class:`~shrmkit.analysis.records.PrefilterInfo`). The stages are ``analysis._prefilter``'s.

    Raises
    ------
    BadInputError
        ε outside (0, 1), an unreadable map or BRDF, an all-zero BRDF, sizes out of range,
        radiance that overflows float32 maps, or ``orders`` chosen at another tolerance, rule
        or view limit.

    Examples
    --------
    A constant sky of radiance 1 over a Lambertian surface of albedo 0.5 reflects 0.5 in
    every direction (closed form), and needs only the l = 0 lighting band:

    >>> m = prefilter("builtin:constant,height=16", "lambert:albedo=0.5")
    >>> m.F, (m.height, m.width)
    (0, (32, 64))
    >>> R = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])
    >>> V = np.array([[0.0, 0.0, 1.0], [0.6, 0.0, 0.8]])
    >>> m.radiance(R, V).round(4)
    array([[0.5, 0.5, 0.5],
           [0.5, 0.5, 0.5]])

    A file works the same way (a 4 × 8 Radiance ``.hdr``, a lat-long file read y-up by default):

    >>> m = prefilter("tests/resources/tiny_4x8.hdr", "phong:s=8", eps=0.1)
    >>> m.P, m.F <= 3   # Phong needs no view dependence; the 4-row map resolves l <= 3
    (0, True)
    """
    rule = resolve_rule(rule, eps=eps, max_F=max_F, max_P=max_P, criterion=criterion, max_view_deg=max_view_deg)
    window = check_window(window)
    lights = check_lights(lights)
    stages = stage.Stages(progress)
    if not isinstance(env, EnvironmentMap):
        env = load_env(env)
    if isinstance(brdf, str | Path):
        brdf = load_brdf(brdf)
    with stages("orders"):
        orders = stage.brdf_orders(brdf, rule, F=F, P=P, orders=orders)
    with stages("lights"):
        extraction = extract_lights(env, lights)  # the SHRM holds the map without its lights
    with stages("lighting"):
        lighting, scene = scene_for(extraction.residual, orders, F=F, nthreads=nthreads)
    s = stage.setup(orders, lighting, scene, eps=rule.eps, F=F, P=P, azimuth_free=azimuth_free, size=size,
                    budget_bytes=budget_bytes, nthreads=nthreads)
    with stages("window"):
        w = stage.choose_window_for(s, window)
    if stage.pixel_rule_applies(s, w, pixel_rule):
        with stages("pixels"):
            w = stage.apply_pixel_rule(s, w, window)
    coefficients = windowed(s.base, w.sigma, w.F_B, s.P_B)
    with stages("map size", announce=None):
        S, budget_bound = stage.map_size(s, w)
    with stages("synthesis"):
        coeffs = stage.synthesize(s, w, coefficients, S, extraction.residual, azimuth_free)
    cube_coeffs = None
    if cube:
        with stages("cube", announce="cube map"):
            cube_coeffs = stage.synthesize_cube(s, w, coefficients, S, cube_size, azimuth_free)
    part = SHRM(F=w.F_B, P=s.P_B, coeffs=coeffs)
    with stages("errors", announce=None):
        st = stage.state_errors(s, w, S, budget_bound, extraction, brdf, env,
                                functools.partial(part.radiance, lights=False))
    info = stage.record(s, w, st, S, brdf=brdf, source_env=env, extraction=extraction, lights=lights,
                        window=window, F=F, P=P, azimuth_free=azimuth_free, timings=stages.timings())
    light_set = extraction.lights if len(extraction.lights) else None
    return SHRM(F=w.F_B, P=s.P_B, coeffs=coeffs, tolerance=rule.eps, eps=st.eps, meta=info.to_meta(),
                cube=cube_coeffs, lights=light_set, brdf=brdf if light_set is not None else None)
