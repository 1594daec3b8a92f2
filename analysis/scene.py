"""Scene orders and the residual error bound ([RH02] §5.1 and Appendix B, re-derived).

The reflected light field has coefficients B_lmpq = L_lm ρ̂_lpq on the orthogonal
functions 𝒟^l_mq(α, β) Y_pq(ω_o'), and ∫|𝒟^l_mq|² dΩ = Λ_l² = 4π/(2l+1). Hence

    ‖B‖² = Σ_l Λ_l² a_l r_l,   a_l = Σ_m |L_lm|²,   r_l = Σ_{p,q} ρ̂_lpq² (q ≠ 0 twice),

and truncating to l <= F, p <= P leaves the error energy

    E_err = Σ_{l>F} Λ_l² a_l r_l + Σ_{l<=F} Λ_l² a_l r_l^{(p>P)}.

Residual bound (using only residual energies): for non-negative terms
Σ_{l>F} x_l y_l <= (Σ_{l>F} x_l)(Σ_{l>F} y_l), and Λ_l is decreasing, so

    E_err <= U = Λ_{F+1}² (E_L ε_L(F)) (E_ρ ε_ρ^l(F)) + max_{l<=F}(Λ_l² a_l) E_ρ ε_ρ^p(F, P),

with ε_ρ^l(F) the fraction of ρ̂'s energy at l > F and ε_ρ^p(F, P) the fraction at
l <= F, p > P. With C the captured energy (known exactly), the relative error obeys
ε_B = E_err/(C + E_err) <= U/(C + U). ([RH02] Appendix B states a bound of this kind; its
Λ power is fixed here by the normalization ∫|𝒟|² = Λ².) Per RGB channel; the worst
channel is reported.

Windows (σ-factors against Gibbs ringing, DESIGN §7): multiplying the kept coefficients
by σ_lp ∈ [0, 1] adds the energy W = Σ_{l<=F, p<=P} Λ_l² a_l r_lp (1 − σ_lp)², orthogonal
to the truncated part, so ε_B = (E_err + W)/(C + E_err); since W <= C this grows with
E_err and ε_B <= (U + W)/(C + U) still bounds it.

Reference: [RH02] (``data_specs/bibliography.md``).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from ..brdf_io.envmap import EnvironmentMap
from .brdf_coeffs import BRDFCoefficients
from .lighting import LightingCoefficients, lighting_coefficients, point_band_energy
from .orders import CAPPED_SLACK, OrderChoice
from .sh import Lambda
from .view_bands import bands_inside, scene_error_curve, shrm_view_bands, window_matrix

__all__ = [
    "SceneOrders", "scene_orders", "scene_for", "lighting_for", "lighting_lmax", "reflected_error",
    "reflected_error_parts",
    "residual_bound", "lanczos_window", "lanczos_sigma",
]


@dataclass(frozen=True)
class SceneOrders:
    """Orders a scene needs (:func:`scene_orders`): F_B, P_B = P_ρ, and what they achieve.

    ``bound`` is RH02's residual bound on ε_B (energy, all views; ``"rh02"``) or the worst
    ``bound_rel_rms`` inside the view limit (relative RMS; ``"bands"``), as ``bound_units``
    says. ``view_bands`` holds the per-band statement without the map's own loss (that needs
    the map size: :func:`~shrmkit.analysis.shrm.prefilter`)."""

    F_rho: int
    P_rho: int
    F_L: int
    F_B: int
    P_B: int
    eps_L: float
    lighting_capped: bool
    bound: float
    tolerance: float
    criterion: str = "rh02"
    capped: bool = False
    bound_units: str = "energy fraction (RH02 eps)"
    view_bands: tuple = ()


def _brdf_lp_energies(
    coefficients: BRDFCoefficients, P: int, q_max: int | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """r_lp kept (p <= P, |q| <= q_max) per (l, p) (F0+1, P+1, 3), and r_l of all (p, q) (F0+1, 3)."""
    terms = coefficients.parseval_terms()  # (F0+1, P0+1, P0+1 over q, 3)
    q_stop = None if q_max is None else q_max + 1
    return terms[:, : P + 1, :q_stop].sum(axis=2), terms.sum(axis=(1, 2))


def _kept_energy(a: np.ndarray, kept_lp: np.ndarray, F: int) -> np.ndarray:
    """Λ_l² a_l r_lp of the kept terms (l <= F), per (l, p, channel): (F+1, P+1, 3)."""
    lam2 = Lambda(np.arange(F + 1))[:, None, None] ** 2
    return lam2 * a[: F + 1, None] * kept_lp[: F + 1]


def _window_cost(window: np.ndarray | None, kept: np.ndarray, F: int, P: int) -> np.ndarray:
    """Energy a window σ_lp removes from the kept terms, Σ (1 − σ_lp)² Λ_l² a_l r_lp, per channel."""
    if window is None:
        return np.zeros(kept.shape[-1])
    return ((1.0 - window_matrix(window, F, P))[..., None] ** 2 * kept).sum(axis=(0, 1))


def reflected_error_parts(
    lighting: LightingCoefficients,
    coefficients: BRDFCoefficients,
    F: int,
    P: int,
    window: np.ndarray | None = None,
    *,
    q_max: int | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Per channel (3,): the truncation part E_err/total and the window part W/total of ε_B
    (module docs), so that ε_B = max over channels of their sum. A window σ(t) = 1 − t(1 − σ)
    has the window part t² W/total: the strength a budget allows follows in closed form."""
    a = lighting.band_energy()
    kept_lp, all_l = _brdf_lp_energies(coefficients, P, q_max)
    n = min(a.shape[0], all_l.shape[0])
    lam2 = Lambda(np.arange(n))[:, None] ** 2
    full = lam2 * a[:n] * all_l[:n]
    kept = _kept_energy(a, kept_lp, F)
    total = full.sum(axis=0)
    error = total - kept.sum(axis=(0, 1))
    cost = _window_cost(window, kept, F, P)
    live = total > 1e-300
    safe = np.where(live, total, 1.0)
    return np.where(live, error / safe, 0.0), np.where(live, cost / safe, 0.0)


def reflected_error(
    lighting: LightingCoefficients,
    coefficients: BRDFCoefficients,
    F: int,
    P: int,
    window: np.ndarray | None = None,
    *,
    q_max: int | None = None,
) -> float:
    """Relative energy error ε_B of truncating B to l <= F, p <= P, against all the
    coefficients available (l <= min(F0, lmax), p <= P0); worst channel.

    With a ``window`` σ_l (shape (F+1,)) or σ_lp (shape (F+1, P+1)) multiplying the kept
    coefficients, the kept bands contribute their attenuation Σ Λ_l² a_l r_lp (1 − σ_lp)²
    to the error as well. ``q_max=0`` keeps only the azimuth-free terms (Kautz & McCool 2000).
    """
    truncation, cost = reflected_error_parts(lighting, coefficients, F, P, window, q_max=q_max)
    return float((truncation + cost).max())


def lanczos_window(F: int) -> np.ndarray:
    """Lanczos σ-factors σ_l = sinc(l/(F+1)), l = 0..F: damp the Gibbs ringing of a
    truncated expansion at the cost of some blur (the cost enters :func:`reflected_error`)."""
    return np.sinc(np.arange(F + 1) / (F + 1.0))


def lanczos_sigma(F: int, P: int, strength: float = 1.0, *, in_view: bool = True) -> np.ndarray:
    """Lanczos σ-factors in both orders, at a ``strength`` t in [0, 1]:

        σ_lp(t) = 1 − t (1 − sinc(l/(F+1)) sinc(p/(P+1))),   l = 0..F, p = 0..P,

    shape (F+1, P+1). t = 1 is the full Lanczos window (in l, and in the view order p, whose
    truncation rings too); t = 0 is no window. The synthesis is linear in σ, so the map at
    strength t is (1 − t)·(map without window) + t·(map with the full window), and the window
    part of ε_B is t² times that of the full window (:func:`reflected_error_parts`)."""
    t = float(strength)
    if not 0.0 <= t <= 1.0:
        raise ValueError(f"strength must be in [0, 1], got {strength!r}")
    view = np.sinc(np.arange(P + 1) / (P + 1.0)) if in_view else np.ones(P + 1)
    full = np.outer(lanczos_window(F), view)
    return 1.0 - t * (1.0 - full)


def residual_bound(
    lighting: LightingCoefficients,
    coefficients: BRDFCoefficients,
    F: int,
    P: int,
    window: np.ndarray | None = None,
    *,
    q_max: int | None = None,
) -> float:
    """Conservative upper bound U/(C + U) on ε_B from residual energies (module docs); with a
    ``window`` (as in :func:`reflected_error`), (U + W)/(C + U) with its exact cost W."""
    a = lighting.band_energy()
    kept_lp, all_l = _brdf_lp_energies(coefficients, P, q_max)
    r_in = kept_lp.sum(axis=1)
    r_out = all_l - r_in
    E_L = lighting.energy
    E_rho = coefficients.energy
    lam = Lambda(np.arange(F + 2))
    beyond_L = np.clip(E_L - a[: F + 1].sum(axis=0), 0.0, None)  # E_L ε_L(F)
    beyond_rho_l = np.clip(E_rho - (r_in[: F + 1] + r_out[: F + 1]).sum(axis=0), 0.0, None)
    beyond_rho_p = r_out[: F + 1].sum(axis=0)
    kept = (lam[: F + 1, None] ** 2 * a[: F + 1] * r_in[: F + 1]).sum(axis=0)
    peak = (lam[: F + 1, None] ** 2 * a[: F + 1]).max(axis=0)
    U = lam[F + 1] ** 2 * beyond_L * beyond_rho_l + peak * beyond_rho_p
    W = _window_cost(window, _kept_energy(a, kept_lp, F), F, P)
    live = (kept + U) > 1e-300
    return float(((U[live] + W[live]) / (kept[live] + U[live])).max())


def scene_orders(orders: OrderChoice, lighting: LightingCoefficients) -> SceneOrders:
    """F_L, F_B, P_B = P_ρ and what they achieve, by the orders' criterion.

    - ``"rh02"``: F_B = min(F_ρ, F_L) (RH02 §5.1) and the residual bound (module docs).
    - ``"bands"``: F_B = the smallest F <= the lighting's lmax whose reflected field meets the
      tolerance in every view band inside the limit, from the product spectrum
      Λ_l² a_l ρ̂² per band (:func:`~shrmkit.analysis.view_bands.scene_error_curve`):
      a sharp light under a sharp BRDF gets the F it needs (the min rule ignores the lighting
      energy above F_L that the BRDF passes), a smooth one the F it needs. When no F reaches
      the tolerance (``capped``), the smallest F within CAPPED_SLACK·ε of the best.
    """
    tol = orders.tolerance
    eps_L = lighting.eps()
    ok = np.nonzero(eps_L <= tol)[0]
    light_capped = ok.size == 0
    F_L = int(ok[0]) if ok.size else lighting.lmax
    P_B = orders.P
    if orders.criterion == "rh02":
        F_B = min(orders.F, F_L)
        return SceneOrders(
            F_rho=orders.F, P_rho=orders.P, F_L=F_L, F_B=F_B, P_B=P_B, eps_L=float(eps_L[F_L]),
            lighting_capped=light_capped, bound=residual_bound(lighting, orders.coefficients, F_B, P_B),
            tolerance=tol, criterion="rh02",
        )
    coefficients = orders.coefficients_for(P_B)
    band_energy = lighting.band_energy_all()
    curve = scene_error_curve(orders.profile, coefficients, band_energy, P_B)
    inside = bands_inside(orders.profile, orders.max_view_deg)
    top = min(lighting.lmax, curve.shape[1] - 1)
    worst = curve[inside, : top + 1].max(axis=0)
    meets = np.nonzero(worst <= tol)[0]
    capped = meets.size == 0
    F_B = int(meets[0]) if meets.size else int(np.nonzero(worst <= worst.min() + CAPPED_SLACK * tol)[0][0])
    bands = shrm_view_bands(orders.profile, coefficients, band_energy, F_B, P_B, max_view_deg=orders.max_view_deg).bands
    return SceneOrders(
        F_rho=orders.F, P_rho=orders.P, F_L=F_L, F_B=F_B, P_B=P_B, eps_L=float(eps_L[F_L]),
        lighting_capped=light_capped, bound=max(b["bound_rel_rms"] for b in bands if b["inside"]),
        tolerance=tol, criterion="bands", capped=capped, bound_units="relative RMS (worst band inside the view limit)",
        view_bands=tuple(bands),
    )


def lighting_lmax(orders: OrderChoice, env_height: int, F: int | None = None) -> int:
    """The lighting order computed for a scene: beyond F_ρ, so that the achieved error and the
    bound see the residual energy, but never above what the map resolves (rows − 1) or what
    the BRDF coefficients hold (F0). ``"rh02"``: max(2F_ρ, F_ρ + 16) (or a forced ``F``);
    ``"bands"``: all of F0, so that F_B may exceed F_ρ where a sharp light needs it and the
    per-band statement knows the lighting wherever the BRDF has energy."""
    if orders.criterion != "rh02":
        return int(min(env_height - 1, orders.F0))
    return int(min(max(2 * orders.F, orders.F + 16, F or 0), env_height - 1, orders.F0))


def scene_for(
    env: EnvironmentMap, orders: OrderChoice, *, F: int | None = None, nthreads: int = 0
) -> tuple[LightingCoefficients, SceneOrders]:
    """The lighting coefficients to :func:`lighting_lmax` and the scene orders of ``env`` with
    a BRDF's ``orders``: the one rule used by ``prefilter``, ``shrm orders --env`` and
    ``shrm report``."""
    lighting = lighting_for(env, orders, F=F, nthreads=nthreads)
    return lighting, scene_orders(orders, lighting)


def lighting_for(
    env: EnvironmentMap, orders: OrderChoice, *, F: int | None = None, nthreads: int = 0
) -> LightingCoefficients:
    """The lighting coefficients of ``env`` to :func:`lighting_lmax`, and (``"bands"``) the pixels'
    point-light band energies beyond them up to the BRDF's F0."""
    lmax = lighting_lmax(orders, env.radiance.shape[0], F)
    lighting = lighting_coefficients(env.radiance, lmax, name=env.name, nthreads=nthreads)
    if orders.criterion != "rh02" and orders.F0 > lmax:
        # the per-band statement needs the lighting wherever the BRDF has energy: the pixels'
        # point-light spectrum beyond the map's Nyquist limit (what the angular reference sees)
        beyond = point_band_energy(env.radiance, lmax + 1, orders.F0, nthreads=max(nthreads, 1))
        lighting = dataclasses.replace(lighting, beyond=beyond)
    return lighting
