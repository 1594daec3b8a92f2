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
negatives clamped or refused: :class:`EnvironmentMap`). The file readers and the radiance checks
are in ``_env_files.py``, OpenEXR's ``envmap`` conventions in ``_openexr_envmap.py``.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ._env_files import (  # noqa: F401  (re-exported: the reading rules' names stay importable from here)
    ENV_PEAK_BYTES_PER_PIXEL,
    NEGATIVE_CLAMP_FRACTION,
    WHITE_PERCENTILE,
    _check_radiance,
    _load_file,
    _y_up_to_project,
    white_level,
)
from ._openexr_envmap import OPENEXR_CUBE_FACES, OPENEXR_TO_PROJECT, openexr_envmap_to_latlong  # noqa: F401
from .builtin_env import BUILTIN_PREFIX, builtin_radiance
from .errors import BadInputError
from .hdr_codecs import write_image
from .latlong import (
    bilinear_lookup,
    pixel_directions,
    row_edges_cos,
    row_solid_angles,
)
from .notebook import env_html, env_png

__all__ = [
    "EnvironmentMap",
    "load_env",
    "save_env",
    "white_level",
    "openexr_envmap_to_latlong",
    "OPENEXR_TO_PROJECT",
    "NEGATIVE_CLAMP_FRACTION",
]


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
        env = EnvironmentMap(*_load_file(Path(text), up, flip, probe, azimuth, height, layer, part))
    if azimuth:
        env = env.rotated_z(np.radians(azimuth))
    if height is not None and height != env.height:
        env = env.resized(int(height), 2 * int(height))
    return env


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
