"""The Spherical Harmonic Reflection Map (RH02 §4, eqs. 8, 12) and its prefiltering.

An :class:`SHRM` stores the *global* SHRM B̃_pq(α, β): for each reflection direction
(α, β) on a lat-long grid, the real-basis coefficients of the reflected radiance as a
function of the global view direction V,

    B(R, V) = Σ_{p≤P, |q|≤p} B̃_pq(R) Y^r_pq(V)                (RH02 eq. 8)

with the real basis of ``analysis.sh`` at flat index p² + p + q.

Reference: R. Ramamoorthi, P. Hanrahan, "Frequency Space Environment Map Rendering",
SIGGRAPH 2002 (RH02), doi:10.1145/566654.566611.
"""

from __future__ import annotations

import functools
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .._version import __version__
from ..brdf_io.cubemap import cube_map_directions
from ..brdf_io.env_rotation import check_env_rotation, to_map_frame
from ..brdf_io.envmap import EnvironmentMap, load_env
from ..brdf_io.errors import BadInputError
from ..brdf_io.latlong import bilinear_lookup
from ..brdf_io.specs import load_brdf
from .lights import DEFAULT_LIGHTS, LightSet, check_lights, extract_lights, merge_error_by_band
from .map_budget import assess_map
from .map_size import DEFAULT_MAP_BUDGET_BYTES, default_size, fast_map_rows, map_rows
from .notebook import shrm_html, shrm_png
from .orders import (
    DEFAULT_MAX_F,
    DEFAULT_MAX_P,
    OrderChoice,
    choose_orders,
    forced_orders_note,
    orders_on_grid_for,
)
from .pixels import pixel_orders, pixel_sampler, pixel_statement
from .scene import lighting_for, reflected_error_parts, residual_bound, scene_for
from .sh import real_sph_harm
from .shrm_file import read_shrm_fields, save_shrm
from .synthesis import (
    LOCAL_VIEWS_DEG,
    global_from_local,
    global_shrm_cube,
    global_shrm_latlong,
    local_shrm_at,
    local_shrm_direct,
    local_shrm_fast,
    windowed,
)
from .threads import with_single_threaded_blas
from .tolerance import DEFAULT_EPS, check_eps
from .view_bands import DEFAULT_CRITERION, DEFAULT_MAX_VIEW_DEG, bands_inside, shrm_view_bands
from .window import (
    DEFAULT_WINDOW,
    UNDERSHOOT_MAX_VIEW_DEG,
    WINDOW_BUDGET_EPS,
    WINDOW_THRESHOLD,
    WINDOWS,
    WindowChoice,
    check_window,
    choose_window,
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
        Provenance: BRDF and environment names, timings, tool version.
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
            source = self.meta.get("lights_brdf")
            if not source:
                raise BadInputError(self.meta.get("brdf"), "this SHRM has lights but names no BRDF to shade them")
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


def _check_finite(coeffs: np.ndarray, env: Any) -> np.ndarray:
    """``coeffs`` when every value is finite, else :class:`BadInputError` naming the map."""
    if not np.all(np.isfinite(coeffs)):
        raise BadInputError(
            getattr(env, "source", None) or env.name,
            "the prefiltered radiance overflows float32 maps (radiance values near 1e38?): rescale the map",
        )
    return coeffs


def _check_given_orders(orders: OrderChoice, brdf: Any, eps: float, criterion: str, max_view_deg: float) -> None:
    """Refuse an :class:`OrderChoice` made for another tolerance, rule or view limit."""
    given = (orders.tolerance, orders.criterion, orders.max_view_deg)
    if given != (float(eps), criterion, float(max_view_deg)):
        raise BadInputError(
            getattr(brdf, "name", None),
            f"orders chosen at eps={given[0]:g}, criterion={given[1]}, max view {given[2]:g} deg do not match "
            f"eps={eps:g}, criterion={criterion}, max view {max_view_deg:g} deg",
        )


@with_single_threaded_blas
def prefilter(
    env: Any,
    brdf: Any,
    *,
    eps: float = DEFAULT_EPS,
    size: int | None = None,
    budget_bytes: int = DEFAULT_MAP_BUDGET_BYTES,
    F: int | None = None,
    P: int | None = None,
    max_F: int = DEFAULT_MAX_F,
    max_P: int = DEFAULT_MAX_P,
    nthreads: int = 0,
    azimuth_free: bool = False,
    window: str = DEFAULT_WINDOW,
    cube: bool = False,
    cube_size: int | None = None,
    progress: Any = None,
    criterion: str = DEFAULT_CRITERION,
    max_view_deg: float = DEFAULT_MAX_VIEW_DEG,
    orders: OrderChoice | None = None,
    lights: str | int = DEFAULT_LIGHTS,
    pixel_rule: bool = True,
) -> SHRM:
    """Prefilter an environment into a global SHRM (RH02 §4–5, Appendix C).

    Parameters
    ----------
    env
        An :class:`~shrmkit.brdf_io.envmap.EnvironmentMap`, or a spec/path for ``load_env``.
    brdf
        A BRDF, or a spec/path for ``load_brdf``.
    eps
        Tolerance: orders come from :func:`~shrmkit.analysis.orders.choose_orders` and the
        scene's F_B, P_B = P_ρ from :func:`~shrmkit.analysis.scene.scene_orders`.
    criterion, max_view_deg
        The order rule (``"bands"``: every view band θ_v below ``max_view_deg`` meets ε, the
        default; ``"rh02"``: RH02's energy rule and F_B = min(F_ρ, F_L)); see
        :mod:`~shrmkit.analysis.view_bands`. ``meta["view_bands"]`` states the predicted and
        bounded relative RMS per band for either.
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
        float32 global SHRM with orders, achieved errors, timings in ``meta``.

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

    A file works the same way (a 4 × 8 Radiance ``.hdr``, z-up lat-long):

    >>> m = prefilter("tests/resources/tiny_4x8.hdr", "phong:s=8", eps=0.1)
    >>> m.P, m.F <= 3   # Phong needs no view dependence; the 4-row map resolves l <= 3
    (0, True)
    """
    eps = check_eps(eps)
    window = check_window(window)
    lights = check_lights(lights)

    def stage(name: str) -> None:
        if progress is not None:
            progress(name)

    timings: dict[str, float] = {}
    t = time.perf_counter()
    if not isinstance(env, EnvironmentMap):
        env = load_env(env)
    if isinstance(brdf, str | Path):
        brdf = load_brdf(brdf)
    stage("orders")
    t0 = time.perf_counter()
    if F is not None and P is not None:
        orders = orders_on_grid_for(brdf, int(F), int(P), eps=eps, criterion=criterion, max_view_deg=max_view_deg)
    elif orders is not None:
        _check_given_orders(orders, brdf, eps, criterion, max_view_deg)
    else:
        orders = choose_orders(brdf, eps=eps, max_F=max_F, max_P=max_P, criterion=criterion,
                               max_view_deg=max_view_deg)
    timings["orders"] = time.perf_counter() - t0
    stage("lights")
    t0 = time.perf_counter()
    extraction = extract_lights(env, lights)
    light_set = extraction.lights
    timings["lights"] = time.perf_counter() - t0
    source_env, env = env, extraction.residual  # the SHRM holds the map without its lights
    stage("lighting")
    t0 = time.perf_counter()
    lighting, scene = scene_for(env, orders, F=F, nthreads=nthreads)
    timings["lighting"] = time.perf_counter() - t0
    F_B = scene.F_B if F is None else int(min(F, lighting.lmax))
    P_B = scene.P_B if P is None else int(min(P, orders.P0))
    clamp_note = forced_orders_note(F, P, F_B, P_B, F_limit=lighting.lmax, P_limit=orders.P0)  # warns if lowered
    base = orders.coefficients_for(P_B)  # projected (rh02) or fitted to the views that matter (bands)
    band_energy = lighting.band_energy_all()
    q_max = 0 if azimuth_free else None
    top = min(lighting.lmax, orders.F0)
    pixel_choice, pixel_from = None, None
    sampler = pixel_sampler(lighting, base, P_B, q_max=q_max, nthreads=max(nthreads, 1))
    stage("window")
    t0 = time.perf_counter()
    # the window (and, under the bands rule, the F it needs) from the coefficients and a coarse
    # sample of the reflected field; the map itself is synthesized once, below
    lighting_rows = (lighting.rows, lighting.source_rows)

    @functools.cache
    def rows_for(F_: int) -> int:
        """The map's rows at order F_ (the window's sample needs no more)."""
        if size is not None:
            return int(size)
        if orders.criterion == "rh02":
            return fast_map_rows(default_size(F_, P_B, budget_bytes), F_, P_B, budget_bytes)
        return fast_map_rows(map_rows(orders.profile, base, band_energy, F_, P_B, eps, q_max=q_max,
                                   lighting_rows=lighting_rows, max_view_deg=orders.max_view_deg,
                                   budget_bytes=budget_bytes)[0], F_, P_B, budget_bytes)

    def window_at(F_: int, top_: int | None) -> WindowChoice:
        return choose_window(
            window, lighting, base, F_, P_B, eps, criterion=orders.criterion,
            profile=orders.profile if orders.criterion != "rh02" else None, max_view_deg=orders.max_view_deg,
            band_energy=band_energy, projected=orders.coefficients if orders.criterion == "rh02" else None,
            q_max=q_max, top=top_, map_rows=rows_for, nthreads=max(nthreads, 1),
        )

    choice = window_at(F_B, None if F is not None else top)
    F_B, sigma, strength = choice.F, choice.sigma, choice.strength
    timings["window"] = time.perf_counter() - t0
    if pixel_rule and F is None and orders.criterion != "rh02" and F_B < top:
        # the map as windowed so far, per direction; when its 90th percentile passes √ε, the smallest
        # order of the pixel rule's ladder that meets it (bare fields), and the window again there
        stage("pixels")
        t0 = time.perf_counter()
        pixel_from = F_B
        pixel_choice = pixel_statement(lighting, base, F_B, P_B, sigma, eps, top=top, q_max=q_max, fields=sampler)
        if not pixel_choice.p90 <= pixel_choice.tolerance and pixel_choice.F_reference > F_B:
            pixel_choice = pixel_orders(lighting, base, F_B, P_B, eps, top=top, q_max=q_max, fields=sampler)
            if pixel_choice.F > F_B:
                choice = window_at(pixel_choice.F, None)
                F_B, sigma, strength = choice.F, choice.sigma, choice.strength
        timings["pixels"] = time.perf_counter() - t0
    coefficients = windowed(base, sigma, F_B, P_B)
    t0 = time.perf_counter()
    budget_bound = False
    if size is not None:
        S = int(size)
    else:
        if orders.criterion == "rh02":
            S = default_size(F_B, P_B, budget_bytes)  # RH02 §5.2: S ≈ 10 F
            budget_bound = S < int(np.clip(10 * F_B, 32, 1024))
        else:
            S, budget_bound = map_rows(
                orders.profile, base, band_energy, F_B, P_B, eps, sigma=sigma, q_max=q_max,
                lighting_rows=lighting_rows, max_view_deg=orders.max_view_deg, budget_bytes=budget_bytes,
            )
        S = fast_map_rows(S, F_B, P_B, budget_bytes)
    if S < 2 or S > 8192:
        raise BadInputError(None, f"SHRM size must be in [2, 8192] rows, got {S}")
    timings["map size"] = time.perf_counter() - t0
    stage("synthesis")
    t0 = time.perf_counter()
    with np.errstate(over="ignore", invalid="ignore"):  # overflow is checked (and reported) below
        coeffs = global_shrm_latlong(
            lighting, coefficients, F_B, P_B, S, 2 * S, nthreads=nthreads, azimuth_free=azimuth_free
        )
    coeffs = _check_finite(coeffs, env)
    timings["synthesis"] = time.perf_counter() - t0
    reason, before, after, negative_fraction = choice.reason, choice.before, choice.after, choice.negative_fraction
    cube_coeffs = None
    if cube:
        stage("cube map")
        t0 = time.perf_counter()
        n_cube = max(2, S // 2) if cube_size is None else int(cube_size)
        if n_cube < 2 or n_cube > 4096:
            raise BadInputError(None, f"cube face size must be in [2, 4096], got {n_cube}")
        cube_coeffs = global_shrm_cube(lighting, coefficients, F_B, P_B, n_cube, nthreads=nthreads,
                                       azimuth_free=azimuth_free)
        timings["cube"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    def state(signal: np.ndarray | None = None, rows: int | None = S):
        return shrm_view_bands(
            orders.profile, base, band_energy, F_B, P_B, sigma=sigma, q_max=q_max, map_rows=rows,
            lighting_rows=lighting_rows, max_view_deg=orders.max_view_deg,
            signal_band_energy=signal,
        )

    statement = state()
    signal_energy, raw_bands = None, [dict(b) for b in statement.bands]
    if len(light_set):
        # the maps hold the map without its lights: relative to that reflection (what holds away from
        # the lights, ``*_residual``) and, the main statement, to the whole map's reflection (the
        # lights add signal and, where merged from pixels, their merge error)
        whole = lighting_for(source_env, orders, F=F, nthreads=nthreads).band_energy_all()
        signal_energy = whole
        residual_bands, statement = statement.bands, state(whole)
        raw_bands = [dict(b) for b in statement.bands]
        part = SHRM(F=F_B, P=P_B, coeffs=coeffs)
        merge_res, merge_whole = (np.zeros(len(residual_bands)),) * 2
        if extraction.merged:
            merge_res, merge_whole = merge_error_by_band(
                extraction, brdf, lambda R, V: part.radiance(R, V, lights=False), orders.profile.edges_deg,
                whole=lambda R, V: part.radiance(R, V, lights=False) + light_set.radiance(brdf, R, V))
        for band, own, extra_res, extra in zip(statement.bands, residual_bands, merge_res, merge_whole, strict=True):
            # merged samples: a Monte Carlo measure, 1.5× in amplitude in the bound covers its sampling error
            band["lights_rel_rms"] = float(np.sqrt(extra))
            band["predicted_rel_rms"] = float(np.sqrt(band["predicted_rel_rms"] ** 2 + extra))
            band["bound_rel_rms"] = float(band["bound_rel_rms"] + 1.5 * np.sqrt(extra))
            # the residual statements are the map's alone (what holds away from the lights); the merge
            # error, relative to the same reflection, is stated beside them (it lives within the merge angle
            # and the lobe of the merged light: added to them, a dim room's walls made them 10-60x loose)
            band["lights_rel_rms_residual"] = float(np.sqrt(extra_res))
            band["predicted_rel_rms_residual"] = float(own["predicted_rel_rms"])
            band["bound_rel_rms_residual"] = float(own["bound_rel_rms"])
    # what the map's size costs the statement, and whether a cap made a bound say nothing (issue 29)
    map_budget = assess_map(
        statement.bands, raw_bands, state(signal_energy, None).bands, rows=S, P=P_B, budget_bytes=budget_bytes,
        inside=list(bands_inside(orders.profile, orders.max_view_deg)), capped=budget_bound,
        rows_needed=lambda: fast_map_rows(map_rows(
            orders.profile, base, band_energy, F_B, P_B, eps, sigma=sigma, q_max=q_max,
            lighting_rows=lighting_rows, max_view_deg=orders.max_view_deg,
            budget_bytes=1 << 62)[0], F_B, P_B, 1 << 62))
    # on the coefficients the map was made of (the projection for rh02, the view fit for bands):
    # the window's cost, the energy of its change over all views, is exact for either
    truncation, cost = reflected_error_parts(lighting, base, F_B, P_B, sigma, q_max=q_max)
    if orders.criterion == "rh02":
        reflected = float((truncation + cost).max())
        unwindowed = float(truncation.max())
        bound = residual_bound(lighting, base, F_B, P_B, sigma, q_max=q_max)
    else:  # fitted coefficients: Parseval no longer splits the error; the view-band sums do
        reflected, bound = statement.eps_predicted, statement.eps_bound
        unwindowed = reflected if sigma is None else shrm_view_bands(
            orders.profile, base, band_energy, F_B, P_B, q_max=q_max, map_rows=S,
            lighting_rows=lighting_rows, max_view_deg=orders.max_view_deg,
        ).eps_predicted
    # per direction (what a pixel shows), against a higher order: pixels.py
    pixels = pixel_statement(lighting, base, F_B, P_B, sigma, eps, top=top, q_max=q_max, fields=sampler,
                             F_reference=pixel_choice.F_reference if pixel_choice is not None else None)
    eps_info = {
        "brdf": orders.eps_at(min(F_B, orders.F0), P_B),
        "lighting": float(lighting.eps()[min(F_B, lighting.lmax)]),
        "reflected": reflected,
        "bound": bound,
        "gibbs_negative": choice.normal_after,  # the normal views V = R of the undershoot sample
    }
    timings["errors"] = time.perf_counter() - t0
    timings["total"] = time.perf_counter() - t
    pixel_capped = pixel_choice is not None and pixel_choice.capped
    size_note = map_budget.note
    if not size_note:
        size_note = ""
        if budget_bound:
            assert map_budget.bytes_needed is not None  # the budget held the rows: the rows that meet eps are known
            size_note = (
                f"map rows held at {S} by the {budget_bytes / 2**20:g} MiB budget ({map_budget.rows_needed} rows, "
                f"{map_budget.bytes_needed / 2**20:.0f} MiB, would meet eps; use size= or budget_bytes=)")
    meta = {
        "brdf": brdf.name,
        "environment": source_env.name,
        "environment_source": getattr(source_env, "source", ""),
        "lights_requested": lights,
        "lights": [light.to_dict() for light in light_set.lights],
        "lights_flux_share": extraction.flux_share,
        "lights_threshold": float(extraction.threshold) if np.isfinite(extraction.threshold) else None,
        "lights_left_in_map": int(extraction.skipped),
        "lights_brdf": (brdf.to_spec() if brdf.kind == "analytic" else getattr(brdf, "source", None))
        if len(light_set) else None,
        "statement_signal": "the reflection of the map without its lights" if len(light_set) else "the reflection",
        "F_rho": orders.F,
        "P_rho": orders.P,
        "F_L": scene.F_L,
        "lighting_capped": bool(scene.lighting_capped),
        "orders_message": "; ".join(m for m in (orders.message, clamp_note, size_note) if m),
        "orders_asked": None if F is None and P is None else {"F": F if F is None else int(F),
                                                              "P": P if P is None else int(P)},
        "timings": timings,
        "shrmkit_version": __version__,
        "frame": "z-up; lat-long pixel centres theta=(i+1/2)pi/H, phi=2pi(j+1/2)/W",
        "azimuth_free": bool(azimuth_free),
        "window": "lanczos" if strength > 0.0 else "none",
        "window_requested": window,
        "window_strength": float(strength),
        "window_reason": reason,
        "window_threshold": WINDOW_THRESHOLD,
        "window_cost": float(cost.max()),
        "eps_reflected_unwindowed": unwindowed,
        "negative_before": before,
        "negative_after": after,
        "negative_fraction_after": negative_fraction,
        "negative_max_view_deg": float(max(v[0] for v in LOCAL_VIEWS_DEG)) if P_B > 0 else 0.0,
        "negative_sample_pairs": choice.pairs,
        "window_capped": bool(choice.capped),
        "criterion": orders.criterion,
        "max_view_deg": orders.max_view_deg,
        "scene_capped": bool(scene.capped),
        # one summary of every budget that stops the rule from meeting ε (orders' caps, the map's
        # resolution of the lighting, the window, the map's memory budget)
        "capped": bool(orders.capped or scene.capped or choice.capped or budget_bound or pixel_capped),
        "capped_by": [name for name, hit in (
            ("orders: max_F/max_P", orders.capped), ("lighting: the map's resolution (F_B at its lmax)",
                                                           scene.capped),
            ("window budget", choice.capped), (f"map budget: {budget_bytes / 2**20:g} MiB", budget_bound),
            ("pixel rule: no order the lighting holds meets √ε per direction", pixel_capped)) if hit],
        # the rule's check: from F_B (the energy rule's, after the window) to F (raised when it failed)
        "pixel_rule": {**pixel_choice.to_dict(), "F_from": pixel_from} if pixel_choice is not None else None,
        "pixel_errors": pixels.to_dict(),
        "view_bands": statement.bands,
        "map_budget": map_budget.to_dict(),
        "extrapolated_samples": int(orders.n_without_data),
    }
    return SHRM(F=F_B, P=P_B, coeffs=coeffs, tolerance=float(eps), eps=eps_info, meta=meta, cube=cube_coeffs,
                lights=light_set if len(light_set) else None, brdf=brdf if len(light_set) else None)
