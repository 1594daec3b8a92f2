"""Environment-map files into checked project-frame radiance: the lat-long, probe, cube and OpenEXR ``envmap`` paths.

:func:`_load_file` reads one file (or a cube-map folder), checks its shape and memory plan on the
header before a pixel is decoded, checks its radiance (:func:`_check_radiance`: non-finite values
refused, tiny negatives clamped) and maps its orientation convention into the project frame;
:func:`~shrmkit.brdf_io.envmap.load_env` wraps the result into an
:class:`~shrmkit.brdf_io.envmap.EnvironmentMap` and re-exports the public names. The rules:
data_specs/environment_maps.md (orientation, §6 negatives) and data_specs/limits.md (memory).
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np

from ._openexr_envmap import openexr_envmap_to_latlong
from .cubemap import CUBE_FACES, cube_to_latlong
from .errors import BadInputError
from .exr import ExrImage, read_exr, read_exr_image
from .hdr_codecs import IMAGE_SUFFIXES, read_image
from .limits import check_memory, check_pixels
from .probe import probe_to_latlong

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


def _options_text(up: str, flip: bool, azimuth: float, kind: str) -> str:
    parts = [kind, f"up={up}"]
    if flip:
        parts.append("flip")
    if azimuth:
        parts.append(f"azimuth={azimuth:g}")
    return " [" + ", ".join(parts) + "]"


def _load_file(
    path: Path,
    up: str | None,
    flip: bool,
    probe: bool | None,
    azimuth: float,
    height: int | None,
    layer: str | None = None,
    part: int | str | None = None,
) -> tuple[np.ndarray, str, str]:
    """The radiance, name and source (with the options read) of a map file or cube folder, checked
    and oriented into the project frame (:func:`~shrmkit.brdf_io.envmap.load_env` wraps them into an
    :class:`~shrmkit.brdf_io.envmap.EnvironmentMap`)."""
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
        return radiance, folder.name, f"{folder}" + _options_text("y", False, azimuth, "cube")
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
        return radiance, path.stem, f"{path}" + _options_text("y", False, azimuth, "probe")
    if flip:
        image = image[::-1]
    up = up or "y"  # files in the wild are y-up (module docstring, data_specs §3)
    if up == "y":
        image = _y_up_to_project(image)
    return np.ascontiguousarray(image), path.stem, f"{path}" + _options_text(up, flip, azimuth, "latlong")


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
) -> tuple[np.ndarray, str, str]:
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
    return radiance, path.stem, f"{path}" + _options_text("y", False, azimuth, f"openexr-{kind}")
