"""The engines' split-sum prefiltered environment lighting for GGX materials ([Karis13] § Image
Based Lighting, "Split Sum Approximation"; [LdR14] §4.9, distant light probes): the speed baseline of
``benchmarks/prefilter_speed.py``.

The reflected radiance of a Cook–Torrance GGX material under distant lighting is approximated by
splitting the integral of the specular term into two factors (:class:`SplitSum`):

    B(R, V) ≈ ks · L̄_α(R) · (F0 · A(μ, r) + B(μ, r)) + kd/π · E(N),
    N = normalize(R + V), μ = N·V, r = √α (UE4's "roughness"),

1. the **prefiltered environment** L̄_α(R) (:func:`ggx_prefiltered`, :func:`prefiltered_levels`),
   summed over every pixel of the lat-long map by a zonal convolution (:func:`zonal_convolution`);
2. the **environment BRDF** A, B (:func:`env_brdf_lut` → :class:`EnvBRDFLUT`), the directional
   albedo of *this* model's specular term;
3. the **diffuse** term: kd/π times the irradiance E(N), by the same zonal convolution.

:func:`split_sum` builds it for an environment and a material. For a constant environment it equals
the directional albedo × L exactly (up to the table's interpolation); otherwise the split costs an
accuracy that ``benchmarks/prefilter_speed.py`` measures against brute force. Citation keys:
``data_specs/bibliography.md``.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from ...brdf_io.brdf import BRDF
from ...brdf_io.errors import BadInputError
from ...brdf_io.latlong import bilinear_lookup, pixel_angles, pixel_directions, row_solid_angles
from ...brdf_io.models import CookTorrance, smith_g1_over_cos

__all__ = [
    "EnvBRDFLUT",
    "env_brdf_lut",
    "zonal_convolution",
    "ggx_kernel",
    "ggx_prefiltered",
    "default_level_rows",
    "prefiltered_levels",
    "SplitSum",
    "split_sum",
]


# ----------------------------------------------------------------------------------------
# the environment BRDF table (Karis 2013, "Environment BRDF")
# ----------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class EnvBRDFLUT:
    """Scale A and bias B of F0 in the GGX specular directional albedo, over (μ, r).

    ∫ ρ_spec(L, V) cos θ_i dL = ks (F0 A(μ, r) + B(μ, r)) for ρ_spec = D F G / (4 cos θ_i cos θ_o),
    μ = cos θ_o = N·V, r = √α.

    Attributes
    ----------
    mu, roughness
        (n_mu,), (n_r,) node positions (texel centres unless given).
    scale, bias
        float32 (n_mu, n_r) tables A, B.
    seconds
        Time to compute it.
    """

    mu: np.ndarray
    roughness: np.ndarray
    scale: np.ndarray
    bias: np.ndarray
    seconds: float = float("nan")

    @property
    def nbytes(self) -> int:
        """Bytes of the two float32 tables (an RG texture)."""
        return int(self.scale.nbytes + self.bias.nbytes)

    def lookup(self, mu: np.ndarray, alpha: float) -> tuple[np.ndarray, np.ndarray]:
        """(A, B) at μ (any shape) and GGX width α: bilinear between the nodes, clamped to the
        outer nodes (a texture lookup with clamp-to-edge)."""
        mu = np.asarray(mu, dtype=np.float64)
        r = float(np.sqrt(alpha))

        def weights(nodes: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
            if nodes.size == 1:
                zero = np.zeros(np.shape(x), dtype=np.int64)
                return zero, zero, np.zeros(np.shape(x))
            x = np.clip(x, nodes[0], nodes[-1])
            hi = np.clip(np.searchsorted(nodes, x, side="right"), 1, nodes.size - 1)
            lo = hi - 1
            return lo, hi, (x - nodes[lo]) / (nodes[hi] - nodes[lo])

        m0, m1, fm = weights(self.mu, mu)
        r0, r1, fr = weights(self.roughness, np.asarray(r))
        out = []
        for table in (self.scale.astype(np.float64), self.bias.astype(np.float64)):
            at_r = table[:, r0] * (1.0 - fr) + table[:, r1] * fr  # (n_mu,)
            out.append(at_r[m0] * (1.0 - fm) + at_r[m1] * fm)
        return out[0], out[1]


def env_brdf_lut(
    *, n_mu: int = 32, n_roughness: int = 32, roughness: Sequence[float] | None = None,
    mu: Sequence[float] | None = None, n_xi: int = 64, n_phi: int = 64,
) -> EnvBRDFLUT:
    """Compute the environment-BRDF table of GGX with shrmkit's Smith G (Karis 2013).

    For each (μ, r), α = r², with V = (√(1 − μ²), 0, μ):

        A = ∫∫ (1 − F_c) G_vis dξ dφ/2π,   B = ∫∫ F_c G_vis dξ dφ/2π,
        G_vis = G1(θ_i)/cos θ_i · G1(θ_o)/cos θ_o · cos θ_i · (V·H) / cos θ_h

    (Karis's ``IntegrateBRDF``: the specular integrand divided by the pdf D cos θ_h of his GGX
    half-vector warp cos θ_h = √((1 − ξ)/(1 + (α² − 1)ξ)); L = 2(V·H)H − V, zero below the
    horizon), with ``n_xi`` Gauss–Legendre nodes in ξ and ``n_phi`` uniform φ.

    Parameters
    ----------
    n_mu, n_roughness
        Table size, nodes at texel centres (j + ½)/n (UE4 uses a 128 × 32 texture; the
        default 32 × 32 is the common real-time size).
    roughness, mu
        Explicit node positions instead (increasing, in (0, 2] and (0, 1]).
    n_xi, n_phi
        Quadrature nodes.

    Returns
    -------
    EnvBRDFLUT
    """
    t0 = time.perf_counter()
    mu_n = (np.arange(n_mu) + 0.5) / n_mu if mu is None else np.asarray(mu, dtype=np.float64)
    r_n = (np.arange(n_roughness) + 0.5) / n_roughness if roughness is None else np.asarray(roughness, float)
    if mu_n.ndim != 1 or np.any(mu_n <= 0) or np.any(mu_n > 1) or np.any(np.diff(mu_n) <= 0):
        raise BadInputError(None, f"LUT mu nodes must increase within (0, 1], got {mu_n}")
    if r_n.ndim != 1 or np.any(r_n <= 0) or np.any(r_n > 2) or np.any(np.diff(r_n) <= 0):
        raise BadInputError(None, f"LUT roughness nodes must increase within (0, 2], got {r_n}")
    x, w = np.polynomial.legendre.leggauss(n_xi)
    xi, w_xi = (x + 1.0) / 2.0, w / 2.0
    phi = 2.0 * np.pi * (np.arange(n_phi) + 0.5) / n_phi
    scale = np.empty((mu_n.size, r_n.size))
    bias = np.empty((mu_n.size, r_n.size))
    sin_o = np.sqrt(1.0 - mu_n**2)[:, None, None]
    cos_o = mu_n[:, None, None]
    for k, r in enumerate(r_n):
        alpha = r * r
        cos_h = np.sqrt((1.0 - xi) / (1.0 + (alpha**2 - 1.0) * xi))[None, :, None]
        sin_h = np.sqrt(np.clip(1.0 - cos_h**2, 0.0, None))
        # V = (sin θ_o, 0, cos θ_o), H = (sin θ_h cos φ, sin θ_h sin φ, cos θ_h)
        v_dot_h = sin_o * sin_h * np.cos(phi)[None, None, :] + cos_o * cos_h  # (n_mu, n_xi, n_phi)
        cos_i = 2.0 * v_dot_h * cos_h - cos_o  # L_z of L = 2(V·H)H − V
        ok = (cos_i > 0.0) & (v_dot_h > 0.0)
        g_vis = np.where(
            ok,
            smith_g1_over_cos(cos_i, alpha, "ggx") * smith_g1_over_cos(cos_o, alpha, "ggx")
            * np.clip(cos_i, 0.0, None) * v_dot_h / cos_h,
            0.0,
        )
        fc = (1.0 - np.clip(v_dot_h, 0.0, 1.0)) ** 5
        weight = w_xi[None, :, None] / n_phi
        scale[:, k] = ((1.0 - fc) * g_vis * weight).sum(axis=(1, 2))
        bias[:, k] = (fc * g_vis * weight).sum(axis=(1, 2))
    return EnvBRDFLUT(mu=mu_n, roughness=r_n, scale=scale.astype(np.float32), bias=bias.astype(np.float32),
                      seconds=time.perf_counter() - t0)


# ----------------------------------------------------------------------------------------
# zonal convolution on the lat-long grid (angular domain, exact pixel sums)
# ----------------------------------------------------------------------------------------
def zonal_convolution(
    radiance: np.ndarray, kernel: Callable[[np.ndarray], np.ndarray], rows: int, *, chunk_rows: int = 16
) -> tuple[np.ndarray, np.ndarray]:
    """Σ_p L_p Ω_p k(R·ω_p) at the pixel centres R of a rows × 2·rows lat-long grid.

    A zonal kernel k depends only on the angle between R and ω_p: for output row i and map
    row k the sum over the map's columns is a circular convolution in φ, evaluated with real
    FFTs (O(rows · H · W log W) instead of O(rows · 2rows · H · W)). Every pixel of the map
    enters with its exact solid angle Ω_p and its centre direction (DESIGN §2), as in
    :func:`~shrmkit.analysis.reference.reference_radiance`.

    Parameters
    ----------
    radiance
        (H, W, C) map; W must be a multiple of 2·rows (so that the output columns fall on
        the FFT's shifted grid).
    kernel
        k(cos γ), vectorized.
    rows
        Output rows (a divisor of W/2).
    chunk_rows
        Output rows per batch (memory ~ chunk_rows · H · W · 24 bytes).

    Returns
    -------
    conv
        (rows, 2·rows, C) float64 sums.
    norm
        (rows,) Σ_p Ω_p k(R·ω_p): the same sum for a map of ones (independent of φ).
    """
    radiance = np.asarray(radiance, dtype=np.float64)
    height, width = radiance.shape[:2]
    w_out = 2 * rows
    if rows < 1 or width % w_out:
        raise BadInputError(None, f"output rows {rows}: the map's width {width} must be a multiple of 2 x rows")
    step = width // w_out
    theta_in, _ = pixel_angles(height, width)
    theta_out, _ = pixel_angles(rows, w_out)
    omega = row_solid_angles(height, width)
    l_hat = np.fft.rfft(radiance * omega[:, None, None], axis=1)  # (H, F, C)
    l_hat = np.moveaxis(l_hat, 1, 0)  # (F, H, C)
    # φ_out − φ_in = (π/W_out − π/W) + 2π n/W, n = output column (map's spacing) − map column
    dphi = np.pi / w_out - np.pi / width + 2.0 * np.pi * np.arange(width) / width
    cos_dphi = np.cos(dphi)
    conv = np.empty((rows, w_out, radiance.shape[2]))
    norm = np.empty(rows)
    for a in range(0, rows, chunk_rows):
        t = theta_out[a : a + chunk_rows]
        cos_g = (np.cos(t)[:, None, None] * np.cos(theta_in)[None, :, None]
                 + np.sin(t)[:, None, None] * np.sin(theta_in)[None, :, None] * cos_dphi[None, None, :])
        k = kernel(np.clip(cos_g, -1.0, 1.0))  # (c, H, W)
        norm[a : a + chunk_rows] = (k.sum(axis=2) * omega[None, :]).sum(axis=1)
        k_hat = np.moveaxis(np.fft.rfft(k, axis=2), 2, 0)  # (F, c, H)
        out_hat = np.matmul(k_hat, l_hat)  # (F, c, C)
        conv[a : a + chunk_rows] = np.fft.irfft(np.moveaxis(out_hat, 0, 1), n=width, axis=1)[:, ::step]
    return conv, norm


def ggx_kernel(alpha: float) -> Callable[[np.ndarray], np.ndarray]:
    """Karis's prefilter weight as a zonal kernel: D_α(h) max(cos γ, 0), cos θ_h = cos(γ/2)
    (N = V = R: h bisects R and ω), D the GGX distribution of ``CookTorrance``."""
    a2 = alpha * alpha

    def k(cos_g: np.ndarray) -> np.ndarray:
        c2 = (1.0 + cos_g) / 2.0  # cos² θ_h
        return a2 / (np.pi * (c2 * (a2 - 1.0) + 1.0) ** 2) * np.maximum(cos_g, 0.0)

    return k


def ggx_prefiltered(radiance: np.ndarray, alpha: float, rows: int) -> np.ndarray:
    """The GGX-prefiltered map L̄_α at the pixel centres of rows × 2·rows, float32 (rows, 2rows, 3)."""
    conv, norm = zonal_convolution(radiance, ggx_kernel(alpha), rows)
    return (conv / norm[:, None, None]).astype(np.float32)


def _divisor_at_least(height: int, target: float) -> int:
    """The smallest divisor of ``height`` that is >= target (``height`` itself if none is)."""
    for d in range(1, height + 1):
        if height % d == 0 and d >= target:
            return d
    return height


def default_level_rows(height: int, alpha: float) -> int:
    """Rows of the prefiltered level for GGX width α on an H-row map: pixel pitch at most α/4
    (the lobe is ~2α wide in the reflected direction), i.e. rows >= 4π/α, at least 8, rounded
    up to a divisor of H (at most H: the map's own resolution)."""
    return _divisor_at_least(height, max(8.0, 4.0 * np.pi / alpha))


def prefiltered_levels(
    env: object, alphas: Sequence[float], *, rows: Sequence[int] | None = None
) -> tuple[tuple[float, np.ndarray], ...]:
    """The mip chain: one GGX-prefiltered map per α (increasing), each at
    :func:`default_level_rows` unless ``rows`` are given."""
    radiance = np.asarray(getattr(env, "radiance", env), dtype=np.float64)
    alphas = [float(a) for a in alphas]
    if not alphas or any(not 0.0 < a <= 1.0 for a in alphas) or any(np.diff(alphas) <= 0):
        raise BadInputError(None, f"GGX levels need increasing alpha in (0, 1], got {alphas}")
    rows = [default_level_rows(radiance.shape[0], a) for a in alphas] if rows is None else list(rows)
    return tuple((a, ggx_prefiltered(radiance, a, n)) for a, n in zip(alphas, rows, strict=True))


# ----------------------------------------------------------------------------------------
# the split-sum representation
# ----------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class SplitSum:
    """Split-sum lighting of one environment for one GGX Cook–Torrance material.

    The material is ``brdf_io.models.CookTorrance`` with ``dist=ggx``: ρ = kd/π + ks D F G /
    (4 cos θ_i cos θ_o), GGX D of width α, Schlick F with F0, separable exact Smith G. Its
    reflected radiance under distant lighting is B(R, V) ≈ ks · L̄_α(R) · (F0 · A(μ, r) + B(μ, r))
    + kd/π · E(N), N = normalize(R + V), μ = N·V, r = √α:

    1. L̄_α(R) = ∫ L(ω) D_α(h) max(R·ω, 0) dω / ∫ D_α(h) max(R·ω, 0) dω, h = normalize(R + ω):
       Karis's GGX-importance-sampled prefilter under the assumption N = V = R (his
       ``PrefilterEnvMap``: samples of L weighted by N·L), here summed over *every* pixel of the
       lat-long map (exact pixel weights, no sampling noise). The kernel depends on the angle
       between R and ω only (zonal), so on a lat-long grid each pair of (output row, map row) is
       a circular convolution in φ, done with FFTs (:func:`zonal_convolution`). One map per
       roughness (the mip chain of :func:`prefiltered_levels`; the material's own α by default,
       which is the engines' best case);
    2. A, B: the directional albedo of the specular term split into the scale A and bias B of F0
       (F = F0 (1 − F_c) + F_c, F_c = (1 − V·H)⁵), on a 2-D table over (μ, r) at texel centres,
       bilinear between them (:func:`env_brdf_lut`: Gauss–Legendre quadrature over Karis's GGX
       sample warp (ξ ∈ (0, 1), φ ∈ [0, 2π)) with shrmkit's exact separable Smith G, not UE4's
       Schlick k = α/2, so that it is the directional albedo of *this* model);
    3. E(N) = ∫ L(ω) max(N·ω, 0) dω, an irradiance map made by the same zonal convolution
       (engines use 9 SH coefficients or a map).

    For a constant environment L̄ = L and E = πL, so the split sum equals the directional albedo
    × L exactly, up to the table's interpolation. For other lighting the split (and N = V = R
    inside the prefilter: no stretching of the lobe at grazing views) costs accuracy that
    depends on the map and the view; ``benchmarks/prefilter_speed.py`` measures it against
    brute force.

    Attributes
    ----------
    alpha, ks, f0, kd
        The material (α scalar; ks, f0, kd RGB).
    levels
        ((α_j, float32 (rows_j, 2rows_j, 3)), …) the prefiltered maps, α increasing; the
        material's α is looked up between the two levels around it, linearly in r = √α (as a
        trilinear mip lookup), or in the one level equal to it.
    lut
        The environment-BRDF table.
    irradiance
        float32 (rows, 2rows, 3) irradiance map E(N), or None when kd = 0.
    seconds
        Timings: ``"levels"``, ``"irradiance"`` (this environment) and ``"lut"`` (the table,
        computed once for every material and environment).
    """

    alpha: float
    ks: np.ndarray
    f0: np.ndarray
    kd: np.ndarray
    levels: tuple[tuple[float, np.ndarray], ...]
    lut: EnvBRDFLUT
    irradiance: np.ndarray | None = None
    seconds: dict = field(default_factory=dict)

    @property
    def nbytes(self) -> int:
        """Bytes stored: the float32 prefiltered levels, the irradiance map and the table."""
        maps = sum(m.nbytes for _, m in self.levels) + (0 if self.irradiance is None else self.irradiance.nbytes)
        return int(maps + self.lut.nbytes)

    def prefiltered(self, R: np.ndarray) -> np.ndarray:
        """L̄_α(R) (n, 3): bilinear in the levels, linear in √α between the two around α."""
        alphas = np.array([a for a, _ in self.levels])
        j = int(np.searchsorted(alphas, self.alpha))
        if j < alphas.size and np.isclose(alphas[j], self.alpha, rtol=1e-12, atol=0.0):
            return bilinear_lookup(self.levels[j][1], R).astype(np.float64)
        lo, hi = max(j - 1, 0), min(j, alphas.size - 1)
        a = bilinear_lookup(self.levels[lo][1], R).astype(np.float64)
        if lo == hi:
            return a
        b = bilinear_lookup(self.levels[hi][1], R).astype(np.float64)
        f = (np.sqrt(self.alpha) - np.sqrt(alphas[lo])) / (np.sqrt(alphas[hi]) - np.sqrt(alphas[lo]))
        return a * (1.0 - f) + b * f

    def radiance(self, R: np.ndarray, V: np.ndarray) -> np.ndarray:
        """B(R, V) (n, 3) float64 for unit R, V (n, 3) in the global z-up frame."""
        R = np.atleast_2d(np.asarray(R, dtype=np.float64))
        V = np.atleast_2d(np.asarray(V, dtype=np.float64))
        N = R + V
        N /= np.where((n := np.linalg.norm(N, axis=1, keepdims=True)) > 0, n, 1.0)
        mu = np.clip(np.einsum("ij,ij->i", N, V), 0.0, 1.0)
        scale, bias = self.lut.lookup(mu, self.alpha)
        out = self.ks * self.prefiltered(R) * (self.f0[None, :] * scale[:, None] + bias[:, None])
        if self.irradiance is not None:
            out += self.kd / np.pi * bilinear_lookup(self.irradiance, N).astype(np.float64)
        return out

    def view_map(self, view: np.ndarray) -> np.ndarray:
        """Distant-viewer map B(R, V) at the pixel centres R of the material's (finest
        enclosing) level grid for one view direction, float32 (rows, 2rows, 3)."""
        rows = max(m.shape[0] for _, m in self.levels)
        R = pixel_directions(rows, 2 * rows).reshape(-1, 3)
        V = np.broadcast_to(np.asarray(view, float) / np.linalg.norm(view), R.shape)
        return self.radiance(R, V).reshape(rows, 2 * rows, 3).astype(np.float32)


def _ggx_material(brdf: BRDF) -> CookTorrance:
    if not isinstance(brdf, CookTorrance) or brdf.distribution != "ggx":
        raise BadInputError(getattr(brdf, "name", None),
                            "the split sum is defined for Cook-Torrance GGX materials (cook-torrance:...,dist=ggx)")
    if not 0.0 < brdf.alpha <= 1.0:
        raise BadInputError(brdf.name, f"split-sum roughness needs alpha in (0, 1], got {brdf.alpha}")
    return brdf


def split_sum(
    env: object, brdf: BRDF, *, lut: EnvBRDFLUT | None = None, levels: Sequence[float] | None = None,
    rows: int | None = None, irradiance_rows: int = 32,
) -> SplitSum:
    """Build the split-sum lighting of ``env`` for a GGX ``CookTorrance`` material.

    Parameters
    ----------
    env
        An EnvironmentMap or an (H, W, 3) array (lat-long, z-up, DESIGN §2).
    brdf
        ``cook-torrance:…,dist=ggx`` with α in (0, 1].
    lut
        A table from :func:`env_brdf_lut` (computed here when None; an engine computes it once).
    levels
        α of the mip chain's levels (default: the material's α alone, the most accurate chain).
    rows
        Rows of the material's level (default :func:`default_level_rows`); with ``levels``
        each level gets its default.
    irradiance_rows
        Rows of the irradiance map (rounded up to a divisor of H), used when kd > 0.

    Raises
    ------
    BadInputError
        Any other BRDF, α > 1, or grid sizes the map's width does not divide.
    """
    material = _ggx_material(brdf)
    radiance = np.asarray(getattr(env, "radiance", env), dtype=np.float64)
    seconds: dict[str, float] = {}
    if lut is None:
        lut = env_brdf_lut()
    seconds["lut"] = lut.seconds
    t0 = time.perf_counter()
    if levels is None:
        n = default_level_rows(radiance.shape[0], material.alpha) if rows is None else int(rows)
        chain: tuple[tuple[float, np.ndarray], ...] = (
            (float(material.alpha), ggx_prefiltered(radiance, material.alpha, n)),)
    else:
        chain = prefiltered_levels(radiance, levels)
    seconds["levels"] = time.perf_counter() - t0
    irradiance = None
    t0 = time.perf_counter()
    kd = np.broadcast_to(np.asarray(material.kd, dtype=np.float64), (3,))
    if np.any(kd > 0):
        n = _divisor_at_least(radiance.shape[0], irradiance_rows)
        conv, _ = zonal_convolution(radiance, lambda c: np.maximum(c, 0.0), n)
        irradiance = conv.astype(np.float32)
    seconds["irradiance"] = time.perf_counter() - t0
    return SplitSum(
        alpha=float(material.alpha), ks=np.broadcast_to(np.asarray(material.ks, float), (3,)).copy(),
        f0=np.broadcast_to(np.asarray(material.f0, float), (3,)).copy(), kd=kd.copy(), levels=chain, lut=lut,
        irradiance=irradiance, seconds=seconds,
    )
