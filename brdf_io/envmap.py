"""Environment maps: the :class:`EnvironmentMap` container, :func:`load_env` and :func:`save_env`.

An environment map is linear radiance on an equirectangular (lat-long) grid in the
project frame (right-handed, z up; DESIGN §2): pixel (i, j) of an H × W map is centred
at θ = (i + ½)π/H, φ = 2π(j + ½)/W (φ from +x toward +y), direction
ω = (sin θ cos φ, sin θ sin φ, cos θ); the grid geometry comes from
:mod:`~shrmkit.brdf_io.latlong`.

:func:`load_env` reads OpenEXR, Radiance .hdr and PFM lat-long maps, Debevec angular
probes, Direct3D cube maps (a folder of six faces), OpenEXR files carrying the standard
``envmap`` attribute (lat-long or cube, OpenEXR's own conventions, ImfEnvmap) and
procedural ``builtin:`` specs, and maps each file's own orientation convention into the
project frame (the rules: data_specs/environment_maps.md); lat-long files are read **y-up by
default**, as Blender, three.js and Mitsuba 3 place them. :func:`save_env` writes the same y-up
convention, so a saved map reads back unchanged. Every map's radiance is checked (finite,
negatives clamped or refused: :class:`EnvironmentMap`).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .builtin_env import BUILTIN_PREFIX, builtin_radiance
from .cubemap import CUBE_FACES, cube_to_latlong
from .errors import BadInputError
from .exr import ExrImage, read_exr, read_exr_image
from .hdr_codecs import IMAGE_SUFFIXES, read_image, write_image
from .latlong import (
    bilinear_lookup,
    default_gather_samples,
    gather_to_latlong,
    pixel_directions,
    row_edges_cos,
    row_solid_angles,
)
from .limits import check_memory, check_pixels
from .notebook import env_html, env_png
from .probe import probe_to_latlong

__all__ = [
    "EnvironmentMap",
    "load_env",
    "save_env",
    "white_level",
    "openexr_envmap_to_latlong",
    "OPENEXR_TO_PROJECT",
    "NEGATIVE_CLAMP_FRACTION",
]


#: Negative radiance up to this fraction of the map's white level is clamped to 0 (with a
#: warning); beyond it the map is refused (data_specs/environment_maps.md §6).
NEGATIVE_CLAMP_FRACTION = 1e-3
#: Peak bytes per pixel while :func:`load_env` reads and orients a map, beside the file's bytes
#: (the reader's arrays, the checked copy, the y-up transform: measured 24-54 B/px for 2048 x 1024
#: EXR, RGBE and PFM maps), and per output pixel of a resampling (a cube, a probe, ``height=``):
#: the memory plan of data_specs/limits.md, checked on the header before a pixel is decoded.
ENV_PEAK_BYTES_PER_PIXEL = 64
#: The white level: this percentile of the per-pixel largest channel (robust to a sun or a
#: lamp covering less than 0.1 % of the pixels).
WHITE_PERCENTILE = 99.9


def white_level(radiance: np.ndarray) -> float:
    """The map's white level S: the 99.9th percentile (over pixels) of the per-pixel largest
    channel, non-finite pixels left out; 0 for an empty or all-non-finite array."""
    peak = np.asarray(radiance).max(axis=-1).reshape(-1)
    peak = peak[np.isfinite(peak)]
    return float(np.percentile(peak, WHITE_PERCENTILE)) if peak.size else 0.0


def _check_radiance(source: object, radiance: np.ndarray, white: float | None = None) -> np.ndarray:
    """Refuse NaN, infinite or clearly negative radiance, counting the offending pixels; clamp
    negatives no larger than :data:`NEGATIVE_CLAMP_FRACTION` × the white level (``white``,
    default :func:`white_level` of ``radiance``) to 0 with a warning that counts them.

    Returns ``radiance`` itself when nothing is clamped, else a clamped copy.

    Raises
    ------
    BadInputError
        NaN or infinite values; negatives beyond the threshold (all problems in one message).
    """
    problems = []
    nan = np.isnan(radiance).any(axis=-1)
    if nan.any():
        problems.append(f"{int(nan.sum())} pixel(s) with NaN radiance")
    inf = np.isinf(radiance).any(axis=-1)
    if inf.any():
        problems.append(f"{int(inf.sum())} pixel(s) with infinite radiance")
    negative = (radiance < 0).any(axis=-1)
    clamp = False
    if negative.any():
        lowest = float(np.nanmin(radiance))
        white = white_level(radiance) if white is None else white
        limit = NEGATIVE_CLAMP_FRACTION * white
        if -lowest <= limit:
            clamp = True
        else:
            problems.append(
                f"{int(negative.sum())} pixel(s) with negative radiance (min {lowest:g}, beyond the clamping "
                f"threshold {NEGATIVE_CLAMP_FRACTION:g} x white level {white:g} = {limit:g})"
            )
    if problems:
        raise BadInputError(source, "; ".join(problems) + " (refused)")
    if clamp:
        warnings.warn(
            f"{source}: clamped {int(negative.sum())} negative pixel(s) to 0 (min {lowest:g}, within "
            f"{NEGATIVE_CLAMP_FRACTION:g} x the white level {white:g})",
            stacklevel=2,
        )
        return np.maximum(radiance, 0).astype(radiance.dtype, copy=False)
    return radiance


def _interval_overlap(edges_out: np.ndarray, edges_in: np.ndarray) -> np.ndarray:
    """Overlap lengths of increasing intervals: (len(edges_out) - 1, len(edges_in) - 1)."""
    lo = np.maximum(edges_out[:-1, None], edges_in[None, :-1])
    hi = np.minimum(edges_out[1:, None], edges_in[None, 1:])
    return np.maximum(hi - lo, 0.0)


@dataclass(frozen=True)
class EnvironmentMap:
    """Linear radiance on a lat-long grid in the project frame (DESIGN §2).

    Radiance checks (all sources, :func:`EnvironmentMap` included): NaN and infinite values are
    refused; negative values no larger than :data:`NEGATIVE_CLAMP_FRACTION` (10⁻³) × the map's
    white level (:func:`white_level`: the 99.9th percentile of the per-pixel largest channel) are
    clamped to 0 with a warning that counts them (camera processing leaves such pixels in real
    photographs); larger negatives are refused.

    Parameters
    ----------
    radiance
        ``(H, W, 3)`` float32 or float64, finite and non-negative; row 0 is the zenith
        (+z). Stored read-only. Negatives within 10⁻³ × the white level are clamped to 0
        with a warning (above); NaN, infinities and larger negatives raise
        :class:`BadInputError`.
    name
        Short name (file stem or built-in name).
    source
        Provenance: the file or spec and the orientation options it was read with.
    """

    radiance: np.ndarray
    name: str = ""
    source: str = ""

    def __post_init__(self) -> None:
        radiance = np.asarray(self.radiance)
        where = self.source or self.name or None
        if radiance.ndim != 3 or radiance.shape[2] != 3 or radiance.shape[0] < 1 or radiance.shape[1] < 1:
            raise BadInputError(where, f"radiance must have shape (H, W, 3) with H, W >= 1, got {radiance.shape}")
        if radiance.dtype not in (np.float32, np.float64):
            raise BadInputError(where, f"radiance must be float32 or float64, got {radiance.dtype}")
        checked = _check_radiance(where, radiance)  # a fresh copy when tiny negatives were clamped
        if checked is radiance and radiance.flags.writeable:
            checked = radiance.copy()
        checked.flags.writeable = False
        object.__setattr__(self, "radiance", checked)

    @classmethod
    def derived(cls, radiance: np.ndarray, *, name: str = "", source: str = "") -> EnvironmentMap:
        """A map computed from a checked one by operations that keep every value finite and
        non-negative (a light taken out of it, say): the reading checks of ``__post_init__`` are
        skipped (they cost a full pass over a 2-Mpixel map). ``radiance`` is taken as is, made
        read-only.

        Raises
        ------
        ValueError
            A shape or dtype the class does not hold (a programming error, not bad input).
        """
        radiance = np.asarray(radiance)
        if radiance.ndim != 3 or radiance.shape[2] != 3 or radiance.dtype not in (np.float32, np.float64):
            raise ValueError(f"a derived map must be (H, W, 3) float32/float64, got {radiance.dtype} {radiance.shape}")
        radiance.flags.writeable = False
        out = object.__new__(cls)
        for key, value in (("radiance", radiance), ("name", name), ("source", source)):
            object.__setattr__(out, key, value)
        return out

    @property
    def height(self) -> int:
        """Number of rows H."""
        return int(self.radiance.shape[0])

    @property
    def width(self) -> int:
        """Number of columns W."""
        return int(self.radiance.shape[1])

    def directions(self) -> np.ndarray:
        """Pixel-centre unit vectors, ``(H, W, 3)`` float64."""
        return pixel_directions(self.height, self.width)

    def solid_angles(self) -> np.ndarray:
        """Exact per-row pixel solid angle (2π/W)(cos θ_top − cos θ_bottom), ``(H,)`` float64."""
        return row_solid_angles(self.height, self.width)

    def integral(self) -> np.ndarray:
        """∫ L dω per channel, ``(3,)`` float64: Σ_ij L_ij Ω_i (exact for the piecewise-constant map)."""
        rows = self.radiance.sum(axis=1, dtype=np.float64)
        return self.solid_angles() @ rows

    def lookup(self, dirs: np.ndarray) -> np.ndarray:
        """Bilinear radiance at directions, ``(..., 3)`` -> ``(..., 3)`` float64.

        The directions need not be unit length (zero vectors are refused). Interpolation
        is between pixel centres, periodic in φ, and clamped to the first/last row
        beyond the outermost row centres (within π/2H of the poles):
        :func:`~shrmkit.brdf_io.latlong.bilinear_lookup` at the normalized directions.
        """
        d = np.asarray(dirs, dtype=np.float64)
        if d.shape[-1:] != (3,):
            raise BadInputError(None, f"lookup directions must have shape (..., 3), got {d.shape}")
        norm = np.linalg.norm(d, axis=-1)
        if not np.all(norm > 0) or not np.all(np.isfinite(norm)):
            raise BadInputError(None, "lookup directions must be finite and non-zero")
        return bilinear_lookup(self.radiance, d / norm[..., None])

    def resized(self, height: int, width: int | None = None) -> EnvironmentMap:
        """Area-weighted resampling to ``height`` rows (``width`` defaults to W·height/H).

        Output pixel = Σ over input pixels of (overlap solid angle / output pixel solid
        angle) × input radiance, with overlaps measured exactly in cos θ and φ (the grid is
        separable in those). Each input pixel's solid angle is fully distributed, so
        ∫ L dω is preserved exactly; a constant map stays constant. Integer downsampling
        is the solid-angle-weighted block mean.
        """
        if width is None:
            width = max(1, round(self.width * height / self.height))
        if height < 1 or width < 1:
            raise BadInputError(self.source or None, f"resized size must be positive, got {height} x {width}")
        if (height, width) == (self.height, self.width):
            return self
        # rows: measure in μ = -cos θ (increasing with the row index)
        mu_in = -row_edges_cos(self.height)
        mu_out = -row_edges_cos(height)
        rows = _interval_overlap(mu_out, mu_in)
        rows /= rows.sum(axis=1, keepdims=True)
        cols = _interval_overlap(np.linspace(0.0, 1.0, width + 1), np.linspace(0.0, 1.0, self.width + 1))
        cols /= cols.sum(axis=1, keepdims=True)
        out = np.einsum("ai,ijc,bj->abc", rows, self.radiance.astype(np.float64), cols, optimize=True)
        out = np.maximum(out, 0.0).astype(self.radiance.dtype)  # tiny negative round-off only
        return EnvironmentMap(out, self.name, f"{self.source} [resized to {height}x{width}]")

    def _repr_html_(self) -> str:
        """Notebook card: tone-mapped thumbnail, size, orientation, dynamic range (``brdf_io.notebook``)."""
        return env_html(self)

    def _repr_png_(self) -> bytes:
        """Notebook picture: the tone-mapped lat-long thumbnail as PNG."""
        return env_png(self)

    def rotated_z(self, angle: float) -> EnvironmentMap:
        """Rotate the environment by ``angle`` radians about +z: L'(ω) = L(R_z(−angle) ω).

        A feature at azimuth φ moves to φ + angle (counterclockwise seen from above). A
        whole number of columns is an exact roll; otherwise linear interpolation along φ,
        which keeps Σ L exactly (so ∫ L dω too).
        """
        shift = angle * self.width / (2.0 * np.pi)
        whole = int(np.floor(shift))
        frac = shift - whole
        img = np.roll(self.radiance, whole, axis=1)
        if frac > 1e-12:
            img = (1.0 - frac) * img + frac * np.roll(img, 1, axis=1)
        img = img.astype(self.radiance.dtype)
        return EnvironmentMap(img, self.name, f"{self.source} [rotated_z {np.degrees(angle):g} deg]")


# --------------------------------------------------------------------------------------
# loading
# --------------------------------------------------------------------------------------
def _y_up_to_project(image: np.ndarray) -> np.ndarray:
    """Re-index a y-up lat-long file (data_specs: up='y', the default) into the project frame.

    The file column j looks at ψ = 2π(j + ½)/W − π in the file frame, i.e. the file's
    direction (sin θ cos ψ, cos θ, sin θ sin ψ) = (x_f, y_f, z_f); project (X, Y, Z) =
    (x_f, −z_f, y_f), so φ = −ψ and project column j' = (W/2 − 1 − j) mod W. A pure
    permutation of columns (exact for even W, as every 2:1 map has) and its own inverse, so
    :func:`save_env` writes a map into the file convention with the same call.
    """
    w = image.shape[1]
    j = (w // 2 - 1 - np.arange(w)) % w
    return image[:, j]


def _read_face(path: Path, layer: str | None, part: int | str | None) -> np.ndarray:
    if path.suffix.lower() == ".exr":
        return read_exr(path, layer=layer, part=part)
    if layer is not None or part is not None:
        raise BadInputError(path, "layer and part apply to OpenEXR files only")
    return read_image(path)


def _cube_faces(
    source: Path, folder: Path, layer: str | None = None, part: int | str | None = None
) -> dict[str, np.ndarray]:
    faces: dict[str, np.ndarray] = {}
    missing = []
    for face in CUBE_FACES:
        found = [folder / f"{face}{s}" for s in IMAGE_SUFFIXES if (folder / f"{face}{s}").is_file()]
        if not found:
            missing.append(face)
        elif len(found) > 1:
            raise BadInputError(source, f"cube face {face} exists in several formats: {[p.name for p in found]}")
        else:
            faces[face] = _read_face(found[0], layer, part)
    if missing:
        raise BadInputError(
            source, f"cube map needs six faces {', '.join(CUBE_FACES)}; missing {', '.join(missing)} in {folder}"
        )
    shapes = {f: im.shape[:2] for f, im in faces.items()}
    n = shapes["px"][0]
    if any(s != (n, n) for s in shapes.values()):
        raise BadInputError(source, f"cube faces must be square and of equal size; sizes {shapes}")
    finite = [im for im in faces.values() if np.isfinite(im).all()]
    white = white_level(np.concatenate([im.reshape(-1, 3) for im in finite])) if finite else 0.0
    for face, image in faces.items():
        faces[face] = _check_radiance(folder / face, image, white)
    return faces


# --------------------------------------------------------------------------------------
# OpenEXR's own environment-map conventions (the `envmap` attribute, ImfEnvmap.h/.cpp)
# --------------------------------------------------------------------------------------
#: OpenEXR environment frame (x_e, y_e, z_e; y up) → project frame: X = x_e, Y = −z_e,
#: Z = y_e. A rotation (det +1) by +90° about x; the same map as ``up="y"`` lat-long files.
OPENEXR_TO_PROJECT = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])

# OpenEXR cube faces in file order (ImfEnvmap.h CubeMapFace): +X, −X, +Y, −Y, +Z, −Z
OPENEXR_CUBE_FACES = ("+X", "-X", "+Y", "-Y", "+Z", "-Z")


def _openexr_latlong_texel(h: int, w: int):
    """texel_of(x, y, z) for an OpenEXR lat-long data window of h × w: the nearest pixel to
    ImfEnvmap ``LatLongMap::pixelPosition``: x = (lon/(−2π) + ½)(w − 1), y = (lat/(−π) + ½)(h − 1),
    lat = asin(y_e), lon = atan2(x_e, z_e) (pixel centres on the poles and on the ±π seam)."""

    def texel_of(x: np.ndarray, y: np.ndarray, z: np.ndarray) -> np.ndarray:
        lat = np.arcsin(np.clip(y, -1.0, 1.0))
        lon = np.arctan2(x, z)
        col = np.clip(np.rint((lon / (-2.0 * np.pi) + 0.5) * (w - 1)), 0, w - 1).astype(np.int64)
        row = np.clip(np.rint((lat / -np.pi + 0.5) * (h - 1)), 0, h - 1).astype(np.int64)
        return row * w + col

    return texel_of


def _openexr_cube_texel(n: int):
    """texel_of(x, y, z) for an OpenEXR cube of six n × n faces stacked vertically (+X, −X,
    +Y, −Y, +Z, −Z): the face of the largest |component| (ties: x, then y), the in-face
    position of ImfEnvmap ``CubeMap::faceAndPixelPosition`` (p = (d_a/|d_major| + 1)/2 · (n − 1),
    a = y, z for ±X; x, z for ±Y; x, y for ±Z) and the file pixel of ``CubeMap::pixelPosition``,
    rounded to the nearest pixel. Flat index (face·n + row)·n + column."""
    last = n - 1

    def texel_of(x: np.ndarray, y: np.ndarray, z: np.ndarray) -> np.ndarray:
        ax, ay, az = np.abs(x), np.abs(y), np.abs(z)
        on_x = (ax >= ay) & (ax >= az)
        on_y = ~on_x & (ay >= az)
        major = np.maximum(np.where(on_x, ax, np.where(on_y, ay, az)), 1e-300)
        first = np.where(on_x, y, x) / major  # pif.x
        second = np.where(on_x | on_y, z, y) / major  # pif.y
        px = (first + 1.0) * 0.5 * last
        py = (second + 1.0) * 0.5 * last
        negative = np.where(on_x, x < 0, np.where(on_y, y < 0, z < 0))
        face = np.where(on_x, 0, np.where(on_y, 2, 4)) + negative
        # CubeMap::pixelPosition, relative to the face's top-left pixel: (column, row)
        col = np.select(
            [face == 0, face == 1, face == 4], [py, last - py, last - px], default=px
        )
        row = np.select([face == 3], [py], default=last - np.where(face <= 1, px, py))
        col = np.clip(np.rint(col), 0, last).astype(np.int64)
        row = np.clip(np.rint(row), 0, last).astype(np.int64)
        return (face * n + row) * n + col

    return texel_of


def openexr_envmap_to_latlong(image: np.ndarray, kind: str, height: int, samples: int | None = None) -> np.ndarray:
    """Resample an OpenEXR environment map (its data window) to a project-frame lat-long map.

    Parameters
    ----------
    image
        ``(h, w, 3)`` data-window pixels: ``kind="latlong"`` (ImfEnvmap LatLongMap: top row
        latitude +π/2, bottom −π/2, left column longitude +π, right −π, direction
        (sin lon cos lat, sin lat, cos lon cos lat)), or ``kind="cube"`` (h = 6w: faces +X,
        −X, +Y, −Y, +Z, −Z from the top, ImfEnvmap CubeMap).
    height
        Output rows H (width 2H).
    samples
        Equal-area sub-samples per pixel and axis; default
        :func:`~shrmkit.brdf_io.latlong.default_gather_samples` with h (lat-long) or 2w (cube)
        source rows.

    Returns
    -------
    numpy.ndarray
        ``(H, 2H, 3)`` float64: each pixel the mean over its equal-area sub-samples of the
        nearest file pixel (OpenEXR's pixel-centre positions), directions mapped by
        :data:`OPENEXR_TO_PROJECT`. Source: OpenEXR ``ImfEnvmap.cpp``.
    """
    h, w = image.shape[:2]
    values = np.asarray(image, dtype=np.float64).reshape(-1, 3)
    if kind == "latlong":
        texel_of, rows = _openexr_latlong_texel(h, w), h
    elif kind == "cube":
        texel_of, rows = _openexr_cube_texel(w), 2 * w
    else:
        raise ValueError(f"unknown OpenEXR envmap kind {kind!r}")
    s = samples or default_gather_samples(height, rows)
    return gather_to_latlong(values, texel_of, OPENEXR_TO_PROJECT.T, height, s)


def _options_text(up: str, flip: bool, azimuth: float, kind: str) -> str:
    parts = [kind, f"up={up}"]
    if flip:
        parts.append("flip")
    if azimuth:
        parts.append(f"azimuth={azimuth:g}")
    return " [" + ", ".join(parts) + "]"


def load_env(
    spec_or_path: str | Path,
    up: str | None = None,
    azimuth: float = 0.0,
    flip: bool = False,
    probe: bool | None = None,
    height: int | None = None,
    layer: str | None = None,
    part: int | str | None = None,
) -> EnvironmentMap:
    """Load an environment map into the project frame (data_specs/environment_maps.md).

    Parameters
    ----------
    spec_or_path
        ``builtin:NAME[,key=value...]``; a lat-long or angular-probe image (``.exr``,
        ``.hdr``, ``.pfm``); a cube-map folder holding ``px, nx, py, ny, pz, nz`` faces,
        or the path of one of those faces.
    up
        Lat-long file convention. ``"y"`` (the default, None) reads a y-up panorama, the
        convention of files in the wild (Poly Haven, the USC ICT probes, three.js, Blender,
        Mitsuba 3): top row +y_f, image centre looking along +x_f, columns to the right
        turning clockwise seen from above; project (X, Y, Z) = (x_f, −z_f, y_f), so the image
        centre faces project +X and its right-hand quarter −Y, as in Blender's z-up world.
        ``"z"`` reads the file literally in the DESIGN §2 pixel convention (top row +z, φ
        growing with the column, i.e. mirrored for a viewer inside the sphere). Cube maps,
        probes and OpenEXR ``envmap`` files have their own fixed y-up conventions: ``up`` must
        be None or ``"y"`` for them.
        Lat-long files are read y-up by default (``up="y"``), the convention of nearly every
        panorama in the wild and of the tools that read them: a file is placed as Blender's
        Environment Texture places it in its z-up world (Cycles ``direction_to_equirectangular``:
        image centre toward +X), as three.js's ``equirectUv`` places it in its y-up world mapped by
        (X, Y, Z) = (x, −z, y), and as Mitsuba 3's ``envmap`` emitter places it in its y-up world
        mapped by (X, Y, Z) = (z, x, y) (checked against Mitsuba's emitter, and on OpenEXR's
        ``KernerEnvLatLong.exr``, whose ``envmap`` attribute states its orientation: the same map
        turned by −90°); ``up="z"`` reads a file literally in the project convention (mirrored for
        a viewer inside the sphere). :func:`save_env` writes the same y-up convention, so a saved
        map reads back unchanged and opens unmirrored in those tools.
    azimuth
        Degrees; the loaded map is rotated about the project +z axis so that a feature
        at φ moves to φ + azimuth (applied last).
    flip
        Lat-long only: reverse the row order first (files stored bottom row first).
    probe
        True: the image is a Debevec angular map; False: it is lat-long; None: a square
        image whose file name contains "probe" (any case) is a probe, others lat-long.
    height
        Output rows (width 2·height), by area-weighted resampling; default: the file's
        rows (lat-long), 2N for N × N cube faces, D/2 for a D × D probe; for OpenEXR
        ``envmap`` files the data window's rows (lat-long) or 2N (N × N faces).
    layer, part
        OpenEXR only (files and cube faces): the layer (channel prefix) and the part (name
        or index) to read; defaults and rules in
        :func:`~shrmkit.brdf_io.exr.read_exr_image`. A file with the ``envmap`` attribute is
        read in OpenEXR's own convention (y up, mapped by :data:`OPENEXR_TO_PROJECT`); ``up``
        may then be None or ``"y"``, ``flip`` and ``probe`` are refused, ``azimuth`` applies.
        Other OpenEXR files are read on their display window (the data window placed in it).

    Returns
    -------
    EnvironmentMap

    Warns
    -----
    UserWarning
        "clamped N negative pixel(s)" when tiny negatives (≤ 10⁻³ × white level) were set to 0.

    Raises
    ------
    BadInputError
        Missing, unreadable or corrupt file; zero-size image; NaN, infinite or clearly
        negative radiance (the pixels are counted); OpenEXR: deep, ambiguous layers/parts
        without ``layer``/``part``, sizes beyond the limits (brdf_io.limits); layer/part for a
        non-OpenEXR source; a lat-long image that is not
        2:1; a non-square probe; missing, duplicate or unequal cube faces; bad options.

    Examples
    --------
    ``tests/resources/tiny_4x8.hdr`` is a 4 × 8 Radiance file whose pixel (i, j) is
    ((j + 1)/8, (i + 1)/4, (i + j + 1)/16), values RGBE stores exactly. Read literally
    (``up="z"``), file pixel (i, j) is lat-long pixel (i, j), centred at
    θ = (i + ½)π/4, φ = 2π(j + ½)/8:

    >>> import numpy as np
    >>> env = load_env("tests/resources/tiny_4x8.hdr", up="z")
    >>> env.radiance.shape, env.radiance.dtype
    ((4, 8, 3), dtype('float32'))
    >>> env.radiance[1, 6]
    array([0.875, 0.5  , 0.5  ], dtype=float32)
    >>> theta, phi = 1.5 * np.pi / 4, 2 * np.pi * 6.5 / 8
    >>> env.lookup(np.array([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)]))
    array([0.875, 0.5  , 0.5  ])

    With the default (a y-up panorama), file column j becomes project column
    (W/2 − 1 − j) mod W, here (3 − 6) mod 8 = 5:

    >>> load_env("tests/resources/tiny_4x8.hdr").radiance[1, 5]
    array([0.875, 0.5  , 0.5  ], dtype=float32)

    A built-in map, with its closed-form integral ∫ L dω = 4π · 2:

    >>> load_env("builtin:constant,value=2,height=4").integral()
    array([25.13274123, 25.13274123, 25.13274123])
    """
    text = str(spec_or_path)
    if up not in (None, "z", "y"):
        raise BadInputError(text, f"up={up!r}: choose 'z' or 'y'")
    if not np.isfinite(azimuth):
        raise BadInputError(text, f"azimuth={azimuth!r} is not finite")
    if height is not None and (int(height) != height or height < 1):
        raise BadInputError(text, f"height={height!r} must be a positive integer")

    if text.strip().startswith(BUILTIN_PREFIX):
        if up is not None or flip or probe or layer is not None or part is not None:
            raise BadInputError(text, "up, flip, probe, layer and part do not apply to built-in environments")
        name, radiance = builtin_radiance(text)
        env = EnvironmentMap(radiance, name, text.strip())
    else:
        env = _load_file(Path(text), up, flip, probe, azimuth, height, layer, part)
    if azimuth:
        env = env.rotated_z(np.radians(azimuth))
    if height is not None and height != env.height:
        env = env.resized(int(height), 2 * int(height))
    return env


def _load_file(
    path: Path,
    up: str | None,
    flip: bool,
    probe: bool | None,
    azimuth: float,
    height: int | None,
    layer: str | None = None,
    part: int | str | None = None,
) -> EnvironmentMap:
    is_face = path.stem.lower() in CUBE_FACES and path.suffix.lower() in IMAGE_SUFFIXES
    if path.is_dir() or is_face:
        if flip or probe:
            raise BadInputError(path, "flip and probe do not apply to cube maps")
        if up == "z":
            raise BadInputError(path, "cube maps are y-up (Direct3D convention); up='z' does not apply")
        folder = path if path.is_dir() else path.parent
        if not folder.is_dir():
            raise BadInputError(path, "no such cube-map folder")
        faces = _cube_faces(path, folder, layer, part)
        n = faces["px"].shape[0]
        _check_env_memory(folder, 6 * n, n, int(height or 2 * n))
        radiance = cube_to_latlong(faces, int(height or 2 * n)).astype(np.float32)
        return EnvironmentMap(radiance, folder.name, f"{folder}" + _options_text("y", False, azimuth, "cube"))
    if not path.exists():
        raise BadInputError(path, "no such file")
    if path.suffix.lower() == ".exr":
        def check_windows(display: tuple[int, int], data: tuple[int, int], envmap: str | None) -> None:
            if envmap is None:
                is_probe = _plain_shape(path, *display, probe)
                _check_env_memory(path, *display, height or (display[0] // 2 if is_probe else None))
            else:
                _envmap_shape(path, envmap, *data, height)
                _check_env_memory(path, *data, _envmap_rows(envmap, *data, height))

        exr = read_exr_image(path, layer=layer, part=part, check_windows=check_windows)
        if exr.envmap is not None:
            return _load_openexr_envmap(path, exr, up, flip, probe, azimuth, height)
        image = exr.pixels
    else:
        if layer is not None or part is not None:
            raise BadInputError(path, "layer and part apply to OpenEXR files only")
        def check_shape(h: int, w: int) -> None:  # before a pixel is decoded
            is_probe = _plain_shape(path, h, w, probe)
            _check_env_memory(path, h, w, height or (max(1, h // 2) if is_probe else None))

        image = read_image(path, check_shape=check_shape)
    h, w = image.shape[:2]
    is_probe = _plain_shape(path, h, w, probe)
    image = _check_radiance(path, image)
    if is_probe:
        if flip:
            raise BadInputError(path, "flip does not apply to angular probes")
        if up == "z":
            raise BadInputError(path, "angular probes are y-up (Debevec convention); up='z' does not apply")
        radiance = probe_to_latlong(image, int(height or max(1, h // 2))).astype(np.float32)
        return EnvironmentMap(radiance, path.stem, f"{path}" + _options_text("y", False, azimuth, "probe"))
    if flip:
        image = image[::-1]
    up = up or "y"  # files in the wild are y-up (module docstring, data_specs §3)
    if up == "y":
        image = _y_up_to_project(image)
    return EnvironmentMap(
        np.ascontiguousarray(image), path.stem, f"{path}" + _options_text(up, flip, azimuth, "latlong")
    )


def _plain_shape(path: Path, h: int, w: int, probe: bool | None) -> bool:
    """The shape rules of a map without an ``envmap`` attribute (an angular probe is square, a
    lat-long map 2:1); True for a probe. Checked on an EXR's header before its pixels are read."""
    if h <= 0 or w <= 0:
        raise BadInputError(path, f"zero-size image ({w} x {h})")
    is_probe = probe if probe is not None else (h == w and "probe" in path.name.lower())
    if is_probe and h != w:
        raise BadInputError(path, f"an angular probe must be square, got {w} x {h}")
    if not is_probe and w != 2 * h:
        raise BadInputError(
            path, f"a lat-long map must be 2:1 (width = 2 x height), got {w} x {h}; pass probe=True for angular maps"
        )
    return bool(is_probe)


def _check_env_memory(path: Path, h: int, w: int, rows_out: int | None) -> None:
    """The memory plan of loading an h × w image as a map resampled to ``rows_out`` rows (None: kept
    as read): refused before a pixel is decoded when over ``SHRM_MAX_MEMORY_BYTES``."""
    try:
        size = path.stat().st_size if path.is_file() else 0
    except OSError:
        size = 0
    out = 2 * rows_out * rows_out if rows_out else 0
    into = f" into {2 * rows_out} x {rows_out}" if rows_out else ""
    check_memory(path, size + ENV_PEAK_BYTES_PER_PIXEL * (h * w + out), f"loading a {w} x {h} map{into}")


def _envmap_rows(kind: str, h: int, w: int, height: int | None) -> int:
    """Rows of the lat-long map an ``envmap`` file of an h × w data window is resampled to: the
    ``height`` asked for, else h for a lat-long map, 2w (twice a cube face) for a cube."""
    return int(height or (h if kind == "latlong" else 2 * w))


def _envmap_shape(path: Path, kind: str, h: int, w: int, height: int | None) -> None:
    """The rules of an OpenEXR ``envmap`` file's data window (h × w), before its pixels are read:
    a known kind, six stacked square faces for a cube, and a lat-long output within the pixel
    limit (``SHRM_MAX_PIXELS``; a 1 × 20,000 window would otherwise ask for 20,000 × 40,000)."""
    if kind not in ("latlong", "cube"):
        raise BadInputError(path, f"envmap attribute {kind!r} is neither ENVMAP_LATLONG nor ENVMAP_CUBE")
    if kind == "cube" and h != 6 * w:
        raise BadInputError(
            path, f"envmap=cube needs a data window of six stacked square faces (h = 6w), got {w} x {h}"
        )
    rows = _envmap_rows(kind, h, w, height)
    check_pixels(path, rows, 2 * rows)


def _load_openexr_envmap(
    path: Path, exr: ExrImage, up: str | None, flip: bool, probe: bool | None, azimuth: float, height: int | None
) -> EnvironmentMap:
    """A file with the ``envmap`` attribute: OpenEXR's own convention, honoured automatically."""
    kind = exr.envmap  # its windows were checked by _envmap_shape before the pixels were read
    assert kind is not None  # the caller takes this path only for files with the attribute
    if flip or probe:
        raise BadInputError(
            path, f"the file declares envmap={kind} (OpenEXR's own orientation, ImfEnvmap); flip and probe do not apply"
        )
    if up == "z":
        raise BadInputError(
            path, f"the file declares envmap={kind}: OpenEXR environment maps are y-up; up='z' does not apply"
        )
    image = exr.data
    h, w = image.shape[:2]
    image = _check_radiance(path, image)
    rows = _envmap_rows(kind, h, w, height)
    radiance = openexr_envmap_to_latlong(image, kind, rows).astype(np.float32)
    return EnvironmentMap(radiance, path.stem, f"{path}" + _options_text("y", False, azimuth, f"openexr-{kind}"))


def save_env(path: str | Path, env: EnvironmentMap, half: bool = False) -> None:
    """Write ``env`` as a y-up lat-long file, the convention :func:`load_env` reads by default
    (and Blender, three.js and Mitsuba 3 read): top row +z, project column j' stored in file
    column (W/2 − 1 − j') mod W (data_specs/environment_maps.md §3), so ``load_env(path)`` gives
    the same map back (exactly, within the format's precision) and the file opens unmirrored in
    those tools. A map to be read back must be 2:1 (W = 2H).

    ``.exr`` (float32, or half floats with ``half=True``), ``.hdr`` (RGBE, run-length
    encoded) or ``.pfm``; the write is atomic (temporary file + ``os.replace``).

    Raises
    ------
    BadInputError
        ``env`` is not an :class:`EnvironmentMap`; the writer's errors (unknown suffix, half
        overflow, an unwritable path).
    """
    if not isinstance(env, EnvironmentMap):
        raise BadInputError(path, f"save_env needs an EnvironmentMap, got {type(env).__name__}")
    write_image(Path(path), _y_up_to_project(env.radiance), half=half)  # the permutation is an involution
