"""The regular icosahedron as a set of view directions, and spherical barycentric weights.

[Cabral99] §4 prefilter one radiance environment map per vertex of an
icosahedron (12 views) and blend, for a new view v, the maps of the three vertices of the
face containing v with *spherical barycentric* weights: the weight of vertex i is the
spherical excess (area) of the sub-triangle spanned by v and the two other vertices,
divided by the area of the face. Inside a face the three sub-triangles tile it, so the
weights are non-negative and sum to 1; at a vertex the weight is 1 on that vertex alone.

Spherical excess by the Van Oosterom–Strackee formula
tan(E/2) = a·(b×c) / (1 + a·b + b·c + c·a) (signed; positive for a counter-clockwise
triangle seen from outside).
"""

from __future__ import annotations

import numpy as np

__all__ = ["icosahedron", "spherical_excess", "barycentric_weights", "containing_face"]


def icosahedron() -> tuple[np.ndarray, np.ndarray]:
    """Unit vertices (12, 3) and faces (20, 3), faces counter-clockwise seen from outside.

    Vertices are the cyclic permutations of (0, ±1, ±φ) / sqrt(1 + φ²), φ the golden ratio,
    so ±z is not a vertex (no view sits exactly at a pole of the lat-long maps).
    """
    phi = (1.0 + np.sqrt(5.0)) / 2.0
    v = []
    for a in (-1.0, 1.0):
        for b in (-phi, phi):
            v += [(0.0, a, b), (a, b, 0.0), (b, 0.0, a)]
    verts = np.array(v) / np.sqrt(1.0 + phi * phi)
    # faces: triples of mutually adjacent vertices (edge length 2/sqrt(1+φ²))
    d = np.linalg.norm(verts[:, None] - verts[None], axis=-1)
    edge = d[d > 1e-9].min()
    adj = np.abs(d - edge) < 1e-9
    faces = []
    for i in range(12):
        for j in range(i + 1, 12):
            for k in range(j + 1, 12):
                if adj[i, j] and adj[j, k] and adj[i, k]:
                    if np.dot(np.cross(verts[j] - verts[i], verts[k] - verts[i]), verts[i]) < 0:
                        j_, k_ = k, j
                    else:
                        j_, k_ = j, k
                    faces.append((i, j_, k_))
    return verts, np.array(faces, dtype=np.int64)


def spherical_excess(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Signed spherical excess (area on the unit sphere) of triangles (a, b, c), shape (...)."""
    triple = np.einsum("...k,...k->...", a, np.cross(b, c))
    denom = 1.0 + np.einsum("...k,...k->...", a, b) + np.einsum("...k,...k->...", b, c) + np.einsum(
        "...k,...k->...", c, a
    )
    return 2.0 * np.arctan2(triple, denom)


def containing_face(v: np.ndarray, verts: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Index of the face containing each unit vector v (n, 3) (largest minimum signed sub-area)."""
    v = np.atleast_2d(v)
    a, b, c = verts[faces[:, 0]], verts[faces[:, 1]], verts[faces[:, 2]]  # (20, 3)
    # v inside (a, b, c) <=> v·(a×b), v·(b×c), v·(c×a) all >= 0 (ccw faces)
    s = np.stack([v @ np.cross(a, b).T, v @ np.cross(b, c).T, v @ np.cross(c, a).T], axis=-1)  # (n, 20, 3)
    return np.argmax(s.min(axis=-1), axis=1)


def barycentric_weights(
    v: np.ndarray, verts: np.ndarray | None = None, faces: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Spherical barycentric weights of the containing face (Cabral et al. 1999 §4).

    Parameters
    ----------
    v
        Unit view directions (n, 3) (or (3,)).
    verts, faces
        The triangulation (default :func:`icosahedron`).

    Returns
    -------
    index
        int (n, 3): the three vertex indices of the face containing v.
    weight
        float (n, 3): w_i = E(v, b, c) / E(a, b, c) and cyclically, E the spherical excess;
        non-negative and summing to 1 inside the face (up to rounding on its edges: the
        values are returned as computed, not clipped or renormalized).
    """
    if verts is None or faces is None:
        verts, faces = icosahedron()
    v = np.atleast_2d(np.asarray(v, dtype=np.float64))
    v = v / np.linalg.norm(v, axis=-1, keepdims=True)
    f = faces[containing_face(v, verts, faces)]
    a, b, c = verts[f[:, 0]], verts[f[:, 1]], verts[f[:, 2]]
    total = spherical_excess(a, b, c)
    w = np.stack([spherical_excess(v, b, c), spherical_excess(a, v, c), spherical_excess(a, b, v)], axis=-1)
    return f, w / total[:, None]
