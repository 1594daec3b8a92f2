"""Lobe-truncated angular-domain sum: the best brute-force baseline ([RH02] Table 4).

[RH02] §6 measures frequency-space prefiltering against an angular-domain integration that
"considers only the pixels where the BRDF lobe is significant". For each output (R, V):

    B(R, V) ≈ Σ_{p : angle(ω_p, R) ≤ c(θ_v)} L_p Ω_p ρ̂(ω_p; V, N),   N = normalize(R + V),

the sum of :func:`~shrmkit.analysis.reference.reference_radiance` (every lit pixel p of the
lat-long map, direction ω_p at its centre, exact solid angle Ω_p, ρ̂ in the local frame of
N) restricted to a cone about R. The cone's half-angle c(θ_v) comes from the BRDF's own ρ̂
(:func:`lobe_cones`, :class:`LobeCones`), the pixels inside it from :func:`cone_pixels`; every
dropped pixel has ρ̂ below ``threshold`` × peak, which bounds the error per output
(:meth:`LobeTruncatedSum.radiance_and_bound`). :func:`lobe_truncated_sum` sets the sum up,
:func:`lobe_truncated_radiance` evaluates it once.

References: [RH02] §6, Table 3 (costs) and Table 4 (the angular-domain baseline that sums only the
significant part of the lobe). Citation keys: ``data_specs/bibliography.md``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.spatial import cKDTree

from ...brdf_io.brdf import BRDF
from ...brdf_io.errors import BadInputError
from ...brdf_io.latlong import pixel_directions, row_solid_angles
from ...brdf_io.reparam import reparam_directions
from ..reference import local_frames

__all__ = [
    "DEFAULT_THRESHOLD",
    "QUERIES",
    "LobeCones",
    "lobe_cones",
    "cone_pixels",
    "LobeTruncatedSum",
    "lobe_truncated_sum",
    "lobe_truncated_radiance",
]

#: Fraction of the lobe's peak below which environment pixels are dropped (RH02 Table 4's
#: "significant" part of the lobe; the issue's 1e-3).
DEFAULT_THRESHOLD = 1e-3


def _rho_hat(brdf: BRDF, L: np.ndarray, V: np.ndarray) -> np.ndarray:
    """ρ̂ = ρ max(N·L, 0) in the local frame (N = +z), as :mod:`~shrmkit.analysis.reference`
    evaluates it: the model's own ρ̂ for analytic models, ρ × cos θ_i otherwise."""
    if brdf.kind == "analytic":
        return brdf.rho_hat(L, V)
    rho, _ = brdf.eval_counted(L, np.broadcast_to(V, L.shape))
    return rho * np.maximum(L[..., 2], 0.0)[..., None]


@dataclass(frozen=True, eq=False)
class LobeCones:
    """Cone half-angles about R that hold the lobe above ``threshold`` × peak, per θ_v.

    Attributes
    ----------
    theta_v
        (n,) tabulated view elevations θ_v (radians), from 0 to π/2.
    half_angle
        (n,) cone half-angle c(θ_v) about R (radians, at most π).
    peak
        (n, 3) largest ρ̂ per channel found on the grid at each θ_v (1/sr).
    threshold
        The fraction of the peak that defines the lobe.
    step
        The θ_i' grid step (radians): each half-angle is rounded up to a node of that grid.
    """

    theta_v: np.ndarray
    half_angle: np.ndarray
    peak: np.ndarray
    threshold: float
    step: float

    def at(self, theta_v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(half-angle, peak (n, 3)) for view elevations ``theta_v`` (radians): the larger of
        the two neighbouring tabulated values (conservative between the nodes)."""
        tv = np.clip(np.asarray(theta_v, dtype=np.float64), self.theta_v[0], self.theta_v[-1])
        hi = np.clip(np.searchsorted(self.theta_v, tv, side="left"), 1, self.theta_v.size - 1)
        lo = hi - 1
        angle = np.maximum(self.half_angle[lo], self.half_angle[hi])
        peak = np.maximum(self.peak[lo], self.peak[hi])
        return angle, peak


def lobe_cones(
    brdf: BRDF, *, threshold: float = DEFAULT_THRESHOLD, n_views: int = 46, n_theta: int = 512, n_phi: int = 17
) -> LobeCones:
    """Tabulate the cone that holds ρ̂ above ``threshold`` × its peak, for each view elevation.

    θ_v = angle(N, V) is half the angle between R and V. The half-angle c(θ_v) is the largest angle
    θ_i' from R at which any channel of ρ̂(θ_i', θ_o' = 2θ_v, φ') exceeds ``threshold`` × that
    channel's peak for the view, found numerically on a fine grid (DESIGN §3):
    in the reflection frame (R = +z, V' at θ_o' = 2θ_v; :func:`~shrmkit.brdf_io.reparam.reparam_directions`)
    ρ̂ is evaluated on ``n_theta`` angles θ_i' uniform in [0, π] × ``n_phi`` azimuths φ'
    uniform in [0, π] (ρ̂ of an isotropic BRDF is even in φ'), for ``n_views`` elevations θ_v
    uniform in [0°, 89.5°] (θ_v = 90° is the grazing singularity θ_o' = π). The half-angle is
    the grid angle two nodes beyond the last node above threshold × peak (per channel, any
    channel), i.e. rounded *up* to the grid with one node to spare for the sampling of φ' and
    θ_v (checked against a 8× finer grid: within 0.02° of it or above; conservative for a lobe
    sampled finer than its width); π when the lobe reaches the antipode.

    Parameters
    ----------
    brdf
        Any evaluable BRDF.
    threshold
        Fraction of the peak, in (0, 1).
    n_views, n_theta, n_phi
        Grid sizes (θ_v, θ_i', φ').

    Returns
    -------
    LobeCones

    Raises
    ------
    BadInputError
        ``threshold`` outside (0, 1), a grid smaller than 2 nodes, or a BRDF whose ρ̂ is zero
        or non-finite at some view on the grid.
    """
    if not 0.0 < threshold < 1.0:
        raise BadInputError(None, f"lobe threshold must be in (0, 1), got {threshold}")
    if min(n_views, n_theta, n_phi) < 2:
        raise BadInputError(None, f"lobe grid needs >= 2 nodes per axis, got {(n_views, n_theta, n_phi)}")
    theta_v = np.linspace(0.0, np.radians(89.5), n_views)
    theta_i = np.linspace(0.0, np.pi, n_theta)
    step = float(theta_i[1] - theta_i[0])
    phi = np.linspace(0.0, np.pi, n_phi)
    half = np.empty(n_views)
    peaks = np.empty((n_views, 3))
    for k, tv in enumerate(theta_v):
        L, V = reparam_directions(np.cos(theta_i)[:, None], np.cos(2.0 * tv), phi[None, :])
        rho = _rho_hat(brdf, L, np.broadcast_to(V, L.shape))  # (n_theta, n_phi, 3)
        peak = rho.max(axis=(0, 1))  # (3,)
        if not (np.all(np.isfinite(rho)) and np.any(peak > 0.0)):
            raise BadInputError(getattr(brdf, "name", None),
                                f"rho-hat is zero or not finite at theta_v = {np.degrees(tv):.1f} deg")
        above = np.any(rho > threshold * peak, axis=(1, 2))  # per θ_i' node
        last = int(np.flatnonzero(above).max())
        # the next node holds no value above the threshold; one node more covers the φ' and θ_v sampling
        half[k] = np.pi if last >= n_theta - 2 else theta_i[last + 2]
        peaks[k] = peak
    return LobeCones(theta_v=theta_v, half_angle=half, peak=peaks, threshold=float(threshold), step=step)


#: The cone queries :func:`cone_pixels` knows.
QUERIES = ("rows", "kdtree")


def _ranges(starts: np.ndarray, counts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(owner, value) of the concatenated integer ranges starts[k] + 0 … counts[k] − 1."""
    owner = np.repeat(np.arange(counts.size), counts)
    first = np.cumsum(counts) - counts
    return owner, starts[owner] + (np.arange(int(counts.sum())) - first[owner])


def cone_pixels(
    R: np.ndarray, half_angle: np.ndarray, height: int, width: int, *, query: str = "rows", tree: Any = None
) -> tuple[np.ndarray, np.ndarray]:
    """The pixels of an H × W lat-long map whose centres lie within ``half_angle`` of each R.

    Parameters
    ----------
    R
        (n, 3) unit vectors (cone axes), z-up frame.
    half_angle
        (n,) cone half-angles in radians (π or more: the whole sphere).
    height, width
        The map's grid (pixel centres θ = (i + ½)π/H, φ = 2π(j + ½)/W, DESIGN §2).
    query
        ``"rows"`` (default): exact geometry of the lat-long grid — the rows with
        |θ_i − θ_R| ≤ c, and in each row the contiguous (wrapping) run of columns with
        cos θ_i cos θ_R + sin θ_i sin θ_R cos Δφ ≥ cos c, all in numpy; ``"kdtree"``:
        ``cKDTree.query_ball_point`` on the unit pixel directions with the chord radius
        2 sin(c/2) (``tree``: a ``cKDTree`` of ``pixel_directions(H, W)``, built here when None).
        Both include pixels up to ~1e-9 rad beyond the cone (conservative).

    Returns
    -------
    owner, pixel
        int64 arrays of equal length: output index k and flat pixel index i·W + j of every
        (output, pixel) pair inside the cones, grouped by output.
    """
    R = np.asarray(R, dtype=np.float64)
    c = np.minimum(np.asarray(half_angle, dtype=np.float64), np.pi)
    n = R.shape[0]
    if query == "kdtree":
        tree = cKDTree(pixel_directions(height, width).reshape(-1, 3)) if tree is None else tree
        chord = np.where(c >= np.pi, 2.0 + 1e-9, 2.0 * np.sin(c / 2.0) + 1e-9)
        lists = tree.query_ball_point(R, chord, return_sorted=False)
        counts = np.fromiter((len(x) for x in lists), dtype=np.int64, count=n)
        pixel = np.fromiter((i for x in lists for i in x), dtype=np.int64, count=int(counts.sum()))
        return np.repeat(np.arange(n), counts), pixel
    if query != "rows":
        raise BadInputError(None, f"cone query must be one of {QUERIES}, got {query!r}")
    theta_r = np.arccos(np.clip(R[:, 2], -1.0, 1.0))
    phi_r = np.mod(np.arctan2(R[:, 1], R[:, 0]), 2.0 * np.pi)
    scale = height / np.pi
    row_lo = np.clip(np.ceil((theta_r - c) * scale - 0.5 - 1e-9), 0, height).astype(np.int64)
    row_hi = np.clip(np.floor((theta_r + c) * scale - 0.5 + 1e-9), -1, height - 1).astype(np.int64)
    nrows = np.maximum(row_hi - row_lo + 1, 0)
    out_of_row, row = _ranges(row_lo, nrows)
    theta = (row + 0.5) / scale
    a = np.cos(theta) * np.cos(theta_r[out_of_row])
    b = np.sin(theta) * np.sin(theta_r[out_of_row])
    cos_c = np.cos(c[out_of_row])
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(b > 1e-300, (cos_c - a) / np.where(b > 1e-300, b, 1.0), np.where(a >= cos_c - 1e-12, -2.0, 2.0))
    delta = np.arccos(np.clip(t, -1.0, 1.0)) + 1e-9
    cols = width / (2.0 * np.pi)
    col_lo = np.ceil((phi_r[out_of_row] - delta) * cols - 0.5).astype(np.int64)
    col_hi = np.floor((phi_r[out_of_row] + delta) * cols - 0.5).astype(np.int64)
    count = np.clip(col_hi - col_lo + 1, 0, width)
    whole = (t <= -1.0) | (count >= width)
    count = np.where(t > 1.0 + 1e-12, 0, np.where(whole, width, count))
    col_lo = np.where(whole, 0, col_lo)
    run, col = _ranges(col_lo, count)
    return out_of_row[run], row[run] * width + np.mod(col, width)


@dataclass(frozen=True, eq=False)
class LobeTruncatedSum:
    """The lobe-truncated angular sum for one (environment, BRDF), ready to evaluate.

    Attributes
    ----------
    brdf
        The BRDF.
    cones
        Its :class:`LobeCones`.
    shape
        (H, W) of the environment map.
    emitted
        (H·W, 3) float64 L_p Ω_p of every pixel (radiance × exact solid angle; 0 for black
        pixels, which are skipped).
    directions
        (H·W, 3) float64 unit directions of the pixel centres (``pixel_directions``).
    lit
        (H·W,) bool: the pixels with some non-zero radiance (the only ones summed).
    flux
        (3,) Σ_p L_p Ω_p over the whole map (for the bound on the dropped part).
    query
        The cone query (:func:`cone_pixels`).
    tree
        ``cKDTree`` on the pixel directions (``query="kdtree"`` only, else None).
    seconds
        Time to set it up (cone table, pixel arrays, tree), seconds.
    """

    brdf: BRDF
    cones: LobeCones
    shape: tuple[int, int]
    emitted: np.ndarray
    directions: np.ndarray
    lit: np.ndarray
    flux: np.ndarray
    query: str = "rows"
    tree: Any = None
    seconds: float = float("nan")

    @property
    def nbytes(self) -> int:
        """Bytes of the arrays it keeps: L Ω and the unit direction of every pixel, the
        lit-pixel mask, and a KD-tree's copy of the points and index permutation (its nodes
        are not counted)."""
        tree = 0 if self.tree is None else int(self.tree.data.nbytes + self.tree.indices.nbytes)
        return int(self.emitted.nbytes + self.directions.nbytes + self.lit.nbytes + tree)

    def radiance(self, R: np.ndarray, V: np.ndarray) -> np.ndarray:
        """B(R, V) (n, 3) float64 for unit R, V (n, 3) in the global z-up frame."""
        return self.radiance_and_bound(R, V)[0]

    def radiance_and_bound(
        self, R: np.ndarray, V: np.ndarray, *, chunk_terms: int = 1 << 20
    ) -> tuple[np.ndarray, np.ndarray, int]:
        """B(R, V), the bound on what the truncation dropped, and the number of terms summed.

        Parameters
        ----------
        R, V
            Unit reflection and view directions (n, 3), global z-up frame.
        chunk_terms
            About how many (output, pixel) terms to evaluate at once (~250 bytes each).

        Returns
        -------
        radiance
            (n, 3) float64.
        bound
            (n, 3) float64: threshold × peak(θ_v) × the flux of the pixels outside the cone,
            an upper bound on |reference − radiance| per pair and channel (up to the grid of
            :func:`lobe_cones`): every dropped pixel has ρ̂ below threshold × peak. Relative to B
            that is ~``threshold`` for smooth lighting and can be much more for a bright source
            just outside a sharp lobe.
        terms
            The number of (output, lit pixel) terms summed; the brute-force reference sums
            n × (lit pixels).
        """
        R = np.atleast_2d(np.asarray(R, dtype=np.float64))
        V = np.atleast_2d(np.asarray(V, dtype=np.float64))
        if R.shape != V.shape or R.ndim != 2 or R.shape[1] != 3:
            raise BadInputError(None, f"R and V must have the same shape (n, 3), got {R.shape} and {V.shape}")
        n = R.shape[0]
        height, width = self.shape
        N = R + V
        norm = np.linalg.norm(N, axis=1)
        cos_tv = np.clip(np.einsum("ij,ij->i", N, V) / np.where(norm > 0, norm, 1.0), -1.0, 1.0)
        angle, peak = self.cones.at(np.arccos(cos_tv))
        frames = local_frames(N)
        V_loc = np.einsum("kij,kj->ki", frames, V)
        out = np.zeros((n, 3))
        inside = np.zeros((n, 3))
        terms = 0
        # blocks of outputs whose expected number of terms (cone area × pixels) is about chunk_terms
        expected = np.cumsum((1.0 - np.cos(np.minimum(angle, np.pi))) / 2.0 * height * width + width)
        cuts = np.searchsorted(expected, np.arange(chunk_terms, expected[-1], chunk_terms), side="right")
        edges = np.unique(np.concatenate([[0], cuts, [n]]))
        for a, b in zip(edges[:-1], edges[1:], strict=True):
            owner, pixel = cone_pixels(R[a:b], angle[a:b], height, width, query=self.query, tree=self.tree)
            keep = self.lit[pixel]
            owner, pixel = owner[keep], pixel[keep]
            terms += int(owner.size)
            if owner.size == 0:
                continue
            # np.take along axis 0: numpy's (n, 3)[index] path is several times slower
            L_loc = np.einsum("tij,tj->ti", np.take(frames[a:b], owner, axis=0),
                              np.take(self.directions, pixel, axis=0))
            rho = _rho_hat(self.brdf, L_loc, np.take(V_loc[a:b], owner, axis=0))
            emitted = np.take(self.emitted, pixel, axis=0)
            for ch in range(3):
                out[a:b, ch] = np.bincount(owner, weights=rho[:, ch] * emitted[:, ch], minlength=b - a)
                inside[a:b, ch] = np.bincount(owner, weights=emitted[:, ch], minlength=b - a)
        outside = np.clip(self.flux[None, :] - inside, 0.0, None)
        return out, self.cones.threshold * peak * outside, terms

    def view_map(self, view: np.ndarray, height: int, width: int) -> np.ndarray:
        """Distant-viewer map: B(R, V) at every pixel centre R of an H × W lat-long grid for
        one view direction (float64 (H, W, 3)), like :func:`~shrmkit.analysis.reference.reference_map`."""
        R = pixel_directions(height, width).reshape(-1, 3)
        V = np.broadcast_to(np.asarray(view, float) / np.linalg.norm(view), R.shape)
        return self.radiance(R, np.ascontiguousarray(V)).reshape(height, width, 3)


def lobe_truncated_sum(
    env: object, brdf: BRDF, *, threshold: float = DEFAULT_THRESHOLD, cones: LobeCones | None = None,
    query: str = "rows",
) -> LobeTruncatedSum:
    """Set up the lobe-truncated sum of ``env`` (an EnvironmentMap or an (H, W, 3) array)
    with ``brdf``: the cone table (:func:`lobe_cones`, or ``cones`` when given), the pixels'
    L Ω and directions (the reference's conventions), and for ``query="kdtree"`` a KD-tree on
    the unit pixel directions. Black pixels are skipped (exact, as in the reference)."""
    t0 = time.perf_counter()
    if query not in QUERIES:
        raise BadInputError(None, f"cone query must be one of {QUERIES}, got {query!r}")
    radiance = np.asarray(getattr(env, "radiance", env), dtype=np.float64)
    if radiance.ndim != 3 or radiance.shape[2] != 3:
        raise BadInputError(None, f"environment radiance must have shape (H, W, 3), got {radiance.shape}")
    height, width = radiance.shape[:2]
    cones = lobe_cones(brdf, threshold=threshold) if cones is None else cones
    directions = pixel_directions(height, width).reshape(-1, 3)
    emitted = radiance.reshape(-1, 3) * np.repeat(row_solid_angles(height, width), width)[:, None]
    lit = np.any(emitted != 0, axis=1)
    tree = cKDTree(directions) if query == "kdtree" else None
    return LobeTruncatedSum(
        brdf=brdf, cones=cones, shape=(height, width), emitted=emitted, directions=directions, lit=lit,
        flux=emitted.sum(axis=0), query=query, tree=tree, seconds=time.perf_counter() - t0,
    )


def lobe_truncated_radiance(
    env: object, brdf: BRDF, R: np.ndarray, V: np.ndarray, *, threshold: float = DEFAULT_THRESHOLD,
    query: str = "rows",
) -> np.ndarray:
    """B(R, V) (n, 3) by the lobe-truncated sum (set up, then evaluated once)."""
    return lobe_truncated_sum(env, brdf, threshold=threshold, query=query).radiance(R, V)
