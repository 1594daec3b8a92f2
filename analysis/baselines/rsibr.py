"""Reflection Space Image Based Rendering [Cabral99] as an SHRM comparator (the ``rsibr`` method).

Cabral et al. prefilter one *radiance environment
map* per sample view v_i — the 12 vertices of an icosahedron — and render a new view v by
blending the maps of the three vertices of the face containing v with spherical
barycentric weights (:mod:`.icosahedron`), after warping each map into reflection space.

Our maps and the warp, precisely
--------------------------------
Map i is stored indexed by the **reflection direction** R on the lat-long grid of DESIGN §2:

    M_i(R) = B(R, v_i),    the radiance leaving a surface with normal n = normalize(R + v_i)
                           toward the distant viewer v_i ([RH02] eq. 12 with V = v_i).

Cabral's maps are images of a sphere seen from v_i, i.e. indexed by the **normal** n. Their
reflection-space warp looks map i up, for a pixel of the new view with reflection r, at the
normal that reflects v_i into r: n_i = normalize(v_i + r), the half-angle direction between
v_i and r (:func:`warp_normal`). Because our map is indexed by the reflection direction of
v_i about that very normal — 2(n_i·v_i) n_i − v_i = r — the warped lookup of map i is
M_i(r): the same reflection direction r for all three maps. The reconstruction is

    B_rsibr(r, v) = Σ_{i ∈ face(v)} w_i(v) M_i(r),   Σ w_i = 1, w_i ≥ 0.

At v = v_i it is M_i(r) exactly (bilinear interpolation of the map only). Between views it
replaces B(r, v) by B(r, v_i): wrong wherever the lobe's shape depends on the view (the
Fresnel and shadowing rise and the off-specular shift near grazing).

For a distant viewer the per-frame work is one weighted sum of three maps
(:meth:`RSIBRMaps.view_map`), the same kind of per-frame map as [RH02] eq. 12.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ...brdf_io.latlong import bilinear_lookup, pixel_directions
from ..reference import reference_map
from .icosahedron import barycentric_weights, icosahedron

__all__ = ["RSIBRMaps", "rsibr_from_shrm", "rsibr_reference", "warp_normal"]


def warp_normal(r: np.ndarray, v_i: np.ndarray) -> np.ndarray:
    """Normal n_i = normalize(v_i + r) that reflects the sample view v_i into r (Cabral's warp).

    Undefined (returned as NaN) where r = −v_i, the grazing singularity of map i.
    """
    s = np.asarray(r, dtype=np.float64) + np.asarray(v_i, dtype=np.float64)
    with np.errstate(invalid="ignore", divide="ignore"):
        return s / np.linalg.norm(s, axis=-1, keepdims=True)


@dataclass(frozen=True, eq=False)
class RSIBRMaps:
    """Twelve radiance environment maps at the icosahedron's vertices.

    Attributes
    ----------
    views
        (12, 3) unit sample view directions v_i (z-up frame).
    faces
        (20, 3) icosahedron faces (indices into ``views``).
    maps
        float32 (12, H, W, 3): M_i(R) = B(R, v_i) on the lat-long grid of DESIGN §2.
    meta
        Provenance: ``source`` ("shrm" or "reference") and ``seconds`` to build the maps.
    """

    views: np.ndarray
    faces: np.ndarray
    maps: np.ndarray
    meta: dict[str, Any] = field(default_factory=dict)

    @property
    def nbytes(self) -> int:
        """Storage of the twelve float32 maps in bytes."""
        return int(self.maps.nbytes)

    def weights(self, V: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(indices (n, 3), spherical barycentric weights (n, 3)) of the face containing each V."""
        return barycentric_weights(V, self.views, self.faces)

    def radiance(self, R: np.ndarray, V: np.ndarray) -> np.ndarray:
        """B_rsibr(R, V) = Σ_i w_i(V) M_i(R) over the face containing V, shape (n, 3)."""
        R = np.atleast_2d(np.asarray(R, dtype=np.float64))
        idx, w = self.weights(V)
        out = np.zeros((R.shape[0], 3))
        for k in range(3):
            for i in np.unique(idx[:, k]):
                sel = idx[:, k] == i
                out[sel] += w[sel, k, None] * bilinear_lookup(self.maps[i], R[sel])
        return out

    def view_map(self, view: np.ndarray) -> np.ndarray:
        """Distant-viewer map Σ w_i(v) M_i for one view direction v, float32 (H, W, 3)."""
        idx, w = self.weights(np.asarray(view, dtype=np.float64).reshape(1, 3))
        out = w[0, 0].astype(np.float32) * self.maps[idx[0, 0]]
        out += w[0, 1].astype(np.float32) * self.maps[idx[0, 1]]
        out += w[0, 2].astype(np.float32) * self.maps[idx[0, 2]]
        return out


def rsibr_from_shrm(shrm: Any) -> RSIBRMaps:
    """The twelve maps from an SHRM: M_i = Σ B̃_pq Y^r_pq(v_i) (RH02 eq. 12), on the SHRM's grid,
    plus, when the SHRM has explicit lights (DESIGN §5a), their reflection at each pixel's R
    (Cabral's maps hold the whole radiance: they have no other place for the lights)."""
    views, faces = icosahedron()
    t0 = time.perf_counter()
    maps = np.stack([shrm.view_map(v) for v in views]).astype(np.float32)
    if getattr(shrm, "has_lights", False):
        R = pixel_directions(shrm.height, shrm.width).reshape(-1, 3)
        for i, v in enumerate(views):
            V = np.broadcast_to(np.asarray(v, dtype=np.float64) / np.linalg.norm(v), R.shape)
            maps[i] += shrm.light_radiance(R, V).reshape(maps.shape[1:]).astype(np.float32)
    seconds = time.perf_counter() - t0
    return RSIBRMaps(views, faces, maps, {"source": "shrm", "seconds": seconds})


def rsibr_reference(env: Any, brdf: Any, height: int, width: int | None = None) -> RSIBRMaps:
    """The twelve maps by brute-force angular integration (the original method's cost).

    Each map is :func:`~shrmkit.analysis.reference.reference_map` at v_i: O(H W S_L²)
    BRDF evaluations per map (RH02 Table 3).
    """
    views, faces = icosahedron()
    width = 2 * height if width is None else int(width)
    t0 = time.perf_counter()
    maps = np.stack([reference_map(env, brdf, v, height, width) for v in views]).astype(np.float32)
    seconds = time.perf_counter() - t0
    return RSIBRMaps(views, faces, maps, {"source": "reference", "seconds": seconds})
