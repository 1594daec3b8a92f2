"""The stages of :func:`~shrmkit.analysis.shrm.prefilter` (internal; DESIGN §5–7).

orders → lights → lighting and scene orders → window (+ the pixel rule) → map size → synthesis
→ statements and errors → :class:`~shrmkit.analysis.records.PrefilterInfo`. Each stage is a
small function over the frozen :class:`Setup` (what the lighting and the orders fix) and
:class:`Windowed` (the window's choice); ``prefilter`` calls them in that order and times them
(:class:`Stages`).
"""

from __future__ import annotations

import functools
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._version import __version__
from ..brdf_io.errors import BadInputError
from .brdf_coeffs import BRDFCoefficients
from .lighting import LightingCoefficients
from .lights import Extraction, merge_error_by_band
from .map_budget import MapAssessment, assess_map
from .map_size import default_size, fast_map_rows, map_rows
from .order_rule import OrderRule
from .orders import OrderChoice, choose_orders, forced_orders_note, orders_on_grid_for
from .pixels import PixelCheck, pixel_orders, pixel_sampler, pixel_statement
from .records import LightsInfo, PrefilterInfo, Timings, ViewBand, WindowInfo
from .scene import SceneOrders, lighting_for, reflected_error_parts, residual_bound
from .synthesis import LOCAL_VIEWS_DEG, global_shrm_cube, global_shrm_latlong
from .view_bands import BandStatement, bands_inside, shrm_view_bands
from .window import WINDOW_THRESHOLD, WindowChoice, choose_window

FRAME = "z-up; lat-long pixel centres theta=(i+1/2)pi/H, phi=2pi(j+1/2)/W"


class Stages:
    """Tells ``progress(stage)`` when a stage starts and keeps its seconds (``meta["timings"]``)."""

    def __init__(self, progress: Callable[[str], Any] | None) -> None:
        self.progress = progress
        self.seconds: dict[str, float] = {}
        self.start = time.perf_counter()

    @contextmanager
    def __call__(self, key: str, announce: str | None = "") -> Iterator[None]:
        """Time the block as ``key``; announce it as ``announce`` ('' : the key, None: silently)."""
        if self.progress is not None and announce is not None:
            self.progress(announce or key)
        t0 = time.perf_counter()
        yield
        self.seconds[key] = time.perf_counter() - t0

    def timings(self) -> Timings:
        """The stages timed so far, and the total since this object was made."""
        s = self.seconds
        return Timings(orders=s["orders"], lights=s["lights"], lighting=s["lighting"], window=s["window"],
                       pixels=s.get("pixels"), map_size=s["map size"], synthesis=s["synthesis"],
                       cube=s.get("cube"), errors=s["errors"], total=time.perf_counter() - self.start)


def check_given_orders(orders: OrderChoice, brdf: Any, rule: OrderRule) -> None:
    """Refuse an :class:`OrderChoice` made for another tolerance, rule or view limit (the caps are
    not compared)."""
    given = (orders.tolerance, orders.criterion, orders.max_view_deg)
    if given != (rule.eps, rule.criterion, rule.max_view_deg):
        raise BadInputError(
            getattr(brdf, "name", None),
            f"orders chosen at eps={given[0]:g}, criterion={given[1]}, max view {given[2]:g} deg do not match "
            f"eps={rule.eps:g}, criterion={rule.criterion}, max view {rule.max_view_deg:g} deg",
        )


def brdf_orders(brdf: Any, rule: OrderRule, *, F: int | None, P: int | None,
                orders: OrderChoice | None) -> OrderChoice:
    """Stage 1: the BRDF's orders under ``rule`` — on the grid of forced (F, P), the caller's, or chosen."""
    if F is not None and P is not None:
        return orders_on_grid_for(brdf, int(F), int(P), rule=rule)
    if orders is not None:
        check_given_orders(orders, brdf, rule)
        return orders
    return choose_orders(brdf, rule=rule)


@dataclass(frozen=True)
class Setup:
    """What the orders and the lighting fix before the window (stage 3)."""

    eps: float
    orders: OrderChoice
    lighting: LightingCoefficients
    scene: SceneOrders
    F_forced: int | None
    F_B: int  # the scene's, before the window
    P_B: int
    clamp_note: str
    base: BRDFCoefficients  # projected (rh02) or fitted to the views that matter (bands)
    band_energy: np.ndarray
    q_max: int | None
    top: int
    lighting_rows: tuple[int, int]
    sampler: Any
    size: int | None
    budget_bytes: int
    nthreads: int
    rows_for: Callable[[int], int]  # the map's rows at order F (the window's sample needs no more)

    @property
    def rh02(self) -> bool:
        return self.orders.criterion == "rh02"


def setup(orders: OrderChoice, lighting: LightingCoefficients, scene: SceneOrders, *, eps: float,
          F: int | None, P: int | None, azimuth_free: bool, size: int | None, budget_bytes: int,
          nthreads: int) -> Setup:
    """Stage 3: the scene's orders (forced ones clamped, with a warning), the coefficients the map is
    made of and the lighting's band energies."""
    F_B = scene.F_B if F is None else int(min(F, lighting.lmax))
    P_B = scene.P_B if P is None else int(min(P, orders.P0))
    clamp_note = forced_orders_note(F, P, F_B, P_B, F_limit=lighting.lmax, P_limit=orders.P0)  # warns if lowered
    base = orders.coefficients_for(P_B)
    band_energy = lighting.band_energy_all()
    q_max = 0 if azimuth_free else None
    lighting_rows = (lighting.rows, lighting.source_rows)

    @functools.cache
    def rows_for(F_: int) -> int:
        if size is not None:
            return int(size)
        if orders.criterion == "rh02":
            return fast_map_rows(default_size(F_, P_B, budget_bytes), F_, P_B, budget_bytes)
        return fast_map_rows(map_rows(orders.profile, base, band_energy, F_, P_B, eps, q_max=q_max,
                                      lighting_rows=lighting_rows, max_view_deg=orders.max_view_deg,
                                      budget_bytes=budget_bytes)[0], F_, P_B, budget_bytes)

    return Setup(
        eps=eps, orders=orders, lighting=lighting, scene=scene, F_forced=F, F_B=F_B, P_B=P_B, clamp_note=clamp_note,
        base=base, band_energy=band_energy, q_max=q_max, top=min(lighting.lmax, orders.F0),
        lighting_rows=lighting_rows, size=size, budget_bytes=budget_bytes, nthreads=nthreads, rows_for=rows_for,
        sampler=pixel_sampler(lighting, base, P_B, q_max=q_max, nthreads=max(nthreads, 1)),
    )


@dataclass(frozen=True)
class Windowed:
    """The window's choice (stage 4) and, when it ran, the pixel rule's check and the F it started from."""

    choice: WindowChoice
    pixel_choice: PixelCheck | None = None
    pixel_from: int | None = None

    @property
    def F_B(self) -> int:
        return self.choice.F

    @property
    def sigma(self) -> np.ndarray | None:
        return self.choice.sigma


def _window_at(s: Setup, window: str, F: int, top: int | None) -> WindowChoice:
    """The window at order F (under the bands rule raising F up to ``top`` when it needs to)."""
    o = s.orders
    return choose_window(
        window, s.lighting, s.base, F, s.P_B, s.eps, criterion=o.criterion,
        profile=o.profile if not s.rh02 else None, max_view_deg=o.max_view_deg,
        band_energy=s.band_energy, projected=o.coefficients if s.rh02 else None,
        q_max=s.q_max, top=top, map_rows=s.rows_for, nthreads=max(s.nthreads, 1),
    )


def choose_window_for(s: Setup, window: str) -> Windowed:
    """Stage 4: the window (and, under the bands rule, the F it needs) from the coefficients and a
    coarse sample of the reflected field; the map itself is synthesized once, later."""
    return Windowed(_window_at(s, window, s.F_B, None if s.F_forced is not None else s.top))


def pixel_rule_applies(s: Setup, w: Windowed, pixel_rule: bool) -> bool:
    """The pixel rule runs under the bands rule, orders not forced, below the highest order."""
    return pixel_rule and s.F_forced is None and not s.rh02 and w.F_B < s.top


def apply_pixel_rule(s: Setup, w: Windowed, window: str) -> Windowed:
    """Stage 4b: the map as windowed so far, per direction; when its 90th percentile passes √ε, the
    smallest order of the pixel rule's ladder that meets it (bare fields), and the window again there."""
    F_B, choice = w.F_B, w.choice
    check = pixel_statement(s.lighting, s.base, F_B, s.P_B, w.sigma, s.eps, top=s.top, q_max=s.q_max,
                            fields=s.sampler)
    if not check.p90 <= check.tolerance and check.F_reference > F_B:
        check = pixel_orders(s.lighting, s.base, F_B, s.P_B, s.eps, top=s.top, q_max=s.q_max, fields=s.sampler)
        if check.F > F_B:
            choice = _window_at(s, window, check.F, None)
    return Windowed(choice, check, F_B)


def map_size(s: Setup, w: Windowed) -> tuple[int, bool]:
    """Stage 5: the map's rows S and whether the memory budget held them (``size`` overrides)."""
    budget_bound = False
    if s.size is not None:
        S = int(s.size)
    else:
        if s.rh02:
            S = default_size(w.F_B, s.P_B, s.budget_bytes)  # RH02 §5.2: S ≈ 10 F
            budget_bound = S < int(np.clip(10 * w.F_B, 32, 1024))
        else:
            S, budget_bound = map_rows(
                s.orders.profile, s.base, s.band_energy, w.F_B, s.P_B, s.eps, sigma=w.sigma, q_max=s.q_max,
                lighting_rows=s.lighting_rows, max_view_deg=s.orders.max_view_deg, budget_bytes=s.budget_bytes,
            )
        S = fast_map_rows(S, w.F_B, s.P_B, s.budget_bytes)
    if S < 2 or S > 8192:
        raise BadInputError(None, f"SHRM size must be in [2, 8192] rows, got {S}")
    return S, budget_bound


def synthesize(s: Setup, w: Windowed, coefficients: BRDFCoefficients, S: int, env: Any,
               azimuth_free: bool) -> np.ndarray:
    """Stage 6: the S × 2S lat-long maps (float32), refused when they overflow."""
    with np.errstate(over="ignore", invalid="ignore"):  # overflow is checked (and reported) below
        coeffs = global_shrm_latlong(s.lighting, coefficients, w.F_B, s.P_B, S, 2 * S, nthreads=s.nthreads,
                                     azimuth_free=azimuth_free)
    if not np.all(np.isfinite(coeffs)):
        raise BadInputError(
            getattr(env, "source", None) or env.name,
            "the prefiltered radiance overflows float32 maps (radiance values near 1e38?): rescale the map",
        )
    return coeffs


def synthesize_cube(s: Setup, w: Windowed, coefficients: BRDFCoefficients, S: int, cube_size: int | None,
                    azimuth_free: bool) -> np.ndarray:
    """Stage 6b: the same SHRM on a 6 × n × n cube map (default n = S // 2, at least 2)."""
    n_cube = max(2, S // 2) if cube_size is None else int(cube_size)
    if n_cube < 2 or n_cube > 4096:
        raise BadInputError(None, f"cube face size must be in [2, 4096], got {n_cube}")
    return global_shrm_cube(s.lighting, coefficients, w.F_B, s.P_B, n_cube, nthreads=s.nthreads,
                            azimuth_free=azimuth_free)


# ------------------------------------------------------------------------------ statements


@dataclass(frozen=True)
class Statement:
    """Stage 7: every error the SHRM states of itself."""

    bands: list[dict]  # meta["view_bands"]
    map_budget: MapAssessment
    budget_bound: bool
    window_cost: float
    unwindowed: float
    pixels: PixelCheck
    eps: dict[str, float]  # SHRM.eps


def _bands(s: Setup, w: Windowed, signal: np.ndarray | None = None, rows: int | None = None) -> BandStatement:
    """The per-band statement of the map as made (``rows=None``: exact lookup)."""
    return shrm_view_bands(s.orders.profile, s.base, s.band_energy, w.F_B, s.P_B, sigma=w.sigma, q_max=s.q_max,
                           map_rows=rows, lighting_rows=s.lighting_rows, max_view_deg=s.orders.max_view_deg,
                           signal_band_energy=signal)


def _add_lights(bands: list[dict], residual_bands: list[dict], s: Setup, extraction: Extraction, brdf: Any,
                map_radiance: Callable) -> None:
    """Add to ``bands`` (in place; the statement relative to the whole map's reflection) the lights'
    merge error and the statements relative to the map without its lights (``*_residual``)."""
    merge_res, merge_whole = (np.zeros(len(residual_bands)),) * 2
    if extraction.merged:
        light_set = extraction.lights
        merge_res, merge_whole = merge_error_by_band(
            extraction, brdf, map_radiance, s.orders.profile.edges_deg,
            whole=lambda R, V: map_radiance(R, V) + light_set.radiance(brdf, R, V))
    for band, own, extra_res, extra in zip(bands, residual_bands, merge_res, merge_whole, strict=True):
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


def _map_assessment(s: Setup, w: Windowed, S: int, statement: BandStatement, raw_bands: list[dict],
                    signal: np.ndarray | None, budget_bound: bool) -> MapAssessment:
    """What the map's size costs the statement, and whether a cap made a bound say nothing (issue 29)."""
    o = s.orders
    return assess_map(
        statement.bands, raw_bands, _bands(s, w, signal, None).bands, rows=S, P=s.P_B, budget_bytes=s.budget_bytes,
        inside=list(bands_inside(o.profile, o.max_view_deg)), capped=budget_bound,
        rows_needed=lambda: fast_map_rows(map_rows(
            o.profile, s.base, s.band_energy, w.F_B, s.P_B, s.eps, sigma=w.sigma, q_max=s.q_max,
            lighting_rows=s.lighting_rows, max_view_deg=o.max_view_deg,
            budget_bytes=1 << 62)[0], w.F_B, s.P_B, 1 << 62))


def _reflected(s: Setup, w: Windowed, S: int, statement: BandStatement) -> tuple[float, float, float, float]:
    """(ε_B, its bound, ε_B without the window, the window's cost) on the coefficients the map was
    made of (the projection for rh02, the view fit for bands): the window's cost, the energy of its
    change over all views, is exact for either."""
    truncation, cost = reflected_error_parts(s.lighting, s.base, w.F_B, s.P_B, w.sigma, q_max=s.q_max)
    if s.rh02:
        reflected = float((truncation + cost).max())
        unwindowed = float(truncation.max())
        bound = residual_bound(s.lighting, s.base, w.F_B, s.P_B, w.sigma, q_max=s.q_max)
    else:  # fitted coefficients: Parseval no longer splits the error; the view-band sums do
        reflected, bound = statement.eps_predicted, statement.eps_bound
        unwindowed = reflected if w.sigma is None else shrm_view_bands(
            s.orders.profile, s.base, s.band_energy, w.F_B, s.P_B, q_max=s.q_max, map_rows=S,
            lighting_rows=s.lighting_rows, max_view_deg=s.orders.max_view_deg,
        ).eps_predicted
    return reflected, bound, unwindowed, float(cost.max())


def state_errors(s: Setup, w: Windowed, S: int, budget_bound: bool, extraction: Extraction, brdf: Any,
                 source_env: Any, map_radiance: Callable) -> Statement:
    """Stage 7: the per-band statement (with the lights' share), the map budget's assessment, ε_B and
    its bound, the per-direction (pixel) statement against a higher order, and ``SHRM.eps``."""
    statement, signal = _bands(s, w, rows=S), None
    raw_bands = [dict(b) for b in statement.bands]  # before the lights and the map assessment add keys
    if len(extraction.lights):
        # the maps hold the map without its lights: relative to that reflection (what holds away from
        # the lights, ``*_residual``) and, the main statement, to the whole map's reflection (the
        # lights add signal and, where merged from pixels, their merge error)
        signal = lighting_for(source_env, s.orders, F=s.F_forced, nthreads=s.nthreads).band_energy_all()
        residual_bands, statement = statement.bands, _bands(s, w, signal, S)
        raw_bands = [dict(b) for b in statement.bands]
        _add_lights(statement.bands, residual_bands, s, extraction, brdf, map_radiance)
    map_budget = _map_assessment(s, w, S, statement, raw_bands, signal, budget_bound)
    reflected, bound, unwindowed, cost = _reflected(s, w, S, statement)
    reference = w.pixel_choice.F_reference if w.pixel_choice is not None else None
    pixels = pixel_statement(s.lighting, s.base, w.F_B, s.P_B, w.sigma, s.eps, top=s.top, q_max=s.q_max,
                             fields=s.sampler, F_reference=reference)
    eps = {
        "brdf": s.orders.eps_at(min(w.F_B, s.orders.F0), s.P_B),
        "lighting": float(s.lighting.eps()[min(w.F_B, s.lighting.lmax)]),
        "reflected": reflected,
        "bound": bound,
        "gibbs_negative": w.choice.normal_after,  # the normal views V = R of the undershoot sample
    }
    return Statement(statement.bands, map_budget, budget_bound, cost, unwindowed, pixels, eps)


# ---------------------------------------------------------------------------------- record


def _lights_info(extraction: Extraction, brdf: Any, requested: str | int) -> LightsInfo:
    n = len(extraction.lights)
    return LightsInfo(
        requested=requested, lights=tuple(light.to_dict() for light in extraction.lights.lights),
        flux_share=extraction.flux_share,
        threshold=float(extraction.threshold) if np.isfinite(extraction.threshold) else None,
        left_in_map=int(extraction.skipped),
        brdf=(brdf.to_spec() if brdf.kind == "analytic" else getattr(brdf, "source", None)) if n else None,
        statement_signal="the reflection of the map without its lights" if n else "the reflection",
    )


def _window_info(w: Windowed, requested: str, st: Statement, P_B: int) -> WindowInfo:
    c = w.choice
    return WindowInfo(
        used="lanczos" if c.strength > 0.0 else "none", requested=requested, strength=float(c.strength),
        reason=c.reason, threshold=WINDOW_THRESHOLD, cost=st.window_cost, eps_reflected_unwindowed=st.unwindowed,
        negative_before=c.before, negative_after=c.after, negative_fraction_after=c.negative_fraction,
        negative_max_view_deg=float(max(v[0] for v in LOCAL_VIEWS_DEG)) if P_B > 0 else 0.0,
        negative_sample_pairs=c.pairs, capped=bool(c.capped),
    )


def _caps(s: Setup, w: Windowed, st: Statement) -> tuple[str, ...]:
    """Every budget that stops the rule from meeting ε (orders' caps, the map's resolution of the
    lighting, the window, the map's memory budget, the pixel rule)."""
    pixel_capped = w.pixel_choice is not None and w.pixel_choice.capped
    return tuple(name for name, hit in (
        ("orders: max_F/max_P", s.orders.capped),
        ("lighting: the map's resolution (F_B at its lmax)", s.scene.capped),
        ("window budget", w.choice.capped),
        (f"map budget: {s.budget_bytes / 2**20:g} MiB", st.budget_bound),
        ("pixel rule: no order the lighting holds meets √ε per direction", pixel_capped)) if hit)


def _size_note(s: Setup, st: Statement, S: int) -> str:
    if st.map_budget.note or not st.budget_bound:
        return st.map_budget.note or ""
    assert st.map_budget.bytes_needed is not None  # the budget held the rows: the rows that meet eps are known
    return (f"map rows held at {S} by the {s.budget_bytes / 2**20:g} MiB budget ({st.map_budget.rows_needed} rows, "
            f"{st.map_budget.bytes_needed / 2**20:.0f} MiB, would meet eps; use size= or budget_bytes=)")


def record(s: Setup, w: Windowed, st: Statement, S: int, *, brdf: Any, source_env: Any, extraction: Extraction,
           lights: str | int, window: str, F: int | None, P: int | None, azimuth_free: bool,
           timings: Timings) -> PrefilterInfo:
    """Stage 8: the :class:`~shrmkit.analysis.records.PrefilterInfo` of the run (``SHRM.meta``)."""
    o, caps = s.orders, _caps(s, w, st)
    return PrefilterInfo(
        brdf=brdf.name, environment=source_env.name, environment_source=getattr(source_env, "source", ""),
        lights=_lights_info(extraction, brdf, lights), F_rho=o.F, P_rho=o.P, F_L=s.scene.F_L,
        lighting_capped=bool(s.scene.lighting_capped),
        orders_message="; ".join(m for m in (o.message, s.clamp_note, _size_note(s, st, S)) if m),
        orders_asked=None if F is None and P is None else {"F": F if F is None else int(F),
                                                           "P": P if P is None else int(P)},
        timings=timings, version=__version__, frame=FRAME, azimuth_free=bool(azimuth_free),
        window=_window_info(w, window, st, s.P_B), criterion=o.criterion, max_view_deg=o.max_view_deg,
        scene_capped=bool(s.scene.capped), capped=bool(caps), capped_by=caps,
        # the rule's check: from F_B (the energy rule's, after the window) to F (raised when it failed)
        pixel_rule={**w.pixel_choice.to_dict(), "F_from": w.pixel_from} if w.pixel_choice is not None else None,
        pixel_errors=st.pixels.to_dict(), view_bands=tuple(ViewBand.from_json(b) for b in st.bands),
        map_budget=st.map_budget.to_dict(), extrapolated_samples=int(o.n_without_data),
    )
