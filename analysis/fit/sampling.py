"""Direction samples a model is fitted to, with their quadrature weights.

A fit compares a model with a BRDF on a finite set of direction pairs (L, V):
:func:`collect_samples` builds that set (:class:`FitSamples`) — analytic and tabulated BRDFs on
half/difference angles [Rus98] drawn by a shifted Kronecker sequence [Roberts18]
(:func:`kronecker_points`), MERL tables snapped to their nodes [MERL03], scattered measurements as
they are — with quadrature weights that make a weighted squared error an estimate of the L² error
of ρ·cos θ_i that [RH02] uses, pairs beyond the grazing cut of [Ngan05] left out.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, cast

import numpy as np

from ...brdf_io.brdf import BRDF
from ...brdf_io.errors import BadInputError
from ...brdf_io.halfdiff import halfdiff_to_directions
from ...brdf_io.masked_grid import eval_with_mask
from ...brdf_io.merl import MERL_DIMS, merl_index_coordinates, merl_sample_angles

if TYPE_CHECKING:
    from ...brdf_io.cornell import ScatteredBRDF

__all__ = ["FitSamples", "sample_halfdiff", "collect_samples"]


@dataclass(frozen=True, eq=False)
class FitSamples:
    """Direction pairs with measured RGB rho and quadrature weights.

    Attributes
    ----------
    L, V
        Unit directions (n, 3), local frame, normal +z, both away from the surface.
    rho
        Measured rho (n, 3) in 1/sr (no cosine).
    weight
        Quadrature weights (n,), see :func:`collect_samples`.
    n_dropped
        Sampled points dropped for lack of data (missing measurements, non-finite values).
    source
        Name of the BRDF the samples came from.
    """

    L: np.ndarray
    V: np.ndarray
    rho: np.ndarray
    weight: np.ndarray
    n_dropped: int
    source: str

    @property
    def cos_i(self) -> np.ndarray:
        return self.L[:, 2]

    @property
    def cos_o(self) -> np.ndarray:
        return self.V[:, 2]

    def __len__(self) -> int:
        return len(self.weight)


def _snap_to_merl_nodes(
    theta_h: np.ndarray, theta_d: np.ndarray, phi_d: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    nodes = merl_sample_angles()
    index = merl_index_coordinates(theta_h, theta_d, phi_d)
    snapped = []
    for axis, (u, n) in enumerate(zip(index, MERL_DIMS, strict=True)):
        k = np.rint(u).astype(np.int64)
        k = np.mod(k, n) if axis == 2 else np.clip(k, 0, n - 1)  # φ_d wraps (reciprocity)
        snapped.append(nodes[axis][k])
    return snapped[0], snapped[1], snapped[2]


def kronecker_points(n: int, d: int, seed: int = 0) -> np.ndarray:
    """``n`` points of the randomly shifted Kronecker sequence R_d in [0, 1)^d, shape (n, d).

    u_i = frac(s + i·α) for i = 1…n, α_j = g^−j (j = 1…d) with g the positive root of
    g^(d+1) = g + 1 (Roberts 2018's generalised golden ratio), and s a shift drawn from
    ``numpy.random.default_rng(seed)`` (Cranley–Patterson randomisation). A low-discrepancy
    set like a scrambled Sobol net, made in numpy: ``scipy.stats.qmc`` would cost a command
    ~0.4 s CPU to import.

    Raises
    ------
    ValueError
        ``n`` or ``d`` below 1.
    """
    if n < 1 or d < 1:
        raise ValueError(f"need n >= 1 and d >= 1, got n={n}, d={d}")
    g = 2.0
    for _ in range(80):  # fixed point of g = (1 + g)^(1/(d+1)): a contraction, converged to float64
        g = (1.0 + g) ** (1.0 / (d + 1))
    alpha = g ** -np.arange(1, d + 1, dtype=np.float64)
    shift = np.random.default_rng(seed).random(d)
    i = np.arange(1, n + 1, dtype=np.float64)[:, None]
    return np.mod(shift + i * alpha, 1.0)


def sample_halfdiff(
    n: int, *, seed: int = 0, max_theta_deg: float = 80.0, merl_nodes: bool = False
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Low-discrepancy direction pairs (:func:`kronecker_points`) in half/difference angles,
    kept where θ_i, θ_o <= max_theta_deg.

    Parameters
    ----------
    n
        Number of pairs drawn (a power of two is used internally; about 60–70 % survive
        the default 80° cut).
    seed
        Seed of the sequence's random shift: the same seed gives the same pairs.
    max_theta_deg
        Largest θ_i and θ_o kept, in degrees (0, 90].
    merl_nodes
        Snap the directions to the nearest MERL table node (the weights stay those of
        the drawn points: each node stands for its cell, a midpoint rule).

    Returns
    -------
    L, V, weight
        Directions (m, 3) and quadrature weights (m,) with Σ weight ≈ ∫∫ dω_i dω_o over the
        kept region (= (2π)² when max_theta_deg = 90).
    """
    if not 0.0 < max_theta_deg <= 90.0:
        raise BadInputError(None, f"max_theta_deg must be in (0, 90], got {max_theta_deg}")
    if n < 16:
        raise BadInputError(None, f"need at least 16 samples, got {n}")
    m = int(np.ceil(np.log2(n)))
    u = kronecker_points(1 << m, 3, seed)
    u = np.clip(u, 1e-12, 1.0 - 1e-12)
    theta_h = 0.5 * np.pi * u[:, 0] ** 2
    theta_d = 0.5 * np.pi * u[:, 1]
    phi_d = np.pi * u[:, 2]
    pdf = (2.0 * np.pi * theta_h) ** -0.5 * (2.0 / np.pi) * (1.0 / np.pi)
    jac = 4.0 * np.cos(theta_d) * np.sin(theta_h) * np.sin(theta_d)
    weight = 2.0 * np.pi * 2.0 * jac / pdf / len(u)
    if merl_nodes:
        theta_h, theta_d, phi_d = _snap_to_merl_nodes(theta_h, theta_d, phi_d)
    L, V = halfdiff_to_directions(theta_h, theta_d, phi_d)
    cos_max = np.cos(np.radians(max_theta_deg))
    keep = (L[:, 2] >= cos_max - 1e-12) & (V[:, 2] >= cos_max - 1e-12) & (L[:, 2] > 0) & (V[:, 2] > 0)
    return L[keep], V[keep], weight[keep]


def collect_samples(
    brdf: BRDF, *, n_samples: int = 32768, seed: int = 0, max_theta_deg: float = 80.0
) -> FitSamples:
    """The samples a fit of ``brdf`` uses.

    * **analytic and tabulated BRDFs** are sampled in Rusinkiewicz half/difference angles [Rus98]
      with a randomly shifted Kronecker (R_d) low-discrepancy sequence [Roberts18] (:func:`kronecker_points`,
      deterministic given ``seed``):
      θ_h = (π/2) u₀² (the square-root scale of MERL's θ_h axis: dense near the specular
      peak, so even lobes with exponents ~10⁴ get thousands of samples), θ_d = (π/2) u₁,
      φ_d = π u₂ (φ_d and φ_d + π are the same pair by reciprocity). The BRDF is evaluated
      with its data mask (``eval_masked`` where it has one, else ``eval``); points without
      data (missing measurements, non-finite values) are dropped.
    * **MERL tables**: the same samples are snapped to the nearest table node (θ_h, θ_d, φ_d
      of ``merl_sample_angles``), so the fit compares the model with the stored measurements
      rather than with trilinear interpolations between them (which flatten sharp peaks).
      The points are uniform in MERL index space, so every node is equally likely.
    * **scattered BRDFs** (Cornell measurements) contribute their own (L, V, rgb) samples.

    Each sample carries a quadrature weight ``w`` such that Σ w g ≈ ∫∫ g dω_i dω_o over the
    pairs kept, so a weighted squared error is an estimate of the L² error of ρ·cos θ_i that
    [RH02] uses. With dω_i dω_o = 4 cos θ_d dω_h dω_d ([Rus98]) and the sampling
    density p(θ_h, θ_d, φ_d) = (2π θ_h)^(−1/2) · (2/π) · (1/π),

        w = 2π (φ_h) · 2 (φ_d ≡ φ_d + π) · 4 cos θ_d sin θ_h sin θ_d / p / n.

    Grazing angles are handled in two documented ways: pairs with θ_i or θ_o above
    ``max_theta_deg`` (default 80°, the cut of [Ngan05] — MERL and Cornell data are
    unreliable and enormous there) are not used, and the residual is taken on ρ·cos θ_i, whose
    cosine damps grazing incidence. Scattered samples all get weight 1 (the Cornell gantry
    spreads them roughly evenly over its angle range).

    Raises
    ------
    BadInputError
        Too few usable samples, or measured values that are negative or infinite.
    """
    name = getattr(brdf, "name", type(brdf).__name__)
    if getattr(brdf, "kind", None) == "scattered":
        scattered = cast("ScatteredBRDF", brdf)  # the BRDFs of kind "scattered" (duck-typed by kind)
        L = np.asarray(scattered.L, dtype=np.float64)
        V = np.asarray(scattered.V, dtype=np.float64)
        rho = np.asarray(scattered.rgb, dtype=np.float64)
        cos_max = np.cos(np.radians(max_theta_deg))
        inside = (L[:, 2] >= cos_max - 1e-9) & (V[:, 2] >= cos_max - 1e-9) & (L[:, 2] > 0) & (V[:, 2] > 0)
        finite = np.all(np.isfinite(rho), axis=1)
        keep = inside & finite
        n_dropped = int(np.count_nonzero(inside & ~finite))
        L, V, rho = L[keep], V[keep], rho[keep]
        weight = np.ones(len(L))
    else:
        merl = getattr(getattr(brdf, "values", None), "shape", None) == (3, 90, 90, 180)
        L, V, weight = sample_halfdiff(n_samples, seed=seed, max_theta_deg=max_theta_deg, merl_nodes=merl)
        rho, has = eval_with_mask(brdf, L, V)
        rho = np.asarray(rho, dtype=np.float64)
        finite = has & np.all(np.isfinite(rho), axis=1)
        n_dropped = int(np.count_nonzero(~finite))
        L, V, rho, weight = L[finite], V[finite], rho[finite], weight[finite]
    if len(L) < 64:
        raise BadInputError(name, f"only {len(L)} usable samples to fit (need at least 64)")
    if np.any(np.isinf(rho)):
        raise BadInputError(name, "BRDF values are infinite")
    if np.any(rho < -1e-3 * np.max(np.abs(rho))):
        raise BadInputError(name, f"BRDF values are negative (min {rho.min():.3g})")
    if not np.any(rho > 0):
        raise BadInputError(name, "BRDF is zero everywhere: nothing to fit")
    rho = np.maximum(rho, 0.0)
    return FitSamples(L=L, V=V, rho=rho, weight=weight, n_dropped=n_dropped, source=str(name))
