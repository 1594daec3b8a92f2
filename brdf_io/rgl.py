"""RGL measured materials (``.bsdf``): the reader :func:`read_rgl` and the BRDF :class:`RGLBRDF` ([DJ18]).

The EPFL RGL material database (rgl.epfl.ch/materials) stores each material in the
adaptive parameterization of [DJ18]: for every measured incident direction ω_i the outgoing
directions are not tabulated on an angle grid but on a *warped* unit square, the preimage of the
half-vector under the sampling map of the material's visible-normal distribution (VNDF).
:func:`read_rgl` reads a file (:func:`read_tensor_file`, the container, in ``_tensor_file.py``)
into an :class:`RGLBRDF`, whose ``eval`` (the interpolants and the inverse warp in
``_rgl_warp.py``) reproduces Mitsuba 3's ``measured`` plugin to float32 precision, with the
table's incident direction ω_i played by the view by default, as Mitsuba renders it
(``table_direction``; the formula, the choice and its sources: :class:`RGLBRDF` and
``data_specs/rgl_bsdf.md``).

References: [DJ18]; [Mitsuba3]: ``src/bsdfs/measured.cpp`` (the ``measured`` BSDF: ω_i =
``si.wi``), ``include/mitsuba/render/interaction.h`` (``si.wi = to_local(-ray.d)``: toward the
camera), ``src/integrators/path.cpp`` (``bsdf->eval_pdf(ctx, si, wo = to_local(ds.d))``: wo toward
the light), ``include/mitsuba/core/distr_2d.h`` (``Marginal2D``, continuous variant) and
``src/core/tensor.cpp`` (the ``tensor_file`` container). Citation keys: ``data_specs/bibliography.md``.
"""

from __future__ import annotations

import os
import warnings
from pathlib import Path
from typing import Literal, NamedTuple

import numpy as np

from ._rgl_anisotropy import ANISO_PROBES, _anisotropic_message, rgl_anisotropy
from ._rgl_checks import _checked_tables, _expect
from ._rgl_warp import _Bilinear, _InverseWarp, _normalized, _param_weights, _phi_to_u, _theta_to_u
from ._tensor_file import (  # noqa: F401  (re-exported: the container's names stay importable from here)
    RGL_PEAK_PER_BYTE,
    TENSOR_DTYPES,
    TENSOR_MAGIC,
    TENSOR_VERSION,
    read_tensor_file,
    write_tensor_file,
)
from .brdf import BRDF, Kind, as_directions
from .errors import BadInputError

__all__ = [
    "DEFAULT_TABLE_DIRECTION",
    "GRAZING_COS",
    "RGLBRDF",
    "RGL_INCIDENT",
    "RGLGamutWarning",
    "TENSOR_DTYPES",
    "read_rgl",
    "read_tensor_file",
    "rgl_anisotropy",
    "ANISO_PROBES",
    "write_tensor_file",
]

_REQUIRED = ("description", "theta_i", "phi_i", "ndf", "sigma", "vndf", "rgb", "jacobian")
#: Query points per evaluation block: each temporary of a block (a few dozen arrays of 32 KiB and
#: the gathered per-patch rows, ≤ 400 KiB) stays below the allocator's thresholds, so that freeing a
#: block's memory and taking it again does not fault its pages in again (at 65536 points a block,
#: page faults cost as much CPU as the arithmetic on this machine: benchmarks/rgl_eval_speed.py).
_BLOCK = 1 << 12

#: Floor on cos θ of the non-table direction in ρ = R·D/(4σ cos θ): the stored R does
#: not fall to 0 at the horizon (data_specs/rgl_bsdf.md, "Grazing angles"), so ρ grows
#: like 1/cos θ there; the floor keeps it finite (it acts only within 0.00006° of the
#: horizon).
GRAZING_COS = 1e-6


#: Which argument of ``RGLBRDF.eval(L, V)`` plays the file's incident direction ω_i by default:
#: ``"view"``, as Mitsuba 3 renders the format (data_specs/rgl_bsdf.md, "Which direction is incident").
DEFAULT_TABLE_DIRECTION: Literal["light", "view"] = "view"
#: The command line's and spec strings' names (``--rgl-incident``, ``file.bsdf#light``) -> ``table_direction``.
RGL_INCIDENT: dict[str, Literal["light", "view"]] = {"camera": "view", "light": "light"}
_INCIDENT_NAME = {direction: name for name, direction in RGL_INCIDENT.items()}


#: A negative RGB value larger than this fraction of the table's largest value is corruption, not an
#: out-of-gamut colour (the RGL files of ../shared/data: at most 0.023).
CORRUPT_NEGATIVE = 0.5
#: Largest RGB value a measured file may hold: the spectral reflectance factor R of the format is at
#: most a few units for real materials (the RGL files of ../shared/data: at most 4.7, paper_white); a value of
#: 10⁶ or more is corruption (a flipped exponent), and it would overflow the sums of the analysis.
MAX_MEASURED_RGB = 1e6


class RGLGamutWarning(UserWarning):
    """An RGL RGB table holds negative (out-of-gamut) values; they were clamped to 0."""


# --------------------------------------------------------------------------------------
# the BRDF
# --------------------------------------------------------------------------------------


def _checked_rgb(where: object, rgb: np.ndarray, clip_negative: bool) -> tuple[np.ndarray, int]:
    """The RGB table and its count of negative values, after the corruption checks (values over
    :data:`MAX_MEASURED_RGB`, negatives beyond :data:`CORRUPT_NEGATIVE` of the largest value);
    negatives clamped to 0 with a :class:`RGLGamutWarning` when ``clip_negative`` (called by
    ``RGLBRDF.__init__``: the warning names the caller of the constructor's caller)."""
    n_negative = int(np.sum(rgb < 0))
    peak = float(rgb.max())
    huge = rgb > MAX_MEASURED_RGB
    if np.any(huge):
        raise BadInputError(
            where, f"field 'rgb' holds {int(huge.sum())} value(s) above {MAX_MEASURED_RGB:g} (largest {peak:.4g}): "
            "no measured reflectance is that large; the file is corrupt"
        )
    if n_negative and (peak <= 0.0 or -float(rgb.min()) > CORRUPT_NEGATIVE * peak):
        # an out-of-gamut channel is a small fraction of the colour beside it (≤ 0.023 of the
        # table's largest value in every RGL file of ../shared/data); −2.5e38 is corruption
        raise BadInputError(
            where, f"field 'rgb' holds {float(rgb.min()):.4g} beside a largest value of {peak:.4g}: not an "
            f"out-of-gamut colour (|min| > {CORRUPT_NEGATIVE:g} x max); the file is corrupt"
        )
    if n_negative and clip_negative:
        warnings.warn(
            f"{where}: {n_negative} of {rgb.size} RGB values are negative (out of gamut, min "
            f"{rgb.min():.4g}); clamped to 0",
            RGLGamutWarning,
            stacklevel=4,
        )
        rgb = np.maximum(rgb, 0.0)
    return rgb, n_negative


class RGLBRDF(BRDF):
    """An isotropic RGL measured material ([DJ18]), RGB.

    The container and the evaluation are specified in
    ``data_specs/rgl_bsdf.md``; in short, for light L and view V (unit vectors, normal +z,
    both pointing away from the surface) with half vector H = normalize(L + V)::

        u   = (sqrt(θ_h / (π/2)), frac((φ_h − φ_L + π) / 2π))     half vector in unit coordinates
        s   = W⁻¹_{θ_L}(u)                                        inverse VNDF warp (``vndf`` field)
        R   = rgb_{θ_L}(s)                                        bilinear in s, linear in θ_L
        ρ(L, V) = R · D(u) / (4 σ(L) cos θ_V)                     D = ``ndf``, σ = ``sigma``

    (without the factor D/(4σ) when the file's ``jacobian`` flag is 0), written here with
    the table direction ω_i = L. The stored R is the Monte Carlo weight
    f_r cos θ_o / p(ω_o | ω_i) of VNDF sampling, whose density is p = D(ω_h) / (4 σ(ω_i)), so
    dividing by cos θ_o gives ρ without the cosine. R · D/(4σ) is what Mitsuba 3's
    ``measured`` plugin (and the authors' reference code ``powitacq``) returns as
    ``eval(si.wi, wo)`` = ρ · cos θ_o; this module reproduces it to float32 precision.

    **Which direction is ω_i.** Mitsuba's integrators call ``eval`` with ``si.wi`` pointing
    toward the camera (the previous path vertex) and ``wo`` toward the light, so Mitsuba
    renders the data with ω_i = V. The default ``table_direction="view"`` does the same
    (``eval(L, V)`` = the formula above at ω_i = V, ω_o = L), so renders agree with Mitsuba's;
    ``table_direction="light"`` (ω_i = L, the direction the gonio-photometer lit the sample
    from) is the explicit alternative. The data are not reciprocal (8–19 % for the vinyls),
    so the two differ; the choice and its sources are in data_specs/rgl_bsdf.md. R does not
    vanish at the horizon, so ρ grows like 1/cos θ_o at grazing ω_o (floored at
    :data:`GRAZING_COS`); θ_i outside the measured range uses the nearest measured slice.

    ``eval(L, V)`` implements data_specs/rgl_bsdf.md, "Evaluation": the half vector is
    mapped through the inverse VNDF warp of the incident elevation θ_L, the RGB table is
    interpolated there, and ρ = R · D / (4 σ(L) cos θ_V). Tables are interpolated as
    Mitsuba 3's ``measured`` plugin does: bilinearly on their unit squares, linearly in
    θ_i between measured incident angles and *clamped* (constant) outside the measured
    θ_i range; the result is 0 unless L_z > 0 and V_z > 0.

    Parameters
    ----------
    theta_i
        Measured incident elevations (T,), radians, strictly increasing in [0, π/2].
    ndf, sigma
        D(ω_m) on (θ_m, φ_m) unit coordinates, shape (H, W) (rows φ, columns θ), 1/sr;
        σ(ω_i), projected area, same layout, > 0.
    vndf
        Visible-normal density per incident elevation, (T, H, W), ≥ 0 (the warp).
    rgb
        R per incident elevation on the warped unit square, (T, 3, h, w).
    jacobian
        The file's ``jacobian`` flag: multiply R by D/(4σ) (true in RGL files).
    clip_negative
        Clamp negative (out-of-gamut) RGB values to 0 with a :class:`RGLGamutWarning`
        (the count stays in ``n_negative``); if false they are kept.
    table_direction
        Which argument of ``eval`` plays the file's incident direction ω_i: ``"view"``
        (default, :data:`DEFAULT_TABLE_DIRECTION`; ρ(L, V) = R(θ_V, …) D / (4 σ(V) cos θ_L):
        ρ cos θ_L is exactly what Mitsuba 3 renders, ``eval(si.wi = V, wo = L)`` with
        ``si.wi`` toward the camera, bounded at grazing L) or ``"light"`` (ω_i = L, the
        direction the sample was lit from: ρ(L, V) = R(θ_L, …) D / (4 σ(L) cos θ_V), the
        view-mode value at (V, L)).

    Attributes
    ----------
    n_negative
        Number of negative values in the stored RGB table (before any clamping).
    description, name, source
        The file's description text, the file stem (``read_rgl`` appends ``#light`` for
        ``table_direction="light"``, the spec string that loads it) and path (or a given
        name, ``None``).
    theta_i, ndf, sigma, vndf, rgb, luminance, jacobian
        The tables as float64 (``rgb`` after clamping); ``luminance`` (the sampling
        density of Mitsuba's ``sample``) is kept when given, not used by ``eval``.
    valid
        The file's raw ``valid`` bytes (or ``None``), not used by ``eval``: a bit-packed
        mask whose polarity differs between the database's files
        (data_specs/rgl_bsdf.md, "Fields").
    table_direction
        ``"light"`` or ``"view"``, as given.
    """

    kind: Kind = "tabulated"

    def __init__(
        self,
        theta_i: np.ndarray,
        ndf: np.ndarray,
        sigma: np.ndarray,
        vndf: np.ndarray,
        rgb: np.ndarray,
        *,
        jacobian: bool = True,
        clip_negative: bool = True,
        description: str = "",
        luminance: np.ndarray | None = None,
        valid: np.ndarray | None = None,
        table_direction: Literal["light", "view"] = DEFAULT_TABLE_DIRECTION,
        name: str = "rgl",
        source: str | None = None,
    ) -> None:
        where = source or name
        if table_direction not in ("light", "view"):
            raise BadInputError(where, f"table_direction must be 'light' or 'view', got {table_direction!r}")
        theta_i, ndf, sigma, vndf, rgb = _checked_tables(where, theta_i, ndf, sigma, vndf, rgb)
        warp = _InverseWarp(vndf)
        if np.any(warp.totals <= 0):
            k = int(np.argmax(warp.totals <= 0))
            raise BadInputError(where, f"field 'vndf' slice {k} (θ_i = {theta_i[k]!r}) is zero everywhere")
        rgb, self.n_negative = _checked_rgb(where, rgb, clip_negative)
        self.theta_i, self.ndf, self.sigma, self.vndf, self.rgb = theta_i, ndf, sigma, vndf, rgb
        self.jacobian = bool(jacobian)
        self.table_direction = table_direction
        self.description = description
        self.luminance = None if luminance is None else np.asarray(luminance, dtype=np.float64)
        self.valid = None if valid is None else np.asarray(valid)
        self.name = name
        self.source = source
        self._warp = warp
        self._rgb = _Bilinear(np.moveaxis(rgb, 1, -1))
        self._ndf = _Bilinear(ndf[None, :, :, None])
        self._sigma = _Bilinear(sigma[None, :, :, None])

    def warped_coordinates(self, W_i: np.ndarray, W_o: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Where direction pairs (N, 3), both above the surface, fall on the warped unit
        square, with ``W_i`` the table direction (L when ``table_direction="light"``):
        the half vector's unit coordinates u (N, 2) and the inverse-warped sample
        s = W⁻¹_{θ_i}(u) (N, 2), each as (x = θ part, y = φ part)."""
        W_i, W_o = (w.reshape(-1, 3) for w in np.broadcast_arrays(np.asarray(W_i, dtype=np.float64),
                                                                 np.asarray(W_o, dtype=np.float64)))
        c = self._coordinates(_columns(W_i), _columns(W_o))
        return np.stack(c.u, axis=-1), np.stack(c.s, axis=-1)

    def _coordinates(self, wi: _Vectors, wo: _Vectors) -> _Coordinates:
        """The block's coordinates (:class:`_Coordinates`) for the table direction wi and the
        other direction wo, as components (x, y, z) (each (N,)), not necessarily unit, both above
        the surface."""
        xi, yi, zi, phi_i, param, four_sigma = self._incident(wi)
        xo, yo, zo = _normalized(*wo)
        xo += xi  # the half vector, unnormalized: Wi + Wo (H_z > 0: never zero)
        yo += yi
        zo_unit, zo = zo, zo + zi
        hx, hy, hz = _normalized(xo, yo, zo)
        theta_h = np.arctan2(np.hypot(hx, hy), hz, out=hz)
        phi_h = np.arctan2(hy, hx, out=hx)
        # isotropic: the half vector's azimuth is taken relative to the incident one
        u = (_theta_to_u(theta_h, out=theta_h), _phi_to_u(np.subtract(phi_h, phi_i, out=phi_h), out=phi_h))
        s = self._warp(u[0], u[1], param)
        return _Coordinates(u, s, param, four_sigma, zo_unit)

    def _incident(self, wi: _Vectors) -> _Incident:
        """The table direction's quantities (:class:`_Incident`) for components wi (each (N,)),
        computed once per run of bitwise-equal consecutive directions (:func:`_run_starts`: the
        reparameterized grid and the brute-force reference repeat the view) and repeated over the run."""
        starts = _run_starts(wi)
        x, y, z = _normalized(*(wi if starts is None else (c[starts] for c in wi)))
        theta = np.arctan2(np.hypot(x, y), z)
        phi = np.arctan2(y, x)
        param = _param_weights(self.theta_i, theta)
        four_sigma = None
        if self.jacobian:  # σ(ω_i) has no θ_i-slice dependence
            four_sigma = self._sigma.columns(_theta_to_u(theta, out=theta), _phi_to_u(phi))[0]
            four_sigma *= 4.0
        if starts is None:
            return _Incident(x, y, z, phi, param, four_sigma)
        counts = np.diff(starts, append=wi[0].shape[0])
        x, y, z, phi, lo, hi, w = (np.repeat(a, counts) for a in (x, y, z, phi, *param))
        return _Incident(x, y, z, phi, (lo, hi, w), None if four_sigma is None else np.repeat(four_sigma, counts))

    def _eval_block(self, wi: _Vectors, wo: _Vectors) -> list[np.ndarray]:
        """ρ per channel (3 arrays (N,)) for the table direction wi and the other direction wo as
        in :meth:`_coordinates`."""
        c = self._coordinates(wi, wo)
        value = self._rgb.columns(c.s[0], c.s[1], c.param)  # R
        d = None
        if c.four_sigma is not None:  # the jacobian flag: R · D / (4σ) = ρ cos θ_o
            d = self._ndf.columns(c.u[0], c.u[1])[0]  # D; the ndf has no θ_i dependence
            d /= c.four_sigma
        cos_o = np.maximum(c.z_o, GRAZING_COS, out=c.z_o)
        for channel in value:
            if d is not None:
                channel *= d
            channel /= cos_o
        return value

    def eval(self, L: np.ndarray, V: np.ndarray) -> np.ndarray:
        """RGB ρ(L, V) in 1/sr, shape (..., 3); 0 unless L_z > 0 and V_z > 0.

        With ``table_direction="view"`` (default) V is the file's incident direction ω_i
        and ρ = R(θ_V, …) · D / (4 σ(V) cos θ_L), as Mitsuba renders it; with ``"light"``
        the roles of L and V swap.
        Directions are normalized first. Where the stored R does not fall to 0 at the
        horizon ρ grows like 1/cos θ of the other direction; cos θ is floored at
        :data:`GRAZING_COS`, so ρ is finite for every pair above the surface.
        """
        L, V = as_directions(L, V)
        shape = L.shape[:-1]
        L, V = L.reshape(-1, 3), V.reshape(-1, 3)
        if not (np.all(np.isfinite(L)) and np.all(np.isfinite(V))):
            raise ValueError("directions must be finite")
        Wi, Wo = (np.ascontiguousarray(W) for W in ((V, L) if self.table_direction == "view" else (L, V)))
        out = np.zeros((L.shape[0], 3))
        above = (L[:, 2] > 0) & (V[:, 2] > 0)
        # blocks of the pairs above the surface (the others keep their 0): slices of consecutive pairs when
        # all are (views, no copy), else of their indices
        rows = None if above.all() else np.flatnonzero(above)
        for start in range(0, L.shape[0] if rows is None else rows.size, _BLOCK):
            sel = slice(start, start + _BLOCK) if rows is None else rows[start : start + _BLOCK]
            for c, value in enumerate(self._eval_block(_columns(Wi, sel), _columns(Wo, sel))):
                out[sel, c] = value
        return out.reshape(*shape, 3)


#: A block of direction vectors as their components (x, y, z), each (N,).
_Vectors = tuple[np.ndarray, np.ndarray, np.ndarray]


def _columns(W: np.ndarray, rows: np.ndarray | slice | None = None) -> _Vectors:
    """The components (x, y, z) of direction rows W (N, 3, C-contiguous), or of its rows ``rows``
    (a slice: a view; indices: a copy), as strided views."""
    if isinstance(rows, slice):
        W = W[rows]
    elif rows is not None:
        W = np.take(W, rows, axis=0)
    return W[:, 0], W[:, 1], W[:, 2]


class _Coordinates(NamedTuple):
    """Where a block of direction pairs falls in the tables (each array (N,)): the half vector's
    unit coordinates ``u`` = (x, y), the inverse-warped sample ``s`` = W⁻¹_{θ_i}(u), the θ_i
    slice weights ``param`` (:func:`._rgl_warp._param_weights`), 4σ(ω_i) (``None`` without the
    jacobian flag) and cos θ of the other direction ``z_o``."""

    u: tuple[np.ndarray, np.ndarray]
    s: tuple[np.ndarray, np.ndarray]
    param: tuple[np.ndarray, np.ndarray, np.ndarray]
    four_sigma: np.ndarray | None
    z_o: np.ndarray


class _Incident(NamedTuple):
    """The table direction's quantities per point (each (N,)): its unit vector (x, y, z), azimuth
    φ_i, θ_i slice weights ``param`` and 4σ(ω_i) (``None`` without the jacobian flag)."""

    x: np.ndarray
    y: np.ndarray
    z: np.ndarray
    phi: np.ndarray
    param: tuple[np.ndarray, np.ndarray, np.ndarray]
    four_sigma: np.ndarray | None


#: Fewest rows a run of equal table directions must average for :func:`_run_starts` to share them.
_MIN_RUN = 4


def _run_starts(w: _Vectors) -> np.ndarray | None:
    """First index of each run of bitwise-equal consecutive directions, given as components w
    (x, y, z) (each (N,)), or ``None`` when the runs average fewer than :data:`_MIN_RUN`
    directions (computing per run would not pay). Bitwise: −0.0 and 0.0 differ (their azimuths can)."""
    n = w[0].shape[0]
    if n < 2 * _MIN_RUN:
        return None
    new = np.zeros(n - 1, dtype=bool)
    for component in w:
        bits = component.view(np.int64)
        new |= bits[1:] != bits[:-1]
    if (np.count_nonzero(new) + 1) * _MIN_RUN > n:
        return None
    starts = np.flatnonzero(new)
    starts += 1
    return np.concatenate(([0], starts))


# --------------------------------------------------------------------------------------
# the reader
# --------------------------------------------------------------------------------------


def read_rgl(
    path: str | os.PathLike[str],
    *,
    clip_negative: bool = True,
    table_direction: Literal["light", "view"] = DEFAULT_TABLE_DIRECTION,
) -> RGLBRDF:
    """Read an isotropic RGB RGL material (``*_rgb.bsdf``; data_specs/rgl_bsdf.md).

    Parameters
    ----------
    path
        The ``.bsdf`` file.
    clip_negative
        Clamp negative (out-of-gamut) RGB values to 0, with a :class:`RGLGamutWarning`
        naming the count (kept in ``n_negative`` either way).
    table_direction
        ``"view"`` (default: V is the table's ω_i, as Mitsuba 3 renders the format) or
        ``"light"`` (L is ω_i) (:class:`RGLBRDF`). ``load_brdf("file.bsdf#light")`` and
        ``--rgl-incident light`` on the command line select ``"light"``.

    Raises
    ------
    BadInputError
        Any container problem (:func:`read_tensor_file`); a missing field; a dtype or
        shape other than the format's (float32 tables, uint8 ``description`` and
        ``jacobian``, ``vndf`` (n_φ, n_θ, H, W), ``rgb`` (n_φ, n_θ, 3, h, w)); an
        anisotropic file (more than one φ_i: the message states its anisotropy,
        :func:`rgl_anisotropy`); a spectral file (``spectra`` and
        ``wavelengths`` instead of ``rgb``); non-finite values, a negative density, a
        non-positive σ or an all-zero VNDF slice.

    Examples
    --------
    A tiny synthetic file: a uniform VNDF (the warp is then the identity), R = 0.5, 0.25,
    0.125 everywhere, D = 1/π, σ = 1, one incident angle:

    >>> import pathlib, tempfile
    >>> import numpy as np
    >>> folder = tempfile.TemporaryDirectory()
    >>> rgb = np.ones((1, 1, 3, 2, 2), np.float32) * np.float32([0.5, 0.25, 0.125])[:, None, None]
    >>> path = write_tensor_file(pathlib.Path(folder.name) / "flat_rgb.bsdf", {
    ...     "description": "flat", "jacobian": np.uint8([1]),
    ...     "theta_i": np.float32([0.0]), "phi_i": np.float32([0.0]),
    ...     "ndf": np.full((2, 2), 1 / np.pi, np.float32), "sigma": np.ones((2, 2), np.float32),
    ...     "vndf": np.ones((1, 1, 2, 2), np.float32), "rgb": rgb})
    >>> brdf = read_rgl(path)
    >>> brdf.name, brdf.description, brdf.kind
    ('flat_rgb', 'flat', 'tabulated')

    With the default ``table_direction="view"`` the view V is ω_i and
    ρ = R · D / (4 σ cos θ_L); at cos θ_L = 0.8, 0.5/(4π · 0.8) = 0.0497 in red, and with
    ``"light"`` (ω_i = L) ρ = R · D / (4 σ cos θ_V) = 0.5/(4π) = 0.0398 at V = normal:

    >>> brdf.eval(np.array([0.6, 0.0, 0.8]), np.array([0.0, 0.0, 1.0])).round(5)
    array([0.04974, 0.02487, 0.01243])
    >>> lit = read_rgl(path, table_direction="light")
    >>> lit.name, lit.eval(np.array([0.6, 0.0, 0.8]), np.array([0.0, 0.0, 1.0])).round(5)
    ('flat_rgb#light', array([0.03979, 0.01989, 0.00995]))
    >>> brdf.eval(np.array([0.6, 0.0, 0.8]), np.array([0.0, 0.0, -1.0]))  # V below the surface
    array([0., 0., 0.])
    >>> folder.cleanup()
    """
    path = Path(path)
    fields = read_tensor_file(path)
    if "rgb" not in fields and ("spectra" in fields or "wavelengths" in fields):
        raise BadInputError(
            path, "spectral RGL file (fields 'spectra', 'wavelengths'); only the RGB version (*_rgb.bsdf) is "
            "supported"
        )
    missing = [name for name in _REQUIRED if name not in fields]
    if missing:
        raise BadInputError(
            path, f"missing field(s) {', '.join(map(repr, missing))}: not an RGL measured-material file "
            f"(fields: {', '.join(fields)})"
        )
    description = _expect(path, fields, "description", "u1", 1).tobytes().decode("utf-8", errors="replace")
    jacobian = _expect(path, fields, "jacobian", "u1", 1)
    if jacobian.shape != (1,):
        raise BadInputError(path, f"field 'jacobian' has shape {jacobian.shape}, expected (1,)")
    phi_i = _expect(path, fields, "phi_i", "<f4", 1)
    theta_i = _expect(path, fields, "theta_i", "<f4", 1)
    if phi_i.size != 1:
        raise BadInputError(path, _anisotropic_message(path, fields, phi_i, theta_i))
    if not np.isfinite(phi_i[0]):
        raise BadInputError(path, f"field 'phi_i' is not finite ({phi_i[0]!r})")
    T = theta_i.size
    ndf = _expect(path, fields, "ndf", "<f4", 2)
    sigma = _expect(path, fields, "sigma", "<f4", 2)
    vndf = _expect(path, fields, "vndf", "<f4", 4)
    rgb = _expect(path, fields, "rgb", "<f4", 5)
    if vndf.shape[:2] != (1, T):
        raise BadInputError(path, f"field 'vndf' has shape {vndf.shape}, expected (1, {T}, H, W) (n_φ_i, n_θ_i, …)")
    if rgb.shape[:3] != (1, T, 3):
        raise BadInputError(path, f"field 'rgb' has shape {rgb.shape}, expected (1, {T}, 3, h, w)")
    luminance = None
    if "luminance" in fields:
        luminance = _expect(path, fields, "luminance", "<f4", 4)
        if luminance.shape != (1, T, *rgb.shape[3:]):
            raise BadInputError(
                path, f"field 'luminance' has shape {luminance.shape}, expected (1, {T}, {rgb.shape[3]}, "
                f"{rgb.shape[4]}) like 'rgb'"
            )
        luminance = luminance[0]
    return RGLBRDF(
        theta_i,
        ndf,
        sigma,
        vndf[0],
        rgb[0],
        jacobian=bool(jacobian[0]),
        clip_negative=clip_negative,
        description=description,
        luminance=luminance,
        valid=fields.get("valid"),
        table_direction=table_direction,
        # the convention is part of the name where it is not the default: "paper_white_rgb#light"
        name=path.stem if table_direction == DEFAULT_TABLE_DIRECTION
        else f"{path.stem}#{_INCIDENT_NAME.get(table_direction)}",
        source=str(path),
    )
