"""Cube maps: the one table of the six faces, their texel geometry, and resampling to lat-long.

Six square faces px, nx, py, ny, pz, nz (:data:`CUBE_FACES`); a texel at face coordinates (u, v)
looks along ``major + u·u_axis + v·v_axis`` (:data:`CUBE_FACE_AXES`, the table of [GL46] §8.13,
Table 8.19, which Direct3D shares [D3D9Cube]). The table is written in the *cube frame* of whoever
samples the cube: cube-map files are y-up (:data:`CUBE_TO_PROJECT` turns them into the project
frame), an SHRM's cube is in the project frame itself. :func:`cube_to_latlong` resamples a cube
to lat-long (``data_specs/environment_maps.md`` §4).
"""

from __future__ import annotations

import numpy as np

from .latlong import default_gather_samples, gather_to_latlong

__all__ = [
    "CUBE_FACES",
    "CUBE_FACE_AXES",
    "CUBE_TO_PROJECT",
    "face_coordinates",
    "cube_texel_directions",
    "cube_map_directions",
    "cube_texel_solid_angles",
    "cube_texel_index",
    "cube_to_latlong",
]

CUBE_FACES = ("px", "nx", "py", "ny", "pz", "nz")

#: face -> (major axis, u axis (texel columns, rightwards), v axis (texel rows, downwards)),
#: in the cube frame; [GL46] Table 8.19 (the Direct3D layout is the same, [D3D9Cube]):
#:   +X: sc = -rz, tc = -ry    -X: sc = +rz, tc = -ry    +Y: sc = +rx, tc = +rz
#:   -Y: sc = +rx, tc = -rz    +Z: sc = +rx, tc = -ry    -Z: sc = -rx, tc = -ry
#: On a face of N texels the texel in row r, column c has face coordinates u = 2(c + ½)/N − 1
#: (columns, rightwards) and v = 2(r + ½)/N − 1 (rows, downwards) (:func:`face_coordinates`):
#:
#: ====  =======  ==================  ===============
#: face  major    u_axis (columns →)  v_axis (rows ↓)
#: ====  =======  ==================  ===============
#: px    +x       −z                  −y
#: nx    −x       +z                  −y
#: py    +y       +x                  +z
#: ny    −y       +x                  −z
#: pz    +z       +x                  −y
#: nz    −z       −x                  −y
#: ====  =======  ==================  ===============
CUBE_FACE_AXES: dict[str, tuple[tuple[int, int, int], tuple[int, int, int], tuple[int, int, int]]] = {
    "px": ((1, 0, 0), (0, 0, -1), (0, -1, 0)),
    "nx": ((-1, 0, 0), (0, 0, 1), (0, -1, 0)),
    "py": ((0, 1, 0), (1, 0, 0), (0, 0, 1)),
    "ny": ((0, -1, 0), (1, 0, 0), (0, 0, -1)),
    "pz": ((0, 0, 1), (1, 0, 0), (0, -1, 0)),
    "nz": ((0, 0, -1), (-1, 0, 0), (0, -1, 0)),
}
# every axis of the table is a signed unit vector: per face (CUBE_FACES order), the
# component (0, 1, 2) that the u and the v axis pick from a direction, and its sign
_AXES = np.array([CUBE_FACE_AXES[f] for f in CUBE_FACES])  # (6, 3, 3): major, u, v
_COMPONENT = np.abs(_AXES).argmax(axis=-1)  # (6, 3)
_SIGN = _AXES.sum(axis=-1).astype(np.float64)  # (6, 3), ±1

#: Cube-map files: project = CUBE_TO_PROJECT @ cube, X = z_c, Y = -x_c, Z = y_c. The file
#: cube frame is left-handed as seen from inside, so the map is a reflection (det = -1); it
#: keeps the faces unmirrored: looking along cube +z_c with y_c up, +x_c is on the right,
#: and looking along project +X with Z up, -Y is on the right. Chosen so that Debevec's
#: 1999 Grace cube [DebevecProbes] and the shared Grace lat-long file agree
#: (data_specs/environment_maps.md §4). Face py is then the zenith, face pz looks along
#: project +X, face px along project −Y.
#:
#: Two cube frames are in use in shrmkit, and both use the one table :data:`CUBE_FACE_AXES`:
#: (1) cube-map files (a folder of six faces, read by :func:`~shrmkit.brdf_io.envmap.load_env`),
#: in the y-up frame this matrix maps into the project frame (DESIGN §2, right-handed, z up);
#: (2) SHRM cube maps (:func:`shrmkit.analysis.shrm.cube_directions`, data_specs/shrm_file.md),
#: whose cube frame *is* the project frame (the identity map), so that a GLSL ``samplerCube``
#: looked up with a z-up project-frame direction finds the right texel: there face pz (+z) is
#: the zenith and face px (+x) looks along project +X. They are different orientations of the
#: same table: six faces written from an SHRM cube and read back as a cube-map folder come out
#: re-oriented by this matrix.
CUBE_TO_PROJECT = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])


def face_coordinates(n: int) -> np.ndarray:
    """Texel-centre coordinates 2(k + ½)/n − 1 in (−1, 1) of n texels along a face, shape (n,)."""
    return 2.0 * (np.arange(n) + 0.5) / n - 1.0


def cube_texel_directions(n: int, face: str) -> np.ndarray:
    """Texel-centre unit vectors of one face in the cube frame, ``(N, N, 3)`` (row, column)."""
    major, u_axis, v_axis = (np.asarray(a, dtype=float) for a in CUBE_FACE_AXES[face])
    c = face_coordinates(n)
    d = major + c[None, :, None] * u_axis + c[:, None, None] * v_axis
    return d / np.linalg.norm(d, axis=-1, keepdims=True)


def cube_map_directions(n: int) -> np.ndarray:
    """Texel-centre unit vectors of all six faces in the cube frame, ``(6, N, N, 3)``,
    faces in :data:`CUBE_FACES` order."""
    return np.stack([cube_texel_directions(n, face) for face in CUBE_FACES])


def cube_texel_solid_angles(n: int) -> np.ndarray:
    """Exact solid angles of the texels of one N × N cube face, ``(N, N)`` float64.

    A rectangle [u0, u1] × [v0, v1] on the plane at distance 1 subtends
    F(u1, v1) − F(u0, v1) − F(u1, v0) + F(u0, v0) with F(u, v) = atan2(uv, sqrt(u² + v² + 1));
    the six faces sum to 4π.
    """
    edges = np.linspace(-1.0, 1.0, n + 1)
    u, v = np.meshgrid(edges, edges, indexing="ij")
    f = np.arctan2(u * v, np.sqrt(u * u + v * v + 1.0))
    return f[1:, 1:] - f[:-1, 1:] - f[1:, :-1] + f[:-1, :-1]


def cube_texel_index(x: np.ndarray, y: np.ndarray, z: np.ndarray, n: int) -> np.ndarray:
    """Flat index face·N² + row·N + col of the texel containing each cube-frame direction.

    The face is the axis of largest |component| and its sign (ties go to x, then y); the
    face coordinates are (u, v) = (d·u_axis, d·v_axis)/|d·major| from :data:`CUBE_FACE_AXES`,
    the inverse of :func:`cube_texel_directions`.
    """
    ax, ay, az = np.abs(x), np.abs(y), np.abs(z)
    on_x = (ax >= ay) & (ax >= az)
    on_y = ~on_x & (ay >= az)
    major = np.where(on_x, ax, np.where(on_y, ay, az))
    face = np.where(on_x, 0, np.where(on_y, 2, 4)) + np.where(on_x, x < 0, np.where(on_y, y < 0, z < 0))
    u = _SIGN[face, 1] * np.choose(_COMPONENT[face, 1], (x, y, z))  # d·u_axis
    v = _SIGN[face, 2] * np.choose(_COMPONENT[face, 2], (x, y, z))  # d·v_axis
    col = np.clip(((u / major + 1.0) * (0.5 * n)).astype(np.int64), 0, n - 1)
    row = np.clip(((v / major + 1.0) * (0.5 * n)).astype(np.int64), 0, n - 1)
    return (face * n + row) * n + col


def cube_to_latlong(faces: dict[str, np.ndarray], height: int, samples: int | None = None) -> np.ndarray:
    """Resample a cube-map file's faces to a lat-long map in the project frame.

    Parameters
    ----------
    faces
        The six faces ``{"px": (N, N, 3), ...}`` of a cube-map file (frame 1 above:
        :data:`CUBE_FACE_AXES` in the y-up cube frame, :data:`CUBE_TO_PROJECT`).
    height
        Output rows H (width 2H); 2N keeps the face resolution everywhere.
    samples
        Equal-area sub-samples per pixel along θ and along φ (s² in all); default
        :func:`~shrmkit.brdf_io.latlong.default_gather_samples` with 2N source rows,
        clip(ceil(max(4N, 256)/H), 2, 16), about two per texel width along θ.

    Returns
    -------
    numpy.ndarray
        ``(H, 2H, 3)`` float64 radiance; each pixel is the mean of the texels under its
        equal-area sub-samples (:func:`~shrmkit.brdf_io.latlong.gather_to_latlong`), an
        estimate of ∫_pixel L dω / Ω_pixel for the piecewise-constant cube map.
    """
    n = faces["px"].shape[0]
    values = np.concatenate([np.asarray(faces[f], dtype=np.float64).reshape(-1, 3) for f in CUBE_FACES])
    s = samples or default_gather_samples(height, 2 * n)
    return gather_to_latlong(values, lambda x, y, z: cube_texel_index(x, y, z, n), CUBE_TO_PROJECT.T, height, s)
