"""Triangle meshes for rendering: file loading (trimesh), validation, normalization, built-ins.

:func:`load_mesh` accepts a path (OBJ, PLY, STL, OFF, GLB/GLTF; scenes are flattened with
their node transforms) or a built-in spec:

- ``builtin:sphere[:subdivisions=6]`` — icosphere (subdivision 6: 81 920 triangles) with
  exact normals (the positions);
- ``builtin:torus[:R=1,r=0.4,segments=256,sides=64]`` — a torus about the z axis;
- ``builtin:torus-knot[:p=2,q=3,segments=1024,sides=48,r=0.35]`` — a tube around a (p, q)
  torus knot (2·segments·sides triangles).

Every mesh is checked (non-empty, finite vertices, face indices in range, no degenerate
faces) and then centred at its bounding-box centre and scaled so that its bounding sphere
about that centre has radius 1. Vertex normals come from the file when present and valid,
otherwise they are the area-weighted averages of the face normals.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import trimesh

from ..brdf_io.errors import BadInputError

__all__ = ["Mesh", "load_mesh", "make_mesh", "builtin_mesh", "BUILTINS", "MESH_SUFFIXES"]

MESH_SUFFIXES = (".obj", ".ply", ".stl", ".off", ".glb", ".gltf")
BUILTINS = ("sphere", "torus", "torus-knot")


@dataclass(frozen=True, eq=False)
class Mesh:
    """A triangle mesh in the z-up world frame.

    Attributes
    ----------
    vertices
        float64 (n, 3).
    faces
        int64 (m, 3), counter-clockwise seen from outside.
    normals
        float64 (n, 3) unit vertex normals.
    name
        The path or spec it came from.
    """

    vertices: np.ndarray
    faces: np.ndarray
    normals: np.ndarray
    name: str = ""

    @property
    def n_triangles(self) -> int:
        return int(self.faces.shape[0])

    def transformed(self, *, scale: float = 1.0, translate: np.ndarray = (0.0, 0.0, 0.0)) -> Mesh:
        """A copy scaled uniformly about the origin and translated (placing objects in a scene)."""
        t = np.asarray(translate, dtype=np.float64).reshape(3)
        return Mesh(self.vertices * float(scale) + t, self.faces, self.normals, self.name)


def _face_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Unnormalized face normals (length = 2 × area)."""
    a, b, c = (vertices[faces[:, k]] for k in range(3))
    return np.cross(b - a, c - a)


def _vertex_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    fn = _face_normals(vertices, faces)
    out = np.zeros_like(vertices)
    for k in range(3):
        np.add.at(out, faces[:, k], fn)
    return out


def make_mesh(
    vertices: np.ndarray,
    faces: np.ndarray,
    normals: np.ndarray | None = None,
    *,
    name: str = "",
    normalize: bool = True,
) -> Mesh:
    """Validate arrays and build a :class:`Mesh` (centred and scaled to a unit bounding sphere).

    Raises
    ------
    BadInputError
        Empty mesh, non-finite vertices, face indices out of range, degenerate faces
        (repeated index or zero area), naming ``name`` and the offending count.
    """
    v = np.asarray(vertices, dtype=np.float64)
    f = np.asarray(faces)
    if v.ndim != 2 or v.shape[1] != 3 or v.shape[0] == 0:
        raise BadInputError(name, f"mesh has no vertices (vertex array shape {v.shape})")
    if f.ndim != 2 or f.shape[1] != 3 or f.shape[0] == 0:
        raise BadInputError(name, f"mesh has no triangles (face array shape {f.shape})")
    if not np.issubdtype(f.dtype, np.integer):
        raise BadInputError(name, f"face indices must be integers, got {f.dtype}")
    f = f.astype(np.int64)
    bad = ~np.all(np.isfinite(v), axis=1)
    if bad.any():
        raise BadInputError(name, f"{int(bad.sum())} of {len(v)} vertices are not finite (NaN or Inf)")
    if f.min() < 0 or f.max() >= len(v):
        raise BadInputError(name, f"face indices out of range [0, {len(v)}): min {f.min()}, max {f.max()}")
    repeated = (f[:, 0] == f[:, 1]) | (f[:, 1] == f[:, 2]) | (f[:, 0] == f[:, 2])
    extent = float(np.max(v.max(axis=0) - v.min(axis=0)))
    if extent == 0.0:
        raise BadInputError(name, "all vertices coincide (zero-size mesh)")
    area2 = np.linalg.norm(_face_normals(v, f), axis=1)
    zero_area = area2 <= 1e-12 * extent * extent
    degenerate = repeated | zero_area
    if degenerate.any():
        first = int(np.flatnonzero(degenerate)[0])
        raise BadInputError(
            name, f"{int(degenerate.sum())} of {len(f)} faces are degenerate (zero area), first is face {first}"
        )
    n = None if normals is None else np.asarray(normals, dtype=np.float64)
    if n is None or n.shape != v.shape or not np.all(np.isfinite(n)):
        n = _vertex_normals(v, f)
    length = np.linalg.norm(n, axis=1)
    weak = length <= 1e-12
    if weak.any():  # e.g. file normals that are zero: fall back to face averages there
        n[weak] = _vertex_normals(v, f)[weak]
        length = np.linalg.norm(n, axis=1)
        if np.any(length <= 1e-300):
            length = np.where(length <= 1e-300, 1.0, length)
    n = n / length[:, None]
    if normalize:
        center = 0.5 * (v.min(axis=0) + v.max(axis=0))
        radius = float(np.max(np.linalg.norm(v - center, axis=1)))
        v = (v - center) / radius
    return Mesh(v, f, n, name)


def _parse_params(spec: str, text: str, allowed: dict[str, type]) -> dict[str, float]:
    out: dict[str, float] = {}
    if not text:
        return out
    for item in text.split(","):
        key, sep, value = item.partition("=")
        key = key.strip()
        if not sep or key not in allowed:
            raise BadInputError(spec, f"unknown parameter {item!r}; allowed: {', '.join(allowed)}")
        try:
            out[key] = allowed[key](value)
        except ValueError:
            raise BadInputError(spec, f"parameter {key}={value!r} is not a {allowed[key].__name__}") from None
        if not np.isfinite(out[key]) or out[key] <= 0:
            raise BadInputError(spec, f"parameter {key}={value!r} must be positive")
    return out


def _icosphere(subdivisions: int) -> tuple[np.ndarray, np.ndarray]:
    ico = trimesh.creation.icosphere(subdivisions=subdivisions, radius=1.0)
    v = np.asarray(ico.vertices, dtype=np.float64)
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    return v, np.asarray(ico.faces, dtype=np.int64)


def _tube(curve: np.ndarray, tangent: np.ndarray, r: float, sides: int) -> tuple[np.ndarray, np.ndarray]:
    """A closed tube of radius r around a closed curve (segments, 3) with exact normals."""
    seg = len(curve)
    t = tangent / np.linalg.norm(tangent, axis=1, keepdims=True)
    # parallel transport of a normal along the closed curve, then the closure twist spread
    # evenly over the segments, so the tube has no sudden twist
    ref = np.array([0.0, 0.0, 1.0]) if abs(t[0, 2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    n1 = np.empty_like(t)
    cur = np.cross(t[0], ref)
    for k in range(seg):
        cur = cur - np.dot(cur, t[k]) * t[k]
        cur /= np.linalg.norm(cur)
        n1[k] = cur
    end = n1[-1] - np.dot(n1[-1], t[0]) * t[0]
    end /= np.linalg.norm(end)
    twist = np.arctan2(np.dot(np.cross(n1[0], end), t[0]), np.dot(n1[0], end))
    n2 = np.cross(t, n1)
    # rotate frame k by -twist * k / seg so that frame seg coincides with frame 0
    a = -twist * np.arange(seg) / seg
    n1, n2 = np.cos(a)[:, None] * n1 + np.sin(a)[:, None] * n2, -np.sin(a)[:, None] * n1 + np.cos(a)[:, None] * n2
    ang = 2.0 * np.pi * np.arange(sides) / sides
    normals = np.cos(ang)[None, :, None] * n1[:, None, :] + np.sin(ang)[None, :, None] * n2[:, None, :]
    verts = curve[:, None, :] + r * normals
    i = np.arange(seg)[:, None]
    j = np.arange(sides)[None, :]
    a = i * sides + j
    b = ((i + 1) % seg) * sides + j
    c = ((i + 1) % seg) * sides + (j + 1) % sides
    d = i * sides + (j + 1) % sides
    faces = np.concatenate([np.stack([a, c, b], -1).reshape(-1, 3), np.stack([a, d, c], -1).reshape(-1, 3)])
    return verts.reshape(-1, 3), faces, normals.reshape(-1, 3)


def builtin_mesh(spec: str) -> Mesh:
    """A built-in mesh from ``builtin:NAME[:key=value,...]`` (see module docstring)."""
    rest = spec[len("builtin:"):]
    name, _, params = rest.partition(":")
    if name == "sphere":
        p = _parse_params(spec, params, {"subdivisions": int})
        sub = int(p.get("subdivisions", 6))
        if sub > 9:
            raise BadInputError(spec, f"subdivisions={sub} is too fine (at most 9)")
        v, f = _icosphere(sub)
        return make_mesh(v, f, v.copy(), name=spec)
    if name == "torus":
        p = _parse_params(spec, params, {"R": float, "r": float, "segments": int, "sides": int})
        big, small = p.get("R", 1.0), p.get("r", 0.4)
        seg, sides = int(p.get("segments", 256)), int(p.get("sides", 64))
        s = 2.0 * np.pi * np.arange(seg) / seg
        curve = np.stack([big * np.cos(s), big * np.sin(s), np.zeros_like(s)], -1)
        tangent = np.stack([-np.sin(s), np.cos(s), np.zeros_like(s)], -1)
        v, f, n = _tube(curve, tangent, small, sides)
        return make_mesh(v, f, n, name=spec)
    if name == "torus-knot":
        p = _parse_params(spec, params, {"p": int, "q": int, "segments": int, "sides": int, "r": float})
        pp, qq = int(p.get("p", 2)), int(p.get("q", 3))
        seg, sides, r = int(p.get("segments", 1024)), int(p.get("sides", 48)), p.get("r", 0.35)
        s = 2.0 * np.pi * np.arange(seg) / seg
        rad = 2.0 + np.cos(qq * s)
        curve = np.stack([rad * np.cos(pp * s), rad * np.sin(pp * s), -np.sin(qq * s)], -1)
        drad = -qq * np.sin(qq * s)
        tangent = np.stack(
            [
                drad * np.cos(pp * s) - pp * rad * np.sin(pp * s),
                drad * np.sin(pp * s) + pp * rad * np.cos(pp * s),
                -qq * np.cos(qq * s),
            ],
            -1,
        )
        v, f, n = _tube(curve, tangent, r, sides)
        return make_mesh(v, f, n, name=spec)
    raise BadInputError(spec, f"unknown built-in mesh {name!r}; known: {', '.join(BUILTINS)}")


def load_mesh(source: str | Path) -> Mesh:
    """Load a mesh file or built-in spec, validated and normalized to the unit bounding sphere.

    Raises
    ------
    BadInputError
        Unknown spec, missing/unreadable file, unsupported extension, no triangles, or any
        problem :func:`make_mesh` detects.
    """
    text = str(source)
    if text.startswith("builtin:"):
        return builtin_mesh(text)
    path = Path(text)
    suffix = path.suffix.lower()
    if suffix not in MESH_SUFFIXES:
        raise BadInputError(path, f"unsupported mesh extension {suffix!r}; use one of {', '.join(MESH_SUFFIXES)}")
    if not path.is_file():
        raise BadInputError(path, "no such file")
    try:
        # process=False: keep the data as written (trimesh would otherwise silently drop
        # NaN vertices and degenerate faces, which we want to report)
        loaded = trimesh.load(str(path), process=False)
    except Exception as err:  # trimesh raises many types for malformed files
        raise BadInputError(path, f"cannot read mesh: {type(err).__name__}: {err}") from None
    if isinstance(loaded, trimesh.Scene):
        geoms = [g for g in loaded.dump() if isinstance(g, trimesh.Trimesh) and len(g.faces)]
        if not geoms:
            raise BadInputError(path, "file holds no triangle geometry")
        parts_v, parts_f, parts_n, offset = [], [], [], 0
        for g in geoms:  # dump() has already applied each node's transform
            parts_v.append(np.asarray(g.vertices))
            parts_f.append(np.asarray(g.faces) + offset)
            parts_n.append(_file_normals(g))
            offset += len(g.vertices)
        v, f = np.concatenate(parts_v), np.concatenate(parts_f)
        n = None if any(x is None for x in parts_n) else np.concatenate(parts_n)
    elif isinstance(loaded, trimesh.Trimesh):
        v, f, n = np.asarray(loaded.vertices), np.asarray(loaded.faces), _file_normals(loaded)
    else:
        raise BadInputError(path, f"file holds no triangle mesh (got {type(loaded).__name__})")
    if len(f) == 0:
        raise BadInputError(path, "mesh has no triangles")
    return make_mesh(v, f, n, name=str(path))


def _file_normals(mesh) -> np.ndarray | None:
    """Vertex normals stored in the file, or None (trimesh keeps them in its cache)."""
    cached = mesh._cache.cache.get("vertex_normals") if hasattr(mesh, "_cache") else None
    if cached is None or np.shape(cached) != np.shape(mesh.vertices):
        return None
    return np.asarray(cached, dtype=np.float64)
