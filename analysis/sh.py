"""Spherical harmonics in the conventions of DESIGN §2.

Complex, orthonormal, Condon–Shortley phase (as ``scipy.special.sph_harm_y``):
Y_lm(θ, φ) = f_lm(θ) e^{imφ}. Real basis (used for stored maps and shaders)::

    Y^r_l0 = Y_l0,
    Y^r_lm = sqrt(2) (-1)^m Re Y_l|m|   (m > 0),
    Y^r_lm = sqrt(2) (-1)^m Im Y_l|m|   (m < 0),

flattened at index l² + l + m. The normalized associated Legendre functions f_lm are
computed by the standard stable three-term recurrence on normalized functions, tested
against scipy up to l = 500 and for orthonormality by Gauss–Legendre quadrature up to
l = :data:`LEGENDRE_TESTED_LMAX` (2000); beyond that :func:`legendre_f` warns with
:class:`NumericalLimitWarning`.

Reference: [RH02] (``data_specs/bibliography.md``).
"""

from __future__ import annotations

import warnings

import numpy as np

__all__ = [
    "NumericalLimitWarning", "LEGENDRE_TESTED_LMAX", "legendre_f", "real_sph_harm", "real_index", "complex_sph_harm",
    "Lambda", "warn_beyond",
]


#: Largest degree at which the Legendre recurrence is tested (orthonormal to 1e-10 at l = 2000).
LEGENDRE_TESTED_LMAX = 2000


class NumericalLimitWarning(UserWarning):
    """A routine was asked for a degree beyond the range in which its accuracy is tested."""


def warn_beyond(what: str, value: int, tested: int) -> None:
    """Warn (:class:`NumericalLimitWarning`) when ``value`` exceeds the ``tested`` limit of ``what``."""
    if value > tested:
        warnings.warn(f"{what}: degree {value} is beyond the tested range (<= {tested}); accuracy is not verified",
                      NumericalLimitWarning, stacklevel=3)


def Lambda(l: np.ndarray | int) -> np.ndarray:
    """Λ_l = sqrt(4π / (2l + 1)) (RH02 eq. 4)."""
    return np.sqrt(4.0 * np.pi / (2.0 * np.asarray(l, dtype=np.float64) + 1.0))


def real_index(l: int, m: int) -> int:
    """Flat index l² + l + m of the real coefficient (l, m)."""
    return l * l + l + m


def legendre_f(lmax: int, mmax: int, cos_theta: np.ndarray) -> np.ndarray:
    """f_lm(θ) with Y_lm = f_lm(θ) e^{imφ}, for 0 <= m <= min(l, mmax), l <= lmax.

    Parameters
    ----------
    lmax, mmax
        Largest degree and order.
    cos_theta
        cos θ, any shape ``S``.

    Returns
    -------
    ndarray, shape ``(lmax + 1, mmax + 1) + S``; entries with m > l are zero.

    Notes
    -----
    Recurrence on orthonormal functions (Condon–Shortley phase included):
    f_00 = 1/sqrt(4π); f_mm = -sqrt((2m+1)/(2m)) sin θ f_{m-1,m-1};
    f_{m+1,m} = sqrt(2m+3) cos θ f_mm;
    f_lm = a_lm (cos θ f_{l-1,m} - f_{l-2,m} / a_{l-1,m}), a_lm = sqrt((4l²-1)/(l²-m²)).
    Stable to high degree; sin^m θ underflows only for m in the hundreds near the poles.
    """
    warn_beyond("legendre_f", int(lmax), LEGENDRE_TESTED_LMAX)
    x = np.asarray(cos_theta, dtype=np.float64)
    s = np.sqrt(np.clip(1.0 - x * x, 0.0, None))
    out = np.zeros((lmax + 1, mmax + 1) + x.shape)
    fmm = np.full(x.shape, 1.0 / np.sqrt(4.0 * np.pi))
    for m in range(min(mmax, lmax) + 1):
        if m > 0:
            fmm = -np.sqrt((2.0 * m + 1.0) / (2.0 * m)) * s * fmm
        out[m, m] = fmm
        if m + 1 <= lmax:
            out[m + 1, m] = np.sqrt(2.0 * m + 3.0) * x * fmm
    # the three-term recurrence in l, every order m <= l − 2 at once (rows l − 1 and l − 2 are
    # complete for those m: the diagonal, the first off-diagonal or an earlier step set them)
    shape = (-1,) + (1,) * x.ndim
    for l in range(2, lmax + 1):
        ms = np.arange(min(l - 2, mmax) + 1, dtype=np.float64)
        a_l = np.sqrt((4.0 * l * l - 1.0) / (l * l - ms * ms)).reshape(shape)
        a_lm1 = np.sqrt((4.0 * (l - 1) ** 2 - 1.0) / ((l - 1) ** 2 - ms * ms)).reshape(shape)
        k = ms.size
        out[l, :k] = a_l * (x * out[l - 1, :k] - out[l - 2, :k] / a_lm1)
    return out


def complex_sph_harm(lmax: int, dirs: np.ndarray) -> np.ndarray:
    """Complex Y_lm(ω) for unit vectors ``dirs`` (..., 3), all |m| <= l <= lmax.

    Returns an array (..., (lmax+1)²) at flat index l² + l + m.
    """
    dirs = np.asarray(dirs, dtype=np.float64)
    cos_t = np.clip(dirs[..., 2], -1.0, 1.0)
    phi = np.arctan2(dirs[..., 1], dirs[..., 0])
    f = legendre_f(lmax, lmax, cos_t)
    out = np.zeros(dirs.shape[:-1] + ((lmax + 1) ** 2,), dtype=np.complex128)
    for l in range(lmax + 1):
        for m in range(0, l + 1):
            y = f[l, m] * np.exp(1j * m * phi)
            out[..., real_index(l, m)] = y
            if m:
                out[..., real_index(l, -m)] = (-1) ** m * np.conj(y)
    return out


def real_sph_harm(lmax: int, dirs: np.ndarray) -> np.ndarray:
    """Real SH Y^r_lm(ω) (DESIGN §2 real basis) for unit vectors ``dirs`` (..., 3).

    Returns an array (..., (lmax+1)²) at flat index l² + l + m.
    """
    complex_y = complex_sph_harm(lmax, dirs)
    out = complex_y.real.copy()  # m = 0 entries are real already
    for l in range(1, lmax + 1):
        m = np.arange(1, l + 1)
        scale = np.sqrt(2.0) * np.where(m % 2, -1.0, 1.0)
        positive = complex_y[..., l * l + l + m]
        out[..., l * l + l + m] = scale * positive.real
        out[..., l * l + l - m] = scale * positive.imag
    return out
