"""Triangle meshes for rendering: file loading (trimesh), validation, normalization, built-ins.

:func:`load_mesh` accepts a path (OBJ, PLY, STL, OFF, GLB/GLTF; scenes are flattened with
their node transforms) or a built-in spec:

- ``builtin:sphere[:subdivisions=6]`` — icosphere (subdivision 6: 81 920 triangles) with
  exact normals (the positions);
- ``builtin:torus[:R=1,r=0.4,segments=256,sides=64]`` — a torus about the z axis;
- ``builtin:torus-knot[:p=2,q=3,segments=1024,sides=48,r=0.35]`` — a tube around a (p, q)
  torus knot (2·segments·sides triangles).

Every mesh is checked (at least one triangle, finite vertices, face indices in range) and
cleaned: degenerate faces (a repeated index or zero area) are dropped with a
:class:`MeshRepairWarning` that counts them (refused only when no face is left), and so are
vertices no face references (stray points an editor left behind), so that only the drawn
surface decides the placement. The mesh is then centred at the bounding-box centre of its
vertices and scaled so that its bounding sphere about that centre has radius 1. Vertex
normals come from the file when present and valid, otherwise they are the area-weighted
averages of the face normals.

Files are opened only when they are regular files within
:func:`~shrmkit.brdf_io.limits.max_file_bytes` (a FIFO or a link to ``/dev/zero`` named
``x.ply`` is refused before trimesh sees it; so are such files referenced from the mesh,
e.g. an OBJ's ``mtllib``); a PLY header's declared element counts are checked against
:func:`~shrmkit.brdf_io.limits.max_elements` and the bytes the file holds before anything is
parsed. The rules are in ``data_specs/render_outputs.md`` (Meshes).
"""

from __future__ import annotations

import functools
import re
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from ..brdf_io import limits
from ..brdf_io.errors import BadInputError

__all__ = [
    "Mesh",
    "MeshRepairWarning",
    "load_mesh",
    "make_mesh",
    "builtin_mesh",
    "BUILTINS",
    "MESH_SUFFIXES",
]

MESH_SUFFIXES = (".obj", ".ply", ".stl", ".off", ".glb", ".gltf")
BUILTINS = ("sphere", "torus", "torus-knot")


class MeshRepairWarning(UserWarning):
    """A mesh was usable after dropping some of its faces (degenerate triangles)."""


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

    def bounding_sphere(self) -> tuple[np.ndarray, float]:
        """(centre (3,), radius): :func:`bounding_sphere` of the vertices."""
        return bounding_sphere(self.vertices)

    def transformed(self, *, scale: float = 1.0, translate: ArrayLike = (0.0, 0.0, 0.0)) -> Mesh:
        """A copy scaled uniformly about the origin and translated (placing objects in a scene)."""
        t = np.asarray(translate, dtype=np.float64).reshape(3)
        return Mesh(self.vertices * float(scale) + t, self.faces, self.normals, self.name)


def bounding_sphere(vertices: np.ndarray) -> tuple[np.ndarray, float]:
    """The sphere about the centre of the vertices' box through the farthest vertex: (centre (3,),
    radius). What framing, culling and a render's cone of views all take as a mesh's extent."""
    v = np.asarray(vertices, dtype=np.float64)
    centre = 0.5 * (v.min(axis=0) + v.max(axis=0))
    return centre, float(np.max(np.linalg.norm(v - centre, axis=1)))


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
    """Validate and clean arrays and build a :class:`Mesh` (centred, unit bounding sphere).

    Degenerate faces (a repeated index, or an area at most 10⁻¹² × the squared extent of the
    referenced vertices) are dropped with a :class:`MeshRepairWarning` giving their count;
    vertices that no remaining face references are dropped silently (faces are renumbered),
    so stray points do not move the centre or shrink the object.

    Raises
    ------
    BadInputError
        No vertices or no triangles, non-finite vertices, face indices out of range, or
        every face degenerate, naming ``name`` and the offending count.
    """
    v, f, n = _checked_arrays(vertices, faces, normals, name)
    f = _drop_degenerate(v, f, name)
    # keep only the vertices the faces use (renumbering the faces), so that stray points
    # do not decide the centre and the scale
    used, f = np.unique(f, return_inverse=True)
    f = f.reshape(-1, 3).astype(np.int64)
    v = v[used]
    if n is not None:
        n = n[used]
    n = _unit_normals(v, f, n)
    if normalize:
        center, radius = bounding_sphere(v)
        v = (v - center) / radius
    return Mesh(v, f, n, name)


def _checked_arrays(vertices: np.ndarray, faces: np.ndarray, normals: np.ndarray | None, name: str
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """Vertices (n, 3) float64, faces (m, 3) int64 in range, and the normals (n, 3) float64 when
    they are finite and one per vertex (None otherwise: computed from the faces)."""
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
        first = int(np.flatnonzero(bad)[0])
        raise BadInputError(
            name, f"{int(bad.sum())} of {len(v)} vertices are not finite (NaN or Inf), first is vertex {first}"
        )
    if f.min() < 0 or f.max() >= len(v):
        raise BadInputError(name, f"face indices out of range [0, {len(v)}): min {f.min()}, max {f.max()}")
    n = None if normals is None else np.asarray(normals, dtype=np.float64)
    if n is not None and (n.shape != v.shape or not np.all(np.isfinite(n))):
        n = None
    return v, f, n


def _drop_degenerate(v: np.ndarray, f: np.ndarray, name: str) -> np.ndarray:
    """The faces without the degenerate ones (a repeated index, or an area at most 10⁻¹² × the
    squared extent of the referenced vertices), with a :class:`MeshRepairWarning` giving their count."""
    n_faces = len(f)
    used = np.unique(f)
    extent = float(np.max(v[used].max(axis=0) - v[used].min(axis=0)))
    repeated = (f[:, 0] == f[:, 1]) | (f[:, 1] == f[:, 2]) | (f[:, 0] == f[:, 2])
    area2 = np.linalg.norm(_face_normals(v, f), axis=1)
    degenerate = repeated | (area2 <= 1e-12 * extent * extent)
    if degenerate.all():
        raise BadInputError(
            name,
            "all vertices of the faces coincide (zero-size mesh)" if extent == 0.0
            else f"all {n_faces} faces are degenerate (zero area or a repeated vertex)",
        )
    if degenerate.any():
        first = int(np.flatnonzero(degenerate)[0])
        warnings.warn(
            f"{name}: dropped {int(degenerate.sum())} of {n_faces} faces that are degenerate "
            f"(zero area or a repeated vertex), first is face {first}",
            MeshRepairWarning,
            stacklevel=3,  # make_mesh's caller
        )
        f = f[~degenerate]
    return f


def _unit_normals(v: np.ndarray, f: np.ndarray, n: np.ndarray | None) -> np.ndarray:
    """Unit vertex normals (n, 3): the given ones, or area-weighted face averages where they are
    missing or zero."""
    if n is None:
        n = _vertex_normals(v, f)
    length = np.linalg.norm(n, axis=1)
    weak = length <= 1e-12
    if weak.any():  # e.g. file normals that are zero: fall back to face averages there
        n[weak] = _vertex_normals(v, f)[weak]
        length = np.linalg.norm(n, axis=1)
        if np.any(length <= 1e-300):
            length = np.where(length <= 1e-300, 1.0, length)
    return n / length[:, None]


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


#: The icosahedron of :func:`_icosphere`: (±1, ±φ, 0) and its cyclic permutations on the unit sphere, and
#: its 20 counter-clockwise faces, in trimesh's order (``trimesh.creation.icosahedron``).
_GOLDEN = (1.0 + 5.0**0.5) / 2.0
_ICOSAHEDRON_VERTICES = np.array([
    [-1, _GOLDEN, 0], [1, _GOLDEN, 0], [-1, -_GOLDEN, 0], [1, -_GOLDEN, 0], [0, -1, _GOLDEN], [0, 1, _GOLDEN],
    [0, -1, -_GOLDEN], [0, 1, -_GOLDEN], [_GOLDEN, 0, -1], [_GOLDEN, 0, 1], [-_GOLDEN, 0, -1], [-_GOLDEN, 0, 1],
])
_ICOSAHEDRON_FACES = np.array([
    [0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4], [11, 10, 2], [10, 7, 6],
    [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8], [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10],
    [8, 6, 7], [9, 8, 1],
])


def _icosphere(subdivisions: int) -> tuple[np.ndarray, np.ndarray]:
    """The unit icosphere: the icosahedron with every triangle split in four at its edge midpoints
    ``subdivisions`` times, the vertices pushed back onto the sphere after each split.

    The same vertices and faces, in the same order, as ``trimesh.creation.icosphere`` (its
    ``remesh.subdivide``: the unique edges in its order, midpoints appended in that order, each face
    replaced by its corner and centre triangles), checked against it in the tests; written here
    because importing trimesh costs ~0.5 s CPU, a tenth of a quick report, for 12 vertices and
    20 faces."""
    v = _ICOSAHEDRON_VERTICES / np.linalg.norm(_ICOSAHEDRON_VERTICES, axis=1, keepdims=True)
    f = _ICOSAHEDRON_FACES.copy()
    for _ in range(subdivisions):
        edges = np.sort(f[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
        # trimesh's order of the unique edges (a < b): sorted by b, then a (its row hash, grouping.hashable_rows)
        _, first, inverse = np.unique(edges[:, 1] * len(v) + edges[:, 0], return_index=True, return_inverse=True)
        mid_idx = inverse.reshape(-1, 3) + len(v)
        f = np.column_stack([f[:, 0], mid_idx[:, 0], mid_idx[:, 2], mid_idx[:, 0], f[:, 1], mid_idx[:, 1],
                             mid_idx[:, 2], mid_idx[:, 1], f[:, 2], mid_idx[:, 0], mid_idx[:, 1],
                             mid_idx[:, 2]]).reshape(-1, 3)
        v = np.vstack((v, v[edges[first]].mean(axis=1)))
        scalar = np.sqrt(np.dot(v**2, [1, 1, 1]))
        v = v + (v / scalar.reshape(-1, 1)) * (1.0 - scalar).reshape(-1, 1)
    v = v / np.linalg.norm(v, axis=1, keepdims=True)
    return v, f.astype(np.int64)


def _tube(
    curve: np.ndarray, tangent: np.ndarray, r: float, sides: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A closed tube of radius r around a closed curve (segments, 3) with exact normals:
    (vertices (segments·sides, 3), faces (n, 3), normals (segments·sides, 3))."""
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


_PLY_SIZES = {
    "char": 1, "int8": 1, "uchar": 1, "uint8": 1,
    "short": 2, "int16": 2, "ushort": 2, "uint16": 2,
    "int": 4, "int32": 4, "uint": 4, "uint32": 4, "float": 4, "float32": 4,
    "double": 8, "float64": 8,
}
_PLY_HEADER_MAX = 1 << 20


def _check_ply_header(path: Path, size: int) -> None:
    """Refuse a PLY whose header declares more elements than the limits or the file allow.

    Each element needs at least: binary, the bytes of its scalar properties plus the count
    field of each list; ASCII, one character and one separator per property. A header this
    reader cannot parse is left to trimesh (which then reports it).
    """
    with path.open("rb") as handle:
        head = handle.read(min(size, _PLY_HEADER_MAX))
    end = re.search(rb"end_header[ \t]*\r?\n", head)
    if not head.startswith(b"ply") or end is None:
        return  # not a PLY header we can read: trimesh will say what is wrong
    body = size - end.end()
    lines = head[: end.start()].decode("ascii", errors="replace").splitlines()
    binary = any(line.split()[:2] in (["format", "binary_little_endian"], ["format", "binary_big_endian"])
                 for line in lines if line.strip())
    elements: list[list] = []  # [name, count, properties, bytes per element]
    for line in lines:
        words = line.split()
        if len(words) >= 3 and words[0] == "element":
            try:
                count = int(words[2])
            except ValueError:
                return
            elements.append([words[1], count, 0, 0])
        elif len(words) >= 3 and words[0] == "property" and elements:
            el = elements[-1]
            el[2] += 1
            kind = words[2] if words[1] == "list" and len(words) >= 5 else words[1]
            el[3] += _PLY_SIZES.get(kind, 1)
    need = 0
    for name, count, n_props, n_bytes in elements:
        limits.check_elements(path, (count, max(n_props, 1)), f"PLY element {name!r}")
        need += count * (n_bytes if binary else 2 * n_props)
    if not binary:
        need -= 1  # the last value needs no separator after it
    if need > body:
        declared = ", ".join(f"element {name} {count:,}" for name, count, _, _ in elements)
        raise BadInputError(
            path, f"PLY header declares {declared}, which need at least {need:,} bytes, but the file "
            f"holds {body:,} after its header (truncated or corrupt)",
        )


@functools.cache
def _safe_resolver() -> type:
    """trimesh's file resolver restricted as :class:`SafeResolver` says (made on first use, so that
    importing this module does not import trimesh)."""
    import trimesh.resolvers  # imported on use (see _icosphere)

    class SafeResolver(trimesh.resolvers.FilePathResolver):
        """trimesh's file resolver (files a mesh references: OBJ materials and textures, glTF
        buffers) restricted to regular files of allowed size inside the mesh's folder
        (:func:`limits.read_bytes`), so a referenced FIFO or device cannot block or exhaust memory."""

        def get(self, name: str) -> bytes:
            root = Path(self.parent).resolve()
            for candidate in (name.strip(), name.strip().lstrip("/"), Path(name.strip()).name):
                if not candidate:
                    continue
                path = (root / candidate).resolve()
                if path.is_relative_to(root) and path.exists():
                    return limits.read_bytes(path, "file referenced by the mesh")
            raise FileNotFoundError(name)

    return SafeResolver


def load_mesh(source: str | Path) -> Mesh:
    """Load a mesh file or built-in spec, validated, cleaned and normalized to the unit
    bounding sphere (see :func:`make_mesh`).

    Raises
    ------
    BadInputError
        Unknown spec, missing, unreadable or special (FIFO, device) file, unsupported
        extension, PLY header declaring more data than the limits or the file allow,
        no triangles (empty file or a point cloud), or any problem :func:`make_mesh` detects.
    """
    text = str(source)
    if text.startswith("builtin:"):
        return builtin_mesh(text)
    path = Path(text)
    suffix = path.suffix.lower()
    if suffix not in MESH_SUFFIXES:
        raise BadInputError(path, f"unsupported mesh extension {suffix!r}; use one of {', '.join(MESH_SUFFIXES)}")
    size = limits.regular_file(path, "mesh file")
    if size == 0:
        raise BadInputError(path, "empty file")
    if suffix == ".ply":
        _check_ply_header(path, size)
    import trimesh  # imported on use (see _icosphere)

    try:
        # process=False: keep the data as written (trimesh would otherwise silently drop
        # NaN vertices and degenerate faces, which we want to report)
        loaded = trimesh.load(str(path), process=False, resolver=_safe_resolver()(str(path)))
    except BadInputError:
        raise
    except IndexError as err:  # e.g. an OBJ face naming a vertex the file does not have
        raise BadInputError(path, f"cannot read mesh: face index out of range ({err})") from None
    except Exception as err:  # trimesh raises many types for malformed files
        raise BadInputError(path, f"cannot read mesh: {type(err).__name__}: {err}") from None
    if isinstance(loaded, trimesh.Scene):
        geoms = [g for g in loaded.dump() if isinstance(g, trimesh.Trimesh) and len(g.faces)]
        if not geoms:
            raise BadInputError(path, "file holds no triangle geometry")
        parts_v, parts_f, offset = [], [], 0
        parts_n: list[np.ndarray | None] = []
        for g in geoms:  # dump() has already applied each node's transform
            parts_v.append(np.asarray(g.vertices))
            parts_f.append(np.asarray(g.faces) + offset)
            parts_n.append(_file_normals(g))
            offset += len(g.vertices)
        v, f = np.concatenate(parts_v), np.concatenate(parts_f)
        n: np.ndarray | None = None
        if all(x is not None for x in parts_n):
            n = np.concatenate([x for x in parts_n if x is not None])
    elif isinstance(loaded, trimesh.Trimesh):
        v, f, n = np.asarray(loaded.vertices), np.asarray(loaded.faces), _file_normals(loaded)
    elif isinstance(loaded, trimesh.PointCloud):
        raise BadInputError(
            path, f"file holds a point cloud ({len(loaded.vertices)} vertices, no faces); a triangle mesh is needed"
        )
    else:
        raise BadInputError(path, f"file holds no triangle mesh (got {type(loaded).__name__})")
    if len(f) == 0:
        raise BadInputError(path, f"mesh has no triangles ({len(v)} vertices, no faces)")
    return make_mesh(v, f, n, name=str(path))


def _file_normals(mesh) -> np.ndarray | None:
    """Vertex normals stored in the file, or None (trimesh keeps them in its cache)."""
    cached = mesh._cache.cache.get("vertex_normals") if hasattr(mesh, "_cache") else None
    if cached is None or np.shape(cached) != np.shape(mesh.vertices):
        return None
    return np.asarray(cached, dtype=np.float64)
