"""Reparameterization of an isotropic BRDF by the reflection vector ([RH02] §3.1, DESIGN §3).

In a frame where the reflection direction R is +z, the outgoing (view) direction is
V' = (θ_o', φ_o') and the incident direction L' = (θ_i', φ_i'). The surface normal is the
bisector N = normalize(R + V') (so θ_v = θ_o'/2 and the viewer is always above the
surface), and

    ρ̂(θ_i', θ_o', φ') = ρ(L, V; N) · max(N·L', 0),      φ' = φ_o' − φ_i',

with ρ evaluated in its own normal-based frame. For an isotropic ρ the result depends
only on (θ_i', θ_o', φ') and is even in φ'. The grid is a quadrature grid for the
transform of [RH02] eq. 13: Gauss–Legendre in cos θ_i' and cos θ_o' (nodes strictly inside
(0, π): the grazing singularity θ_o' = π is never sampled) and uniform in φ'.

Reference: [RH02] (``data_specs/bibliography.md``).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from .brdf import BRDF
from .errors import BadInputError
from .quadrature import gauss_legendre

__all__ = [
    "ReparamGrid", "ReparamBRDF", "reparameterize", "reparam_directions", "sample_rho_hat", "sample_rho_hat_grid",
    "sample_rho_hat_half",
]


@dataclass(frozen=True)
class ReparamGrid:
    """Quadrature grid (θ_i', θ_o', φ') for RH02 eq. 13.

    Parameters
    ----------
    n_theta_i, n_theta_o
        Gauss–Legendre nodes in cos θ over [−1, 1]. n nodes integrate f_lq f_l'q
        exactly for l + l' <= 2n − 1, so ``n_theta_i > F`` and ``n_theta_o > P`` keep
        the discrete basis orthonormal (discrete Bessel inequality: ε >= 0).
    n_phi
        Uniform nodes φ'_k = 2πk/n_phi; cos(qφ') are orthogonal for q + q' < n_phi.
    """

    n_theta_i: int
    n_theta_o: int
    n_phi: int

    def __post_init__(self) -> None:
        for name in ("n_theta_i", "n_theta_o", "n_phi"):
            value = getattr(self, name)
            if not isinstance(value, int | np.integer) or value < 1:
                raise BadInputError(None, f"ReparamGrid.{name} must be a positive integer, got {value!r}")

    @classmethod
    def for_orders(cls, F: int, P: int, oversample: float = 1.0) -> ReparamGrid:
        """A grid resolving orders up to (F, P): ~2F+24 nodes in θ_i', ~2P+16 in θ_o'."""
        n_i = int(np.ceil(oversample * (2 * F + 24)))
        n_o = int(np.ceil(oversample * (2 * P + 16)))
        n_phi = int(np.ceil(oversample * max(4 * P + 16, 24)))
        return cls(n_i, n_o, n_phi + (n_phi % 2))

    def theta_i(self) -> tuple[np.ndarray, np.ndarray]:
        """(cos θ_i' nodes, weights), nodes descending from near +1 (θ ascending)."""
        return _gauss_legendre_descending(self.n_theta_i)

    def theta_o(self) -> tuple[np.ndarray, np.ndarray]:
        """(cos θ_o' nodes, weights), θ ascending; all strictly inside (0, π)."""
        return _gauss_legendre_descending(self.n_theta_o)

    def phi(self) -> np.ndarray:
        """φ' nodes 2πk/n_phi."""
        return 2.0 * np.pi * np.arange(self.n_phi) / self.n_phi


@lru_cache(maxsize=64)
def _gauss_legendre_descending(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss–Legendre nodes on [−1, 1] in descending order and their weights (read-only)."""
    x, w = gauss_legendre(n)
    x, w = x[::-1].copy(), w[::-1].copy()
    x.setflags(write=False)
    w.setflags(write=False)
    return x, w


@dataclass(frozen=True, eq=False)
class ReparamBRDF:
    """ρ̂(θ_i', θ_o', φ') sampled on a :class:`ReparamGrid`.

    Attributes
    ----------
    values
        float64 (n_theta_i, n_theta_o, n_phi, 3), RGB, cosine factor included.
    grid
        The quadrature grid.
    name
        Name of the source BRDF.
    n_without_data
        Grid points where a tabulated source had no valid measurement to interpolate
        (they hold 0).
    """

    values: np.ndarray
    grid: ReparamGrid
    name: str
    n_without_data: int = 0

    def energy(self) -> np.ndarray:
        """∫∫ ρ̂² dω_i dω_o per channel, by quadrature of the samples (shape (3,))."""
        _, wi = self.grid.theta_i()
        _, wo = self.grid.theta_o()
        dphi = 2.0 * np.pi / self.grid.n_phi
        # 2π from the integral over φ_i' (ρ̂ depends on φ_o' − φ_i' only); blocks of θ_i' rows
        # keep the squares' temporary small
        rows = max(1, SAMPLE_BLOCK // max(self.values.shape[1] * self.values.shape[2], 1))
        total = np.zeros(3)
        for r0 in range(0, self.values.shape[0], rows):
            block = self.values[r0 : r0 + rows]
            total += np.einsum("i,o,iopk->k", wi[r0 : r0 + rows], wo, block * block)
        return 2.0 * np.pi * dphi * total


def reparam_directions(
    cos_theta_i: np.ndarray, cos_theta_o: np.ndarray, phi: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Local-frame (L, V) for reparameterized coordinates, broadcast over the inputs.

    The reflection frame has R = +z, V' = (θ_o', φ'), L' = (θ_i', 0); the returned
    vectors are expressed in the surface frame whose normal N = normalize(R + V') is +z
    (rotate by −φ' about z, then by −θ_o'/2 about y).
    """
    ci = np.asarray(cos_theta_i, float)
    co = np.asarray(cos_theta_o, float)
    ph = np.asarray(phi, float)
    shape = np.broadcast_shapes(ci.shape, co.shape, ph.shape)
    # each factor on its own (small) shape; only the products below are full size
    si = np.sqrt(np.clip(1.0 - ci * ci, 0.0, None))
    # half-angle of θ_o' from cos θ_o' (stable on (0, π)): cos(θ/2), sin(θ/2)
    ch = np.sqrt(np.clip((1.0 + co) / 2.0, 0.0, None))
    sh = np.sqrt(np.clip((1.0 - co) / 2.0, 0.0, None))
    cp, sp = np.cos(ph), np.sin(ph)
    # L' = (si, 0, ci); rotate by -φ' about z: (si cp, -si sp, ci)
    lx = si * cp
    # then by -θ_o'/2 about y: x' = x cos(t) - z sin(t), z' = x sin(t) + z cos(t)
    L = np.empty((*shape, 3))
    np.subtract(lx * ch, ci * sh, out=L[..., 0])
    np.multiply(-si, sp, out=L[..., 1])
    np.add(lx * sh, ci * ch, out=L[..., 2])
    # V' is at polar angle θ_o' and azimuth φ'; in the normal frame it sits at θ_o'/2, azimuth 0
    V = np.empty((*shape, 3))
    V[..., 0] = sh
    V[..., 1] = 0.0
    V[..., 2] = ch
    return L, V


def reparameterize(brdf: BRDF, grid: ReparamGrid) -> ReparamBRDF:
    """Sample ρ̂(θ_i', θ_o', φ') of ``brdf`` on ``grid`` (RH02 §3.1; DESIGN §3).

    Parameters
    ----------
    brdf
        Any BRDF that can be evaluated everywhere (models, MERL, tables). Scattered
        measurements must be fitted first.
    grid
        The quadrature grid.

    Returns
    -------
    ReparamBRDF
        Values with the cosine factor max(N·L', 0) included, zero below the horizon.
    """
    xi, _ = grid.theta_i()
    xo, _ = grid.theta_o()
    values, missing = sample_rho_hat_grid(brdf, xi, xo, grid.n_phi)
    return ReparamBRDF(values=values, grid=grid, name=brdf.name, n_without_data=missing)


#: Points per block of :func:`sample_rho_hat` (its peak memory beyond the result: a few hundred
#: bytes a point).
SAMPLE_BLOCK = 1 << 20


def sample_rho_hat(
    brdf: BRDF, cos_theta_i: np.ndarray, cos_theta_o: np.ndarray, phi: np.ndarray, *, out: np.ndarray | None = None
) -> tuple[np.ndarray, int]:
    """ρ̂ on the product of 1-D node sets: values (n_i, n_o, n_phi, 3) and the number of
    points where a tabulated source had no measurement (they hold 0).

    ``out``: an array of that shape (a view, e.g. some φ' columns of a larger grid) to write the
    values into; it is returned.

    Raises
    ------
    BadInputError
        If the BRDF evaluates to NaN or infinity anywhere on the nodes.
    """
    ci = np.asarray(cos_theta_i, float)
    co = np.asarray(cos_theta_o, float)
    ph = np.asarray(phi, float)
    values = np.empty((ci.size, co.size, ph.size, 3)) if out is None else out
    missing = 0
    # blocks of θ_i' rows: the directions and the model's temporaries stay near SAMPLE_BLOCK
    # points (a fine grid of 2·10⁷ samples would otherwise hold several GB of them at once)
    rows = max(1, SAMPLE_BLOCK // max(co.size * ph.size, 1))
    for r0 in range(0, ci.size, rows):
        L, V = reparam_directions(ci[r0 : r0 + rows, None, None], co[None, :, None], ph[None, None, :])
        values[r0 : r0 + rows], n = _rho_hat_counted(brdf, L, V)
        missing += n
    if not np.all(np.isfinite(values)):
        bad = int(np.count_nonzero(~np.isfinite(values)))
        raise BadInputError(brdf.name, f"BRDF evaluates to {bad} non-finite values on the reparameterized grid")
    return values, missing


def sample_rho_hat_half(
    brdf: BRDF, cos_theta_i: np.ndarray, cos_theta_o: np.ndarray, n_phi: int, *, out: np.ndarray | None = None
) -> tuple[np.ndarray, int]:
    """ρ̂ at the uniform φ' nodes 2πk/n_phi with φ' ∈ [0, π] only, k = 0 .. n_phi // 2:
    values (n_i, n_o, n_phi // 2 + 1, 3) and the number of points of the *whole* grid without
    data (each mirrored point counted twice), as :func:`sample_rho_hat_grid` (which mirrors them).
    ``out``: as for :func:`sample_rho_hat`.

    Raises
    ------
    BadInputError
        As :func:`sample_rho_hat`.
    """
    n_phi = int(n_phi)
    ci = np.asarray(cos_theta_i, float)
    co = np.asarray(cos_theta_o, float)
    phi = 2.0 * np.pi * np.arange(n_phi // 2 + 1) / max(n_phi, 1)
    values = np.empty((ci.size, co.size, phi.size, 3)) if out is None else out
    # the nodes that are their own mirror image (0, and π for even n_phi) count once, the others
    # twice; all as slices of ``values`` (plain copies, no index arrays)
    inner = slice(1, (n_phi + 1) // 2)
    ends = slice(0, n_phi // 2 + 1, n_phi // 2) if n_phi % 2 == 0 and n_phi > 1 else slice(0, 1)  # 0 (and π)
    missing = 0
    for nodes, count in ((ends, 1), (inner, 2)):
        if phi[nodes].size:
            missing += count * sample_rho_hat(brdf, ci, co, phi[nodes], out=values[:, :, nodes])[1]
    return values, missing


def sample_rho_hat_grid(
    brdf: BRDF, cos_theta_i: np.ndarray, cos_theta_o: np.ndarray, n_phi: int
) -> tuple[np.ndarray, int]:
    """ρ̂ on the product of 1-D node sets and the uniform φ' nodes 2πk/n_phi, as
    :func:`sample_rho_hat` (values (n_i, n_o, n_phi, 3), points without data), evaluating
    only φ' ∈ [0, π] (:func:`sample_rho_hat_half`).

    ρ̂ of an isotropic BRDF is even in φ' (DESIGN §3: the plane of R and L' is a mirror plane),
    so the nodes 2π − φ'_k repeat the values at φ'_k: about half the BRDF evaluations. Only the
    even part of a source enters the cosine transforms of RH02 Appendix C; for the tabulated
    isotropic sources we read (MERL, RGL, tables) the odd part is interpolation rounding
    (≤ 5·10⁻⁴ of the peak for the RGL files of ../shared/data). The count of points without
    data is that of the whole grid (each mirrored point counted twice).
    """
    n_phi = int(n_phi)
    if n_phi <= 2:
        ci, co = np.asarray(cos_theta_i, float), np.asarray(cos_theta_o, float)
        return sample_rho_hat(brdf, ci, co, 2.0 * np.pi * np.arange(n_phi) / max(n_phi, 1))
    values = np.empty((np.size(cos_theta_i), np.size(cos_theta_o), n_phi, 3))
    half = n_phi // 2 + 1
    _, missing = sample_rho_hat_half(brdf, cos_theta_i, cos_theta_o, n_phi, out=values[:, :, :half])
    # node n − k repeats node k for k = 1 .. ceil(n/2) − 1, i.e. nodes n − 1 down to n // 2 + 1
    values[:, :, n_phi - 1 : n_phi // 2 : -1] = values[:, :, 1 : (n_phi + 1) // 2]
    return values, missing


def _rho_hat_counted(brdf: BRDF, L: np.ndarray, V: np.ndarray) -> tuple[np.ndarray, int]:
    """ρ̂ = ρ max(N·L, 0) (or the model's own ρ̂) and the count of points without data."""
    if brdf.kind == "analytic":
        return brdf.rho_hat(L, V), 0
    rho, missing = brdf.eval_counted(L, V)
    return rho * np.maximum(L[..., 2], 0.0)[..., None], int(missing)
