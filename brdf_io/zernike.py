"""Koenderink's reciprocal isotropic Zernike-basis BRDF representation [Koe96] (the model; its fit
is ``analysis/fit/zernike.py``).

A BRDF is expanded over the product of the incident and the exit hemisphere, each mapped onto the
unit disc (:func:`disc_radius`), in products of Zernike polynomials (:func:`zernike`, [BornWolf99])
combined into the reciprocal isotropic basis (:func:`zernike_basis`, :func:`basis_terms`);
:class:`ZernikeBRDF` is ρ = Σ_a c_a B_a, written as a spec string by :meth:`ZernikeBRDF.to_spec`.
CURET published its BRDF fits in this basis ([CURET99], 5 and 55 coefficients: orders 2 and 8,
:func:`basis_count`) and [RH02] Fig. 8 analysed those fits.
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np

from .brdf import BRDF, Kind, as_directions
from .errors import BadInputError
from .names import ZERNIKE_MAX_ORDER as MAX_ORDER  # numpy-free home, for the CLI's parsers

__all__ = [
    "TERMS_PER_ORDER",
    "disc_radius",
    "zernike_radial",
    "zernike",
    "basis_terms",
    "basis_count",
    "order_for_count",
    "zernike_basis",
    "ZernikeBRDF",
    "MAX_ORDER",
    "MAX_ZERNIKE_COEFF",
    "check_order",
]

#: Direction pairs evaluated at once by :meth:`ZernikeBRDF.eval` (bounds its temporary memory).
EVAL_BLOCK = 32768
#: Largest |coefficient| a spec string may give, 1/sr (keeps every evaluation finite).
MAX_ZERNIKE_COEFF = 1e9


def basis_count(n_max: int) -> int:
    """Number of reciprocal isotropic basis functions of order ``n_max``.

    With k_m = ⌊(n_max − m)/2⌋ + 1 radial degrees for each m, the count is
    Σ_{m=0}^{n_max} k_m(k_m + 1)/2:

    =======  ===  ===  ===  ===  ===  ===  ===  ===  ===  ===  ===
    n_max     0    1    2    3    4    5    6    7    8    9   10
    terms     1    2    5    8   14   20   30   40   55   70   91
    =======  ===  ===  ===  ===  ===  ===  ===  ===  ===  ===  ===

    so CURET's 5- and 55-coefficient fits [CURET99] are ``n_max`` = 2 and 8
    (:data:`TERMS_PER_ORDER`, :func:`order_for_count`).

    Parameters
    ----------
    n_max
        Largest Zernike degree n of either factor, 0 <= n_max <= 20.

    Returns
    -------
    int
        Σ_{m=0}^{n_max} k_m (k_m + 1) / 2 with k_m = ⌊(n_max − m)/2⌋ + 1 (5 for 2, 55 for 8).

    Raises
    ------
    BadInputError
        ``n_max`` not an integer in [0, 20].
    """
    n_max = check_order(n_max)
    k = (n_max - np.arange(n_max + 1)) // 2 + 1
    return int(np.sum(k * (k + 1) // 2))


def check_order(n_max: object) -> int:
    """``n_max`` as an int in [0, :data:`MAX_ORDER`]; BadInputError (echoing the value) otherwise."""
    if isinstance(n_max, bool) or not isinstance(n_max, int | np.integer) or not 0 <= int(n_max) <= MAX_ORDER:
        raise BadInputError(None, f"Zernike order n_max must be an integer in [0, {MAX_ORDER}], got {n_max!r}")
    return int(n_max)


#: ``{n_max: number of basis functions}`` for n_max = 0..20 (1, 2, 5, 8, 14, 20, 30, 40, 55, ...).
TERMS_PER_ORDER: dict[int, int] = {n: basis_count(n) for n in range(MAX_ORDER + 1)}


def order_for_count(n_coeffs: int) -> int:
    """The order ``n_max`` whose basis has exactly ``n_coeffs`` functions (5 → 2, 55 → 8).

    Raises
    ------
    BadInputError
        No order has that many terms (the message lists the counts that exist).
    """
    for n_max, count in TERMS_PER_ORDER.items():
        if count == n_coeffs:
            return n_max
    listed = ", ".join(str(c) for c in TERMS_PER_ORDER.values())
    raise BadInputError(None, f"no Zernike order has {n_coeffs!r} coefficients; available counts: {listed}")


def basis_terms(n_max: int) -> tuple[tuple[int, int, int], ...]:
    """The (m, n, n') of each basis function of order ``n_max``, in coefficient order.

    Ordered by max(n, n'), then m, then n: the terms of a lower order come first, so the basis of
    order N is the first ``basis_count(N)`` terms of any higher order.

    Returns
    -------
    tuple of (m, n, n')
        ``basis_count(n_max)`` triples with 0 <= m <= n <= n' <= n_max, n ≡ n' ≡ m (mod 2).
    """
    n_max = check_order(n_max)
    terms = []
    for top in range(n_max + 1):
        for m in range(top % 2, top + 1, 2):
            for n in range(m, top + 1, 2):
                terms.append((m, n, top))
    return tuple(terms)


def disc_radius(cos_theta: np.ndarray) -> np.ndarray:
    """Koenderink's hemisphere-to-disc radius ρ = √2 sin(θ/2) = √(1 − cos θ) (area-preserving).

    Each direction (θ, φ) of the upper hemisphere goes to the point (ρ, φ) of the unit disc by the
    Lambert azimuthal equal-area map [Koe96] uses: ρ dρ dφ = ½ sin θ dθ dφ, so the hemisphere
    (solid angle 2π) covers the disc (area π) evenly, the horizon θ = 90° is the rim ρ = 1, and
    orthogonality on the disc is orthogonality on the hemisphere.

    Parameters
    ----------
    cos_theta
        cos θ of directions, any shape; values above 1 are treated as 1.

    Returns
    -------
    numpy.ndarray
        ρ, same shape: 0 at the normal, 1 at the horizon (√2 at the south pole).
    """
    return np.sqrt(np.clip(1.0 - np.asarray(cos_theta, dtype=np.float64), 0.0, None))


def _check_nm(n: int, m: int) -> None:
    if n < 0 or abs(m) > n or (n - abs(m)) % 2:
        raise ValueError(f"Zernike indices need 0 <= |m| <= n and n - |m| even, got n={n}, m={m}")


def zernike_radial(n: int, m: int, rho: np.ndarray) -> np.ndarray:
    """The Zernike radial polynomial R_n^|m|(ρ) ([BornWolf99] App. VII; R_n^m(1) = 1):

        R_n^m(ρ) = Σ_{k=0}^{(n−m)/2} (−1)^k (n−k)! / (k! ((n+m)/2 − k)! ((n−m)/2 − k)!) ρ^{n−2k}
                 = (−1)^{(n−m)/2} ρ^m P_{(n−m)/2}^{(m,0)}(1 − 2ρ²)        (Jacobi form, used here).

    Parameters
    ----------
    n, m
        Degree and azimuthal order, |m| <= n, n − |m| even.
    rho
        Radii, any shape (the polynomial is evaluated for any real ρ).

    Raises
    ------
    ValueError
        Invalid (n, m).
    """
    from scipy.special import eval_jacobi  # imported on use: load_brdf's registry must not pull scipy into start-up

    _check_nm(n, m)
    m = abs(m)
    k = (n - m) // 2
    rho = np.asarray(rho, dtype=np.float64)
    return (-1.0) ** k * rho**m * eval_jacobi(k, m, 0, 1.0 - 2.0 * rho * rho)


def _norm(n: int, m: int) -> float:
    return float(np.sqrt((2.0 if m != 0 else 1.0) * (n + 1) / np.pi))


def zernike(n: int, m: int, rho: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """Zernike polynomial Z_n^m(ρ, φ), orthonormal on the unit disc (measure ρ dρ dφ):
    ∫₀¹∫₀^{2π} Z_n^m Z_n'^m' ρ dρ dφ = δ_nn' δ_mm', for 0 <= |m| <= n, n − |m| even.

    Parameters
    ----------
    n, m
        Degree and signed azimuthal order: cos(mφ) for m >= 0, sin(|m|φ) for m < 0.
    rho, phi
        Polar coordinates (broadcast together); φ in radians.

    Returns
    -------
    numpy.ndarray
        N_n^m R_n^|m|(ρ) cos(mφ) or sin(|m|φ), N_n^m = √((2 − δ_m0)(n + 1)/π).

    Raises
    ------
    ValueError
        Invalid (n, m).
    """
    radial = _norm(n, m) * zernike_radial(n, m, rho)
    phi = np.asarray(phi, dtype=np.float64)
    return radial * (np.cos(m * phi) if m >= 0 else np.sin(-m * phi))


def _term_scale(m: int, n: int, n2: int) -> float:
    """N_n^m N_n'^m c / (1 + δ_nn') of :func:`zernike_basis`."""
    c = 1.0 / np.sqrt(4.0 * (2.0 if m > 0 else 1.0) * (2.0 if n != n2 else 1.0))
    return _norm(n, m) * _norm(n2, m) * c / (2.0 if n == n2 else 1.0)


def _geometry(L: np.ndarray, V: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(ρ_i, ρ_o, φ_i − φ_o, above) for flattened (N, 3) unit directions."""
    above = (L[:, 2] > 0) & (V[:, 2] > 0)
    rho_i = disc_radius(L[:, 2])
    rho_o = disc_radius(V[:, 2])
    dphi = np.arctan2(L[:, 1], L[:, 0]) - np.arctan2(V[:, 1], V[:, 0])
    return rho_i, rho_o, dphi, above


def _radial_table(n_max: int, rho: np.ndarray) -> dict[tuple[int, int], np.ndarray]:
    """R_n^m(ρ) for every 0 <= m <= n <= n_max, n − m even, by the three-term recurrence

        R_n^n = ρⁿ,   R_n^m = ρ (R_{n−1}^{|m−1|} + R_{n−1}^{m+1}) − R_{n−2}^m   (R_{n−2}^m = 0 for m > n − 2)

    (Shakibaei & Paramesran 2013, Opt. Lett. 38(14), 2487, doi:10.1364/OL.38.002487: stable on
    [0, 1]; equal to :func:`zernike_radial` to 1e-13 there for n <= :data:`MAX_ORDER`,
    tests/brdf_io/test_zernike_model.py). Multiplications only: the whole table costs about what
    a few of :func:`zernike_radial`'s Jacobi evaluations cost (it was most of ``eval``'s time).
    Directions below the surface (ρ up to √2) are zeroed by every caller."""
    out: dict[tuple[int, int], np.ndarray] = {(0, 0): np.ones_like(rho)}
    for n in range(1, n_max + 1):
        for m in range(n % 2, n + 1, 2):
            if m == n:
                out[(n, m)] = rho * out[(n - 1, m - 1)]
                continue
            value = rho * (out[(n - 1, abs(m - 1))] + out[(n - 1, m + 1)])
            if m <= n - 2:
                value -= out[(n - 2, m)]
            out[(n, m)] = value
    return out


def _term_values(
    n_max: int, rho_i: np.ndarray, rho_o: np.ndarray, dphi: np.ndarray
) -> list[tuple[float, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]]:
    """Per term: (scale, R_n(ρ_i), R_n'(ρ_o), R_n'(ρ_i), R_n(ρ_o), cos mΔφ) — no product formed."""
    ri, ro = _radial_table(n_max, rho_i), _radial_table(n_max, rho_o)
    cos_m = [np.cos(m * dphi) for m in range(n_max + 1)]
    return [
        (_term_scale(m, n, n2), ri[(n, m)], ro[(n2, m)], ri[(n2, m)], ro[(n, m)], cos_m[m])
        for m, n, n2 in basis_terms(n_max)
    ]


def zernike_basis(L: np.ndarray, V: np.ndarray, n_max: int) -> np.ndarray:
    """The basis functions B_a(L, V) of order ``n_max`` at direction pairs.

    A BRDF that depends on the azimuths only through φ_i − φ_o (isotropy) and is even in it
    (bilateral symmetry, which every isotropic BRDF of this toolkit has: [RH02] eq. 13 uses
    cos(qφ') only) has, in the products Z_n^m(ρ_i, φ_i) Z_n'^m'(ρ_o, φ_o), only the combinations
    m' = m with Z_n^m Z_n'^m + Z_n^{−m} Z_n'^{−m} ∝ R_n^m(ρ_i) R_n'^m(ρ_o) cos(m(φ_i − φ_o)).
    Reciprocity, ρ(L, V) = ρ(V, L), pairs (n, n') with (n', n). The basis functions are, for
    m >= 0 and m <= n <= n' <= n_max with n ≡ n' ≡ m (mod 2),

        B_{m,n,n'}(L, V) = c N_n^m N_n'^m [R_n^m(ρ_i) R_n'^m(ρ_o) + R_n'^m(ρ_i) R_n^m(ρ_o)] / (1 + δ_nn')
                           · cos(m(φ_i − φ_o)),

    with ρ_i, ρ_o from :func:`disc_radius`, N_n^m of :func:`zernike`, and c chosen so that they are
    orthonormal over the product of hemispheres: ∫∫ B_a B_b dω_i dω_o = δ_ab
    (c = 1 / √(4 (1 + [m > 0]) (1 + [n ≠ n']))). Reciprocity and isotropy hold exactly, term by
    term, whatever the coefficients. The sin(m(φ_i − φ_o)) combinations (odd in φ_i − φ_o, allowed
    by isotropy alone and made reciprocal by antisymmetry in (n, n')) are left out; with them
    order 8 would have 73 terms instead of CURET's 55.

    Parameters
    ----------
    L, V
        Unit directions (..., 3) in the local frame (normal +z), both away from the surface;
        broadcast together.
    n_max
        Order (``basis_count(n_max)`` functions).

    Returns
    -------
    numpy.ndarray
        float64 (..., basis_count(n_max)), in 1/sr per unit coefficient; 0 where either
        direction is at or below the surface. Orthonormal over the product of hemispheres.

    Raises
    ------
    BadInputError
        ``n_max`` out of range.
    ValueError
        Directions without a last axis of 3.
    """
    n_max = check_order(n_max)
    L, V = as_directions(L, V)
    shape = L.shape[:-1]
    rho_i, rho_o, dphi, above = _geometry(L.reshape(-1, 3), V.reshape(-1, 3))
    out = np.empty((rho_i.size, basis_count(n_max)))
    for a, (s, a_i, a_o, b_i, b_o, cm) in enumerate(_term_values(n_max, rho_i, rho_o, dphi)):
        out[:, a] = s * (a_i * a_o + b_i * b_o) * cm
    out[~above] = 0.0
    return out.reshape(*shape, -1)


class ZernikeBRDF(BRDF):
    """A BRDF given by Koenderink's reciprocal isotropic Zernike expansion, ρ = Σ_a c_a B_a
    (:func:`zernike_basis`).

    Parameters
    ----------
    coefficients
        (basis_count(n_max), 3) RGB coefficients c_a in 1/sr (a scalar column (K,) or (K, 1)
        is repeated to three channels), in the order of :func:`basis_terms`.
    n_max
        Order of the expansion; inferred from the number of coefficients when omitted.
    name
        Name shown in reports.

    Raises
    ------
    BadInputError
        A coefficient count that is no order's (or not ``n_max``'s), or non-finite values.

    Notes
    -----
    ``eval`` is exactly reciprocal (ρ(L, V) = ρ(V, L)) and isotropic (invariant under a common
    rotation about the normal) for any coefficients, zero below the surface, and may be
    negative where a fit extrapolates. ``kind`` is ``"analytic"``: it evaluates everywhere,
    so every analysis (orders, SHRM prefiltering, rendering) accepts it.
    """

    kind: Kind = "analytic"

    def __init__(self, coefficients: np.ndarray, n_max: int | None = None, *, name: str = "zernike") -> None:
        c = np.asarray(coefficients, dtype=np.float64)
        if c.ndim == 1:
            c = c[:, None]
        if c.ndim != 2 or c.shape[1] not in (1, 3):
            raise BadInputError(name, f"Zernike coefficients must have shape (K,), (K, 1) or (K, 3), got {c.shape}")
        if c.shape[1] == 1:
            c = np.repeat(c, 3, axis=1)
        if n_max is None:
            n_max = order_for_count(c.shape[0])
        n_max = check_order(n_max)
        if c.shape[0] != basis_count(n_max):
            raise BadInputError(
                name, f"order {n_max} has {basis_count(n_max)} Zernike terms, got {c.shape[0]} coefficients"
            )
        if not np.all(np.isfinite(c)):
            raise BadInputError(name, "Zernike coefficients must be finite")
        c.setflags(write=False)
        self.coefficients = c
        self.n_max = n_max
        self.name = name

    @property
    def terms(self) -> tuple[tuple[int, int, int], ...]:
        """(m, n, n') of each coefficient (:func:`basis_terms`)."""
        return basis_terms(self.n_max)

    @functools.cached_property
    def _pair_matrices(self) -> list[np.ndarray]:
        """Per azimuthal order m, the symmetric (k_m, k_m, 3) matrix M_m with
        ρ = Σ_m cos(mΔφ) Σ_jk R_{n_j}^m(ρ_i) M_m[j, k] R_{n_k}^m(ρ_o), n_j = m + 2j: each term
        c_a s_a [R_n(ρ_i) R_n'(ρ_o) + R_n'(ρ_i) R_n(ρ_o)] puts c_a s_a at (n, n') and (n', n)."""
        out = [np.zeros(((self.n_max - m) // 2 + 1,) * 2 + (3,)) for m in range(self.n_max + 1)]
        for c, (m, n, n2) in zip(self.coefficients, self.terms, strict=True):
            j, k = (n - m) // 2, (n2 - m) // 2
            out[m][j, k] += _term_scale(m, n, n2) * c
            out[m][k, j] += _term_scale(m, n, n2) * c
        return out

    def eval(self, L: np.ndarray, V: np.ndarray) -> np.ndarray:
        """RGB ρ(L, V) in 1/sr, shape (..., 3); 0 where either direction is below the surface."""
        L, V = as_directions(L, V)
        shape = L.shape[:-1]
        L, V = L.reshape(-1, 3), V.reshape(-1, 3)
        out = np.zeros((L.shape[0], 3))
        for start in range(0, L.shape[0], EVAL_BLOCK):  # bounded memory for big quadrature grids
            block = slice(start, start + EVAL_BLOCK)
            rho_i, rho_o, dphi, above = _geometry(L[block], V[block])
            ri, ro = _radial_table(self.n_max, rho_i), _radial_table(self.n_max, rho_o)
            acc = np.zeros((rho_i.size, 3))
            for m, M in enumerate(self._pair_matrices):
                ns = range(m, self.n_max + 1, 2)
                Ri = np.stack([ri[(n, m)] for n in ns], axis=1)  # (N, k_m)
                Ro = np.stack([ro[(n, m)] for n in ns], axis=1)
                # Σ_jk R_j(ρ_i) M[j, k, c] R_k(ρ_o); einsum, not BLAS: each row's value does not depend
                # on the block it is evaluated in (a threaded GEMM's kernels do), and k_m <= 11
                inner = np.einsum("nj,jkc->nkc", Ri, M)
                acc += np.einsum("nkc,nk->nc", inner, Ro) * np.cos(m * dphi)[:, None]
            acc[~above] = 0.0
            out[block] = acc
        return out.reshape(*shape, 3)

    def negative_fraction(self, n: int = 4096, *, seed: int = 0) -> float:
        """Fraction of uniformly random direction pairs (both hemispheres) where some channel of
        ρ is negative — a diagnostic of extrapolation; deterministic given ``seed``."""
        rng = np.random.default_rng(seed)
        z = rng.uniform(0.0, 1.0, (2, n))
        phi = rng.uniform(0.0, 2.0 * np.pi, (2, n))
        s = np.sqrt(1.0 - z * z)
        d = np.stack([s * np.cos(phi), s * np.sin(phi), z], axis=-1)
        return float(np.mean(np.any(self.eval(d[0], d[1]) < 0, axis=-1)))

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready description: order, terms (m, n, n') and RGB coefficients."""
        return {
            "model": "zernike",
            "n_max": self.n_max,
            "terms": [list(t) for t in self.terms],
            "coefficients": self.coefficients.tolist(),
        }

    def to_spec(self) -> str:
        """``zernike:n_max=N,c0=r/g/b,c1=r/g/b,...`` at full precision: exactly ``basis_count(N)``
    coefficients ``c<a>`` (1/sr, each a number or r/g/b triple, |c| <= :data:`MAX_ZERNIKE_COEFF`) in
    the order of :func:`basis_terms` (``data_specs/spec_strings.md``), so a fit document's
    ``model_spec`` loads back with ``load_brdf``."""
        items = [f"n_max={self.n_max}"]
        for a, c in enumerate(self.coefficients):
            items.append(f"c{a}=" + ("/".join(f"{v:.17g}" for v in c) if np.ptp(c) > 0 else f"{c[0]:.17g}"))
        return "zernike:" + ",".join(items)
