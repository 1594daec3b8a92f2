"""How far an anisotropic RGL material is from isotropic (:func:`rgl_anisotropy`), and the refusal that states it.

The reader supports isotropic files only; an anisotropic file (more than one incident azimuth
φ_i) is refused with a message that states its anisotropy, the energy share of ρ cos θ_o that
changes with the incident azimuth at fixed relative geometry (data_specs/rgl_bsdf.md,
"Anisotropic files"). :mod:`.rgl` re-exports the public names.

Reference: [DJ18]; [Mitsuba3] ``src/bsdfs/measured.cpp`` (the half vector's absolute azimuth for
anisotropic files). Citation keys: ``data_specs/bibliography.md``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ._rgl_checks import _check_grid, _expect, _float_table
from ._rgl_warp import _Bilinear, _InverseWarp, _param_weights, _phi_to_u, _theta_to_u, _unit
from .errors import BadInputError

#: Outgoing directions per measured incident direction probed by :func:`rgl_anisotropy`
#: (a Fibonacci set on the upper hemisphere, in the incident direction's azimuthal frame).
ANISO_PROBES = 256


def _fibonacci_hemisphere(n: int) -> np.ndarray:
    """n nearly uniform unit directions (n, 3) with z in (0, 1)."""
    k = np.arange(n) + 0.5
    z = 1.0 - k / n
    phi = np.pi * (3.0 - np.sqrt(5.0)) * k
    r = np.sqrt(1.0 - z * z)
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=-1)


def rgl_anisotropy(
    theta_i: np.ndarray, phi_i: np.ndarray, ndf: np.ndarray, sigma: np.ndarray, vndf: np.ndarray,
    rgb: np.ndarray, *, jacobian: bool = True, probes: int = ANISO_PROBES,
) -> float:
    """How far an anisotropic RGL material is from isotropic: the energy fraction of the part of
    ρ cos θ_o that changes with the incident azimuth (data_specs/rgl_bsdf.md, "Anisotropic files").

    For every stored incident azimuth φ_k and elevation θ_t (exactly on the table's slices: no
    interpolation in φ_i) ρ cos θ_o = R · D / (4σ) is evaluated at outgoing directions
    R_z(φ_k) ω_j, the same :data:`ANISO_PROBES` directions ω_j turned with the incident one, the
    half vector's azimuth taken absolute as Mitsuba 3's ``measured`` plugin does for anisotropic
    files. An isotropic material gives the same values for every φ_k; the result is

        A = Σ_{t,j,c} Σ_k (v_ktjc − v̄_tjc)² / Σ_{t,j,c} Σ_k v_ktjc²,

    v̄ the mean over the azimuths (a last azimuth 2π after the first, the same one, is left out).

    Parameters
    ----------
    theta_i, phi_i
        The file's incident elevations (T,) and azimuths (P,), radians.
    ndf, sigma
        D and σ tables (H, W) on absolute (θ, φ) unit coordinates.
    vndf, rgb
        (P, T, H', W') and (P, T, 3, h, w): the warp and the RGB table per (φ_i, θ_i).
    jacobian
        The file's ``jacobian`` flag.
    probes
        Outgoing directions per incident direction.

    Returns
    -------
    float
        A in [0, 1): 0 for identical azimuth slices; NaN when every value is 0.
    """
    theta_i = np.asarray(theta_i, dtype=np.float64)
    phi_i = np.asarray(phi_i, dtype=np.float64)
    P, T = phi_i.size, theta_i.size
    if P > 2 and abs(phi_i[-1] - phi_i[0] - 2.0 * np.pi) < 1e-3:
        P -= 1  # the closing azimuth repeats the first
    rel = _fibonacci_hemisphere(probes)
    d_ndf = _Bilinear(np.asarray(ndf, dtype=np.float64)[None, :, :, None])
    d_sigma = _Bilinear(np.asarray(sigma, dtype=np.float64)[None, :, :, None])
    values = np.zeros((P, T, probes, 3))
    for k in range(P):
        warp = _InverseWarp(np.asarray(vndf[k], dtype=np.float64))
        table = _Bilinear(np.moveaxis(np.asarray(rgb[k], dtype=np.float64), 1, -1))
        c, s = np.cos(phi_i[k]), np.sin(phi_i[k])
        Wo = np.stack([c * rel[:, 0] - s * rel[:, 1], s * rel[:, 0] + c * rel[:, 1], rel[:, 2]], axis=-1)
        for t in range(T):
            Wi = np.broadcast_to([np.sin(theta_i[t]) * c, np.sin(theta_i[t]) * s, np.cos(theta_i[t])], Wo.shape)
            H = _unit(Wi + Wo)[0]
            u = np.stack((_theta_to_u(np.arctan2(np.hypot(H[:, 0], H[:, 1]), H[:, 2])),
                          _phi_to_u(np.arctan2(H[:, 1], H[:, 0]))), axis=-1)
            node = (np.full(probes, t, dtype=np.intp), np.full(probes, t, dtype=np.intp), np.zeros(probes))
            sx, sy = warp(u[:, 0], u[:, 1], node)
            v = table(sx, sy, node)
            if jacobian:
                none = _param_weights(np.zeros(1), u[:, 0])
                ui = (np.full(probes, _theta_to_u(theta_i[t])), np.full(probes, _phi_to_u(phi_i[k])))
                v = v * (d_ndf(u[:, 0], u[:, 1], none)[:, 0] / (4.0 * d_sigma(ui[0], ui[1], none)[:, 0]))[:, None]
            values[k, t] = v
    total = float(np.sum(values**2))
    if total <= 0:
        return float("nan")
    return float(np.sum((values - values.mean(axis=0)) ** 2) / total)


def _anisotropic_message(path: Path, fields: dict[str, np.ndarray], phi_i: np.ndarray, theta_i: np.ndarray) -> str:
    """The refusal of an anisotropic file, with its anisotropy when the tables allow computing it."""
    head = f"anisotropic material ({phi_i.size} incident azimuths φ_i)"
    tail = "; only isotropic files (one φ_i) are supported"
    P, T = phi_i.size, theta_i.size
    try:
        ndf = _float_table(path, "ndf", _expect(path, fields, "ndf", "<f4", 2), 2)
        sigma = _float_table(path, "sigma", _expect(path, fields, "sigma", "<f4", 2), 2)
        vndf = _float_table(path, "vndf", _expect(path, fields, "vndf", "<f4", 4), 4)
        rgb = _float_table(path, "rgb", _expect(path, fields, "rgb", "<f4", 5), 5)
        if vndf.shape[:2] != (P, T) or rgb.shape[:3] != (P, T, 3) or not np.all(np.isfinite(phi_i)):
            raise BadInputError(path, "table shapes do not match phi_i x theta_i")
        for key, table in (("ndf", ndf), ("sigma", sigma), ("vndf", vndf), ("rgb", rgb)):
            _check_grid(path, key, table.shape)
        if np.any(sigma <= 0) or np.any(vndf < 0):
            raise BadInputError(path, "non-positive sigma or negative vndf")
        jac = bool(_expect(path, fields, "jacobian", "u1", 1)[0])
        share = rgl_anisotropy(theta_i, phi_i, ndf, sigma, vndf, np.maximum(rgb, 0.0), jacobian=jac)
    except BadInputError as err:
        return f"{head} (anisotropy not measured: {err.problem}){tail}"
    return (f"{head}: anisotropy {share:.3g} (the share of the energy of ρ cos θ_o that changes with the incident "
            f"azimuth at fixed relative geometry){tail}")
