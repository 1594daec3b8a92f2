"""Whether a mesh's back faces may be culled: closed, consistently wound and outward oriented
(:func:`closed_outward`). Public through :mod:`shrmkit.render.vtk_renderer`.
"""

from __future__ import annotations

import numpy as np

from ..analysis.components import connected_labels
from .mesh import Mesh


def closed_outward(mesh: Mesh) -> bool:
    """Whether ``mesh`` is a closed surface whose faces all wind counter-clockwise seen from outside.

    True when every directed edge (a → b) of the faces occurs exactly once and its reverse
    (b → a) exactly once (closed and consistently oriented: each edge is shared by two faces
    that traverse it in opposite directions), and every connected piece encloses a positive
    signed volume Σ a·(b × c)/6 (outward orientation). For such a mesh, seen from outside its
    bounding sphere, every back face lies behind a front face of the same piece, so culling
    back faces changes no pixel. Meshes with open borders, non-manifold or inconsistently
    wound edges, split seam vertices, or a cavity (a piece with inward orientation) give False.
    """
    faces = np.asarray(mesh.faces, dtype=np.int64)
    n = len(mesh.vertices)
    a = faces.reshape(-1)
    b = faces[:, [1, 2, 0]].reshape(-1)
    directed = np.sort(a * n + b)
    if np.any(directed[1:] == directed[:-1]) or not np.array_equal(directed, np.sort(b * n + a)):
        return False
    label = connected_labels(a, b, n)
    v = mesh.vertices
    volume6 = np.einsum("ij,ij->i", v[faces[:, 0]], np.cross(v[faces[:, 1]], v[faces[:, 2]]))
    return bool(np.all(np.bincount(label[faces[:, 0]], weights=volume6) > 0.0))
