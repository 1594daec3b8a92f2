"""Sphere parameterizations: lat-long pixel geometry, Debevec angular light probes and
Direct3D cube maps, and their conservative resampling to lat-long.

Lat-long (DESIGN §2): row i of H has θ = (i + ½)π/H, column j of W has φ = 2π(j + ½)/W,
direction ω = (sin θ cos φ, sin θ sin φ, cos θ) in the project frame (right-handed, z up).

Cube maps (Direct3D / OpenGL cube-map convention, the same texel → direction table in
both APIs): six square faces px, nx, py, ny, pz, nz; on a face of N texels the texel in
row r, column c has face coordinates u = 2(c + ½)/N − 1 (right), v = 2(r + ½)/N − 1
(down) and looks along ``major + u·u_axis + v·v_axis`` in the cube frame (y up,
left-handed as seen from inside), see :data:`CUBE_FACE_AXES`.

Angular probes (Debevec, "Light Probe Image Gallery", angular map format): a square
image, u = 2(c + ½)/D − 1 to the right, v = 1 − 2(r + ½)/D upwards; the direction (Dx, Dy,
Dz) in the probe frame (y up) appears at (u, v) = (Dx, Dy)·acos(Dz)/(π sqrt(Dx² + Dy²)),
so the image centre looks along +z and the rim along −z.

Both file frames are mapped into the project frame by fixed orthogonal matrices,
:data:`CUBE_TO_PROJECT` and :data:`PROBE_TO_PROJECT` (chosen so that Debevec's 1999 Grace
cube map and the shared Grace lat-long files agree, data_specs/environment_maps.md).

Resampling (:func:`cube_to_latlong`, :func:`probe_to_latlong`) gathers s × s
equal-area sub-samples per lat-long pixel (uniform in cos θ and in φ, so each carries
Ω_pixel/s²), takes the texel containing each (the texel value is the texel's mean
radiance), and averages: an estimate of the pixel's mean radiance ∫_pixel L dω / Ω_pixel.
A constant map stays exactly constant, and ∫ L dω is preserved up to the sub-sampling
error (measured: < 2e-4 for a smooth closed form; 1e-4 to 5e-3 on the real 1999 cube
maps, the worst being galileo's compact lamps; the flux of one isolated texel is kept
only to about ±20 %: raise ``samples`` for such maps).

Public objects: :func:`latlong_directions`, :func:`latlong_solid_angles`,
:data:`CUBE_FACES`, :data:`CUBE_FACE_AXES`, :data:`CUBE_TO_PROJECT`,
:data:`PROBE_TO_PROJECT`, :func:`cube_texel_solid_angles`, :func:`cube_texel_directions`,
:func:`probe_pixel_directions`, :func:`cube_to_latlong`, :func:`probe_to_latlong`.

References
----------
- P. Debevec, "Light Probe Image Gallery", https://www.pauldebevec.com/Probes/
  (angular map formula).
- Microsoft, "Cubic Environment Mapping (Direct3D 9)"; OpenGL 4.6 specification
  §8.13, Table 8.19 (cube-map face selection and (s, t) per face).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

__all__ = [
    "latlong_directions",
    "latlong_solid_angles",
    "CUBE_FACES",
    "CUBE_FACE_AXES",
    "CUBE_TO_PROJECT",
    "PROBE_TO_PROJECT",
    "cube_texel_solid_angles",
    "cube_texel_directions",
    "probe_pixel_directions",
    "cube_to_latlong",
    "probe_to_latlong",
]


# --------------------------------------------------------------------------------------
# lat-long geometry
# --------------------------------------------------------------------------------------
def latlong_directions(height: int, width: int) -> np.ndarray:
    """Pixel-centre unit vectors of a lat-long map, ``(H, W, 3)`` float64 (DESIGN §2)."""
    theta = (np.arange(height) + 0.5) * np.pi / height
    phi = 2.0 * np.pi * (np.arange(width) + 0.5) / width
    st = np.sin(theta)[:, None]
    return np.stack(
        np.broadcast_arrays(st * np.cos(phi), st * np.sin(phi), np.cos(theta)[:, None]), axis=-1
    )


def latlong_solid_angles(height: int, width: int) -> np.ndarray:
    """Exact solid angle of one pixel in each row, ``(H,)`` float64.

    Ω_i = (2π/W)(cos θ_i⁻ − cos θ_i⁺) with row edges θ_i⁻ = iπ/H, θ_i⁺ = (i + 1)π/H;
    the rows sum to 4π/W per column.
    """
    edges = np.cos(np.arange(height + 1) * np.pi / height)
    return (2.0 * np.pi / width) * (edges[:-1] - edges[1:])


# --------------------------------------------------------------------------------------
# cube maps
# --------------------------------------------------------------------------------------
CUBE_FACES = ("px", "nx", "py", "ny", "pz", "nz")

# face -> (major axis, u axis (texel columns, rightwards), v axis (texel rows, downwards)),
# in the cube frame; this is OpenGL Table 8.19 / the Direct3D cube-map layout:
#   +X: sc = -rz, tc = -ry    -X: sc = +rz, tc = -ry    +Y: sc = +rx, tc = +rz
#   -Y: sc = +rx, tc = -rz    +Z: sc = +rx, tc = -ry    -Z: sc = -rx, tc = -ry
CUBE_FACE_AXES: dict[str, tuple[tuple[int, int, int], tuple[int, int, int], tuple[int, int, int]]] = {
    "px": ((1, 0, 0), (0, 0, -1), (0, -1, 0)),
    "nx": ((-1, 0, 0), (0, 0, 1), (0, -1, 0)),
    "py": ((0, 1, 0), (1, 0, 0), (0, 0, 1)),
    "ny": ((0, -1, 0), (1, 0, 0), (0, 0, -1)),
    "pz": ((0, 0, 1), (1, 0, 0), (0, -1, 0)),
    "nz": ((0, 0, -1), (-1, 0, 0), (0, -1, 0)),
}

# project = CUBE_TO_PROJECT @ cube: X = z_c, Y = -x_c, Z = y_c. The cube frame is
# left-handed as seen from inside, so the map is a reflection (det = -1); it keeps the
# faces unmirrored: looking along cube +z_c with y_c up, +x_c is on the right, and
# looking along project -X with Z up, -Y is on the right.
CUBE_TO_PROJECT = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])

# project = PROBE_TO_PROJECT @ probe: X = x_p, Y = -z_p, Z = y_p (a rotation, det = +1):
# the probe's up axis y_p becomes the zenith.
PROBE_TO_PROJECT = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])


def _face_coordinates(n: int) -> np.ndarray:
    return 2.0 * (np.arange(n) + 0.5) / n - 1.0


def cube_texel_directions(n: int, face: str) -> np.ndarray:
    """Texel-centre unit vectors of one cube face in the cube frame, ``(N, N, 3)``."""
    major, u_axis, v_axis = (np.asarray(a, dtype=float) for a in CUBE_FACE_AXES[face])
    c = _face_coordinates(n)
    d = major + c[None, :, None] * u_axis + c[:, None, None] * v_axis
    return d / np.linalg.norm(d, axis=-1, keepdims=True)


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


def _cube_texel_index(x: np.ndarray, y: np.ndarray, z: np.ndarray, n: int) -> np.ndarray:
    """Flat index face·N² + row·N + col of the texel containing each cube-frame direction.

    The face is the axis of largest |component| and its sign (order px, nx, py, ny, pz,
    nz); (u, v) follow :data:`CUBE_FACE_AXES` (OpenGL Table 8.19), divided by |major|.
    """
    ax, ay, az = np.abs(x), np.abs(y), np.abs(z)
    on_x = (ax >= ay) & (ax >= az)
    on_y = ~on_x & (ay >= az)
    major = np.where(on_x, ax, np.where(on_y, ay, az))
    # u, v numerators per face: px (-z, -y), nx (z, -y), py (x, z), ny (x, -z), pz (x, -y), nz (-x, -y)
    u = np.where(on_x, np.where(x > 0, -z, z), np.where(on_y, x, np.where(z > 0, x, -x)))
    v = np.where(on_x, -y, np.where(on_y, np.where(y > 0, z, -z), -y))
    face = np.where(on_x, 0, np.where(on_y, 2, 4)) + np.where(on_x, x < 0, np.where(on_y, y < 0, z < 0))
    col = np.clip(((u / major + 1.0) * (0.5 * n)).astype(np.int64), 0, n - 1)
    row = np.clip(((v / major + 1.0) * (0.5 * n)).astype(np.int64), 0, n - 1)
    return (face * n + row) * n + col


# --------------------------------------------------------------------------------------
# angular probes
# --------------------------------------------------------------------------------------
def probe_pixel_directions(size: int) -> tuple[np.ndarray, np.ndarray]:
    """Directions (probe frame) and solid angles of the pixels of a D × D angular map.

    Returns
    -------
    dirs
        ``(D, D, 3)`` unit vectors (undefined, but finite, outside the disc).
    solid_angles
        ``(D, D)``: π sin(πρ)/ρ · (2/D)² inside the unit disc (ρ = pixel-centre radius,
        the Jacobian of the angular map), 0 outside.
    """
    c = _face_coordinates(size)
    u = c[None, :]
    v = -c[:, None]
    rho = np.hypot(u, v)
    alpha = np.pi * np.minimum(rho, 1.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        s = np.where(rho > 0, np.sin(alpha) / rho, np.pi)
        jac = np.where(rho > 0, np.pi * np.sin(alpha) / rho, np.pi * np.pi)
    dirs = np.stack(np.broadcast_arrays(u * s, v * s, np.cos(alpha)), axis=-1)
    solid = np.where(rho <= 1.0, jac * (2.0 / size) ** 2, 0.0)
    return dirs, solid


def _probe_pixel_index(x: np.ndarray, y: np.ndarray, z: np.ndarray, size: int) -> np.ndarray:
    """Flat index row·D + col of the angular-map pixel that shows each probe-frame direction."""
    r_xy = np.hypot(x, y)
    alpha = np.arccos(np.clip(z, -1.0, 1.0))
    with np.errstate(invalid="ignore", divide="ignore"):
        scale = np.where(r_xy > 1e-300, alpha / (np.pi * r_xy), 0.0)
    u = x * scale
    v = y * scale
    col = np.clip(((u + 1.0) * 0.5 * size).astype(np.int64), 0, size - 1)
    row = np.clip(((1.0 - v) * 0.5 * size).astype(np.int64), 0, size - 1)
    return row * size + col


# --------------------------------------------------------------------------------------
# conservative gather
# --------------------------------------------------------------------------------------
def _gather_latlong(
    values: np.ndarray,
    texel_of: Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray],
    to_source: np.ndarray,
    height: int,
    samples: int,
) -> np.ndarray:
    """Resample flat source texels ``values`` (T, 3) to a (height, 2·height, 3) lat-long map.

    ``texel_of(x, y, z)`` maps source-frame direction components to flat texel indices;
    ``to_source`` maps project-frame vectors to the source frame. Sub-sample (a, b) of
    pixel (i, j) sits at cos θ = cos θ_i⁻ − (a + ½)/s · (cos θ_i⁻ − cos θ_i⁺),
    φ = 2π(j + (b + ½)/s)/W: each carries Ω_i/s², so the pixel value is the plain mean
    of the texels under its sub-samples.
    """
    width = 2 * height
    s = samples
    edges = np.cos(np.arange(height + 1) * np.pi / height)
    frac = (np.arange(s) + 0.5) / s
    cos_t = (edges[:-1, None] - frac[None, :] * (edges[:-1] - edges[1:])[:, None]).reshape(-1)
    sin_t = np.sqrt(np.maximum(0.0, 1.0 - cos_t * cos_t))
    phi = 2.0 * np.pi * (np.arange(width)[:, None] + frac[None, :]).reshape(-1) / width
    cp, sp = np.cos(phi), np.sin(phi)
    texel = np.empty((height * s, width * s), dtype=np.int64)
    block = max(1, 1_000_000 // (width * s))
    for r0 in range(0, height * s, block):
        st, ct = sin_t[r0 : r0 + block, None], cos_t[r0 : r0 + block, None]
        big_x, big_y = st * cp, st * sp
        big_z = np.broadcast_to(ct, big_x.shape)
        # source-frame components: row k of to_source dotted with (X, Y, Z)
        comps = [m[0] * big_x + m[1] * big_y + m[2] * big_z for m in to_source]
        texel[r0 : r0 + block] = texel_of(*comps)
    # sample (i·s + a, j·s + b) -> pixel (i, j): mean over a and b
    picked = values[texel.reshape(height, s, width, s)]
    return picked.mean(axis=(1, 3))


def _default_samples(height: int, source_rows: int) -> int:
    """Sub-samples per axis: at least 2, enough for ~2 per source texel and ≥ 256 sample rows, ≤ 16."""
    return int(np.clip(np.ceil(max(2 * source_rows, 256) / height), 2, 16))


def cube_to_latlong(faces: dict[str, np.ndarray], height: int, samples: int | None = None) -> np.ndarray:
    """Resample a cube map to a lat-long map in the project frame.

    Parameters
    ----------
    faces
        The six faces ``{"px": (N, N, 3), ...}`` in the Direct3D layout (:data:`CUBE_FACE_AXES`).
    height
        Output rows H (width 2H); 2N keeps the face resolution everywhere.
    samples
        Equal-area sub-samples per pixel along θ and along φ (s² in all); default
        clip(ceil(max(4N, 256)/H), 2, 16), about two per texel width along θ.

    Returns
    -------
    numpy.ndarray
        ``(H, 2H, 3)`` float64 radiance; each pixel is the mean of the texels under its
        equal-area sub-samples, an estimate of ∫_pixel L dω / Ω_pixel for the
        piecewise-constant cube map.
    """
    n = faces["px"].shape[0]
    values = np.concatenate([np.asarray(faces[f], dtype=np.float64).reshape(-1, 3) for f in CUBE_FACES])
    s = samples or _default_samples(height, 2 * n)
    return _gather_latlong(values, lambda x, y, z: _cube_texel_index(x, y, z, n), CUBE_TO_PROJECT.T, height, s)


def probe_to_latlong(image: np.ndarray, height: int, samples: int | None = None) -> np.ndarray:
    """Resample a Debevec angular-map probe (D × D × 3) to a lat-long map in the project frame.

    Pixels outside the unit disc are never sampled. See :func:`cube_to_latlong` for the
    parameters (default samples clip(ceil(max(2D, 256)/H), 2, 16)); D/2 rows keep the
    probe's resolution at its centre.
    """
    size = image.shape[0]
    values = np.asarray(image, dtype=np.float64).reshape(-1, 3)
    s = samples or _default_samples(height, size)
    return _gather_latlong(values, lambda x, y, z: _probe_pixel_index(x, y, z, size), PROBE_TO_PROJECT.T, height, s)
