"""The variable-projection objective of a fit.

For shape parameters x the model is ρ = B(x) c with per-channel colour weights c >= 0
(``models_param.py``). The weights are not searched by nlopt: for each x they are the
exact minimizer of the weighted least-squares error (the metric's weights,
``metrics.lsq_weights``) under the physical bounds c >= 0 and Σ a_j c_j <= 1 (energy), a
tiny convex quadratic program solved here in closed form by enumerating its faces. The
objective seen by nlopt is the reduced functional

    φ(x) = min_c Σ_s Σ_ch W_s,ch ((B(x) c)_s,ch − y_s,ch)² cos² θ_i

(variable projection, [GP73]). Eliminating the linear weights leaves nlopt 1–2 dimensions per lobe
instead of 4–8, removes the scale degeneracies between weights and shapes, and makes
multi-start fits fast and robust.
"""

from __future__ import annotations

import functools
import itertools

import numpy as np

from .metrics import METRICS, log_epsilon, lsq_weights
from .models_param import Geometry, ModelParam
from .sampling import FitSamples

__all__ = ["solve_bounded_lsq", "ProjectedObjective"]

_LOG_IRLS = 3  # reweighting passes of the log metric
_LOG_TINY = -700.0  # columns whose true scale is below e^-700 cannot carry a weight


@functools.cache
def _faces(m: int, constrained: bool) -> tuple[np.ndarray, np.ndarray]:
    free = np.array(list(itertools.product([False, True], repeat=m)), dtype=bool)
    if not constrained:
        return free, np.zeros(len(free), dtype=bool)
    active = np.concatenate([np.zeros(len(free), bool), np.ones(len(free), bool)])
    free = np.concatenate([free, free])
    keep = ~active | free.any(axis=1)
    return free[keep], active[keep]


def solve_bounded_lsq(G: np.ndarray, b: np.ndarray, a: np.ndarray | None = None) -> np.ndarray:
    """Minimize cᵀGc − 2bᵀc subject to c >= 0 and (optionally) aᵀc <= 1, per channel.

    The problem is convex, so its minimum is the unconstrained minimum of one face of
    the feasible polytope; every face (free set × constraint active or not) is solved by
    its KKT system and the best feasible candidate kept.

    Parameters
    ----------
    G
        Gram matrices (k, m, m), symmetric positive semi-definite.
    b
        Right-hand sides (k, m).
    a
        Constraint coefficients (m,) >= 0, or None for c >= 0 only.

    Returns
    -------
    c
        Minimizers (k, m), c >= 0.
    """
    k, m, _ = G.shape
    scale = max(float(np.max(np.abs(np.diagonal(G, axis1=1, axis2=2)))), 1e-300)
    G = G + 1e-12 * scale * np.eye(m)
    free, active = _faces(m, a is not None)
    F = len(free)
    K = np.zeros((k, F, m + 1, m + 1))
    rhs = np.zeros((k, F, m + 1))
    eye = np.eye(m + 1)
    rows_free = np.concatenate([free, np.zeros((F, 1), bool)], axis=1)
    K[:] = np.where(rows_free[None, :, :, None], np.pad(G, ((0, 0), (0, 1), (0, 1)))[:, None], eye)
    rhs[:, :, :m] = np.where(free[None], b[:, None, :], 0.0)
    if a is not None:
        a = np.asarray(a, dtype=np.float64)
        ea = np.where(free, a, 0.0) * active[:, None]  # (F, m)
        K[:, :, :m, m] = ea[None]
        K[:, :, m, :m] = ea[None]
        K[:, :, m, m] = np.where(active, -1e-14 * scale, 1.0)[None]
        rhs[:, :, m] = np.where(active, 1.0, 0.0)[None]
    try:
        sol = np.linalg.solve(K, rhs[..., None])[..., 0]
    except np.linalg.LinAlgError:
        sol = np.einsum("kfij,kfj->kfi", np.linalg.pinv(K), rhs)
    c = sol[..., :m]
    cmax = np.maximum(np.max(np.abs(c), axis=-1, keepdims=True), 1e-300)
    ok = np.all(c >= -1e-10 * cmax, axis=-1) & np.all(np.isfinite(c), axis=-1)
    c = np.where(np.isfinite(c), np.maximum(c, 0.0), 0.0)
    with np.errstate(over="ignore", invalid="ignore"):
        if a is not None:
            ok &= c @ a <= 1.0 + 1e-9
        q = np.einsum("kfi,kij,kfj->kf", c, G, c) - 2.0 * np.einsum("kfi,ki->kf", c, b)
    q = np.where(ok & np.isfinite(q), q, np.inf)
    best = np.argmin(q, axis=1)
    return c[np.arange(k), best]


class ProjectedObjective:
    """φ(x) of the module docstring, with evaluation counting and best-point tracking.

    For the ``rel`` metric φ is exactly rel_rms² at the optimal weights. For ``log`` the
    weights come from iteratively reweighted least squares with secant weights
    W = w (ln(ε+m) − ln(ε+y))² / (m − y)² (so that the weighted squared residual equals
    the log residual at the current model m; ``_LOG_IRLS`` passes, starting from the
    ``rel`` weights), and φ is the true log_rms² at the best pass.

    Parameters
    ----------
    param
        The model parameterization.
    samples
        Fit samples.
    metric
        ``"rel"`` or ``"log"`` (``metrics.py``).
    energy_conserving
        Impose Σ a_j c_j <= 1 (``models_param`` docstring); otherwise only c >= 0.
    """

    def __init__(self, param: ModelParam, samples: FitSamples, metric: str, energy_conserving: bool) -> None:
        if metric not in METRICS:
            raise ValueError(f"unknown metric {metric!r}; choose one of {METRICS}")
        self.param = param
        self.metric = metric
        self.geo = Geometry.of(samples)
        self.W_rel = lsq_weights(samples, "rel")
        self.w_log = samples.weight[:, None] / (3.0 * np.sum(samples.weight))
        self.eps = log_epsilon(samples)
        self.cos_i = samples.cos_i
        self.target = samples.rho * samples.cos_i[:, None]
        self.log_target = np.log(self.eps + self.target)
        self.peak = float(np.max(samples.rho))
        self.energy_conserving = energy_conserving
        self.evaluations = 0
        self.best_f = np.inf
        self.best_x: np.ndarray | None = None

    def weights(self, x: np.ndarray) -> tuple[float, np.ndarray]:
        """(φ(x), true colour weights c (m, 3)) — c multiplies the unscaled basis."""
        B, log_scale = self.param.basis(x, self.geo)
        usable = log_scale > _LOG_TINY
        a = None
        if self.energy_conserving:
            with np.errstate(over="ignore"):
                a = self.param.energy(x) * np.exp(-np.where(usable, log_scale, 0.0))
            # a column whose largest allowed weight 1/a_j is below 1e-9 of the data's peak
            # cannot contribute: drop it rather than let a huge a_j ruin the KKT systems
            usable &= a * self.peak < 1e9
            a = np.where(usable, a, 1.0)
        A = np.where(usable, B, 0.0) * self.cos_i[:, None]
        W, same = self.W_rel, True
        best_f, best_c = np.inf, np.zeros((3, A.shape[1]))
        for _ in range(1 if self.metric == "rel" else _LOG_IRLS):
            G, b = self._normal_equations(A, W, same)
            c_scaled = np.where(usable, solve_bounded_lsq(G, b, a), 0.0)  # (3, m)
            model = A @ c_scaled.T
            with np.errstate(over="ignore", invalid="ignore"):
                if self.metric == "rel":
                    f = float(np.sum(W * (model - self.target) ** 2))
                else:
                    r_log = np.log(self.eps + np.maximum(model, 0.0)) - self.log_target
                    f = float(np.sum(self.w_log * r_log**2))
                    d = model - self.target
                    tiny = np.abs(d) <= 1e-9 * (self.eps + self.target)
                    W = self.w_log * np.where(tiny, 1.0 / (self.eps + self.target) ** 2,
                                              (r_log / np.where(tiny, 1.0, d)) ** 2)
                    same = False
            if f < best_f:
                best_f, best_c = f, c_scaled
        c_true = np.where(usable, best_c * np.exp(-np.where(usable, log_scale, 0.0)), 0.0)
        return best_f, c_true.T

    def _normal_equations(self, A: np.ndarray, W: np.ndarray, same: bool) -> tuple[np.ndarray, np.ndarray]:
        """Gram matrices Aᵀ W_c A (3, m, m) and Aᵀ W_c y_c (3, m), by BLAS products."""
        if same:  # one weight per sample for all channels
            AW = A * W[:, :1]
            G = np.broadcast_to(AW.T @ A, (3, A.shape[1], A.shape[1])).copy()
            return G, (AW.T @ self.target).T
        AW = [A * W[:, ch : ch + 1] for ch in range(3)]
        G = np.stack([aw.T @ A for aw in AW])
        b = np.stack([aw.T @ self.target[:, ch] for ch, aw in enumerate(AW)])
        return G, b

    def __call__(self, x: np.ndarray, grad: np.ndarray | None = None) -> float:
        """nlopt objective signature f(x, grad); derivative-free (grad is not filled)."""
        x = np.asarray(x, dtype=np.float64)
        f, _ = self.weights(x)
        if not np.isfinite(f):
            f = 1e30
        self.evaluations += 1
        if f < self.best_f:
            self.best_f, self.best_x = f, x.copy()
        return f
