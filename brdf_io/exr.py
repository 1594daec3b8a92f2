"""OpenEXR reader and writer (through the ``OpenEXR`` 3.x Python bindings) [OpenEXR].

:func:`read_exr_image` reads the colour of one part and one layer of a scanline or tiled OpenEXR
file (single- or multi-part, any resolution level mode: level 0 is read) as an :class:`ExrImage`
on the display window, refusing what it cannot read with one :class:`BadInputError` line naming
the file; :func:`read_exr` returns the pixels only; :func:`write_exr` writes a ZIP scanline file
atomically. The rules (part, layer, colour, windows, size checks before any pixel is read):
``data_specs/environment_maps.md`` §2.1. The headers (parts, size checks, the part and layer
chosen) are read in ``_exr_header.py``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import OpenEXR

from ._exr_header import (
    _box,
    _box_size,
    _check_sizes,
    _choose_layer,
    _choose_part,
    _enum_name,
    _first_line,
    _library_output,
    _Part,
    _read_headers,
)
from .errors import BadInputError
from .image_common import atomic_image_path, check_rgb
from .limits import check_memory, check_pixels, regular_file

__all__ = ["ExrImage", "read_exr_image", "read_exr", "write_exr", "luminance_weights", "REC709_CHROMATICITIES"]

_MAGIC = b"\x76\x2f\x31\x01"

#: Rec. ITU-R BT.709 primaries and D65 white, (x, y) of red, green, blue, white: OpenEXR's
#: default ``Chromaticities`` (ImfChromaticities.h), used when a file has no attribute.
REC709_CHROMATICITIES = (0.6400, 0.3300, 0.3000, 0.6000, 0.1500, 0.0600, 0.3127, 0.3290)

# OpenEXR's chroma reconstruction filter (ImfRgbaYca.cpp, reconstructChromaHoriz/Vert):
# a missing sample at odd position p is Σ_m w_m (c(p − 1 − 2m) + c(p + 1 + 2m)), m = 0..6.
_CHROMA_TAPS = np.array([0.627123, -0.186077, 0.087929, -0.043159, 0.019597, -0.007540, 0.002128])


@dataclass(frozen=True)
class ExrImage:
    """The colour of one part/layer of an OpenEXR file.

    Attributes
    ----------
    pixels
        ``(H, W, 3)`` float32 linear RGB on the **display window** (H, W its size): the data
        window placed at its offset, 0 outside it, cropped to the display window. Row 0 is
        the top (smallest y).
    data
        ``(h, w, 3)`` float32: the data window alone (``pixels`` itself when the windows
        coincide). Environment maps with the ``envmap`` attribute are defined on it (ImfEnvmap).
    data_window, display_window
        ``(x_min, y_min, x_max, y_max)``, inclusive pixel coordinates as in the header.
    envmap
        ``"latlong"``, ``"cube"`` (the standard ``envmap`` attribute, ImfEnvmap.h), None when
        absent, or ``"unknown(N)"`` for another value.
    part, part_name
        Index and name (``""`` when unnamed) of the part read.
    layer
        The channel-name prefix read (``""``: unprefixed channels).
    colour
        ``"rgb"``, ``"yca"`` (Y, RY, BY converted) or ``"y"`` (luminance read as grey).
    notes
        Human-readable remarks (window placement, chroma handling, library messages).
    """

    pixels: np.ndarray
    data: np.ndarray
    data_window: tuple[int, int, int, int]
    display_window: tuple[int, int, int, int]
    envmap: str | None
    part: int
    part_name: str
    layer: str
    colour: str
    notes: tuple[str, ...] = ()


# --------------------------------------------------------------------------------------
# luminance / chroma
# --------------------------------------------------------------------------------------
def luminance_weights(chromaticities: tuple[float, ...] = REC709_CHROMATICITIES) -> np.ndarray:
    """OpenEXR's ``computeYw``: the Y row of the RGB → XYZ matrix of the primaries, normalised
    to sum 1, ``(3,)`` float64 (Rec. 709/D65: 0.2126, 0.7152, 0.0722).

    ``chromaticities`` = (x_r, y_r, x_g, y_g, x_b, y_b, x_w, y_w). Raises ``ValueError``
    for degenerate chromaticities (singular matrix or a non-positive weight)."""
    c = np.asarray(chromaticities, dtype=np.float64)
    if c.shape != (8,) or not np.all(np.isfinite(c)) or np.any(c[1::2] == 0):
        raise ValueError(f"chromaticities {tuple(chromaticities)} are degenerate")
    xy = c.reshape(4, 2)
    xyz = np.column_stack([xy[:, 0] / xy[:, 1], np.ones(4), (1.0 - xy[:, 0] - xy[:, 1]) / xy[:, 1]])  # Y = 1
    primaries = xyz[:3].T  # columns: XYZ of R, G, B (Y = 1)
    try:
        scale = np.linalg.solve(primaries, xyz[3])  # R = G = B = 1 gives the white point, Y_w = 1
    except np.linalg.LinAlgError:
        raise ValueError(f"chromaticities {tuple(chromaticities)} are degenerate") from None
    yw = scale / scale.sum()
    if not np.all(np.isfinite(yw)) or yw[1] <= 0:  # G = (Y − R·yw_r − B·yw_b)/yw_g
        raise ValueError(f"chromaticities {tuple(chromaticities)} give luminance weights {yw}")
    return yw


def _upsample_chroma(samples: np.ndarray, n: int, axis: int) -> np.ndarray:
    """Chroma sampled at every other pixel (positions 0, 2, 4, ... of ``n``) to ``n`` pixels
    along ``axis``: samples kept at even positions, odd positions from OpenEXR's filter,
    sample indices clamped at the ends (ImfRgbaFile padTmpBuf / readYCAScanLine)."""
    samples = np.moveaxis(samples, axis, 0)
    k = samples.shape[0]
    out = np.empty((n,) + samples.shape[1:], dtype=np.float64)
    out[0::2] = samples[: (n + 1) // 2]
    odd = np.arange(n // 2)  # odd position 2j + 1 lies between samples j and j + 1
    acc = np.zeros((len(odd),) + samples.shape[1:], dtype=np.float64)
    for m, w in enumerate(_CHROMA_TAPS):
        acc += w * (samples[np.clip(odd - m, 0, k - 1)] + samples[np.clip(odd + 1 + m, 0, k - 1)])
    out[1::2] = acc
    return np.moveaxis(out, 0, axis)


def _yca_to_rgb(
    path: Path, part: _Part, names: dict[str, str], planes: dict[str, np.ndarray], notes: list[str]
) -> np.ndarray:
    h, w = _box_size(part.data_window)
    y = planes[names["Y"]].astype(np.float64)
    chroma = []
    for key in ("RY", "BY"):
        xs, ys = part.channels[names[key]]
        if xs not in (1, 2) or ys not in (1, 2):
            raise BadInputError(
                path, f"chroma channel {names[key]!r} has sampling {xs} x {ys}; only 1 or 2 are supported"
            )
        c = planes[names[key]].astype(np.float64)
        if ys == 2:
            c = _upsample_chroma(c, h, 0)
        if xs == 2:
            c = _upsample_chroma(c, w, 1)
        chroma.append(c)
        if (xs, ys) != (1, 1):
            notes.append(f"{names[key]} sampled {xs} x {ys}: reconstructed with OpenEXR's chroma filter")
    ry, by = chroma
    raw = part.header.get("chromaticities")
    try:
        yw = luminance_weights(tuple(raw) if raw is not None else REC709_CHROMATICITIES)
    except (TypeError, ValueError) as err:
        raise BadInputError(path, f"unusable chromaticities attribute: {err}") from None
    notes.append("luminance/chroma converted with " + ("the file's chromaticities" if raw is not None
                                                        else "Rec. 709/D65 chromaticities (no attribute)"))
    r = (ry + 1.0) * y
    b = (by + 1.0) * y
    g = (y - r * yw[0] - b * yw[2]) / yw[1]
    grey = (ry == 0) & (by == 0)  # YCAtoRGBA's special case: exact grey
    rgb = np.stack([np.where(grey, y, r), np.where(grey, y, g), np.where(grey, y, b)], axis=-1)
    negative = int(np.count_nonzero(rgb < 0))
    if negative:
        # RGBAtoYCA clamps R, G, B at 0 before encoding: a negative value is filter ringing
        notes.append(f"{negative} reconstructed R/G/B values below 0 (chroma filter ringing) set to 0")
        rgb = np.maximum(rgb, 0.0)
    return rgb.astype(np.float32)


# --------------------------------------------------------------------------------------
# reading
# --------------------------------------------------------------------------------------
def _check_magic(path: Path) -> None:
    try:
        with path.open("rb") as handle:
            head = handle.read(4)
    except OSError as err:
        raise BadInputError(path, f"cannot read ({err.strerror or err})") from None
    if head != _MAGIC:
        raise BadInputError(path, "not an OpenEXR file (no OpenEXR magic number 76 2f 31 01)")


def _read_planes(path: Path, chosen: _Part, wanted: list[str], n_parts: int) -> tuple[dict[str, np.ndarray], str]:
    """Read the file and return the wanted channels of the chosen part (and library text)."""
    try:
        with _library_output() as out, OpenEXR.File(str(path), separate_channels=True) as exr:
            complete = len(exr.parts) == n_parts
            channels = exr.channels(chosen.index) if complete else {}
            planes = {name: np.asarray(channels[name].pixels) for name in wanted if name in channels}
    except Exception as err:
        raise BadInputError(path, f"not a readable OpenEXR file ({_first_line(path, out.text, str(err))})") from None
    if not complete or "Exception" in out.text or len(planes) != len(wanted):
        missing = sorted(set(wanted) - set(planes))
        fallback = f"channels {missing} could not be read" if missing else "incomplete pixel data"
        raise BadInputError(path, f"not a readable OpenEXR file ({_first_line(path, out.text, fallback)})")
    return planes, out.text


#: Peak bytes per data-window pixel of :func:`read_exr_image` beside the file's bytes and the
#: display window's float32 RGB (12 B/px): the decoded planes, their RGB stack (measured 25 B/px in
#: all for equal windows).
EXR_PEAK_BYTES_PER_PIXEL = 28


def read_exr_image(
    path: str | Path,
    *,
    layer: str | None = None,
    part: int | str | None = None,
    check_windows: Callable[[tuple[int, int], tuple[int, int], str | None], None] | None = None,
) -> ExrImage:
    """Read the colour of one part and layer of an OpenEXR file (the rules in full:
    data_specs/environment_maps.md §2.1).

    - **Part** (multi-part files): ``part=`` (name, or index) picks one; otherwise the one part
      that holds colour channels (R, G, B or Y, plain or in a layer) is read; several such
      parts are refused, naming them. Deep parts (``deepscanline``/``deeptile``) are refused.
    - **Layer** (channel-name prefix ``layer.R``): ``layer=`` picks one (``""``: the
      unprefixed channels); otherwise the plain (unprefixed) R, G, B are read when present, else
      the one layer with colour; several such layers are refused, naming them.
    - **Colour**: R, G, B (any pixel type; A and other channels ignored); or luminance/chroma
      Y, RY, BY (OpenEXR's RGBA-YCA encoding, [OpenEXR] ``ImfRgbaYca.cpp``: computeYw, YCAtoRGBA,
      reconstructChromaHoriz/Vert; ``ImfRgbaFile.cpp``: edge padding of the chroma filter),
      converted with the file's ``chromaticities`` (Rec. 709 / D65 when absent), chroma
      subsampled 2 × 2 reconstructed with OpenEXR's own 27-tap interpolation filter; or Y alone,
      read as grey.
    - **Windows**: the data window is placed inside the display window (pixels outside the
      data window are 0, as OpenEXR defines; data outside the display window is cropped);
      negative origins are allowed. The ``envmap`` attribute is read as ``ImfEnvmap.h`` defines it.

    Before any pixel is read the file must be a regular file
    (:func:`~shrmkit.brdf_io.limits.regular_file`) with the OpenEXR magic number, and every
    declared size is checked from the header alone (:func:`~shrmkit.brdf_io.limits.check_pixels`,
    :func:`~shrmkit.brdf_io.limits.check_elements`, and a lower bound on the bytes its chunk table
    and chunks need). The OpenEXR C library's own messages (written straight to file descriptor 2,
    sometimes by the hundred for a truncated file) are captured and only their first line is
    kept in the error.

    Parameters
    ----------
    path
        The file.
    layer
        Channel-name prefix to read (``"diffuse"`` for ``diffuse.R`` …; ``""`` for the
        unprefixed channels). Default: unprefixed colour if present, else the only layer
        with colour.
    part
        Part name or index (an integer, or a string of digits that names no part). Default:
        the only part with colour channels.
    check_windows
        Called as ``check_windows((h, w) of the display window, (h, w) of the data window, envmap
        kind or None)`` after the headers are read and before any pixel is: the caller's shape
        rules (a lat-long map is 2:1, a cube h = 6w, an output size within the limits) refuse a
        file before its windows are allocated (a few hundred bytes can declare gigabytes).

    Returns
    -------
    ExrImage
        ``pixels`` (H, W, 3) float32 on the display window, ``data`` on the data window,
        the windows, ``envmap`` kind and notes.

    Raises
    ------
    BadInputError
        Missing or special file, too large (``SHRM_MAX_FILE_BYTES``), not OpenEXR, corrupt
        or truncated (first line of the library's message), declared sizes beyond
        ``SHRM_MAX_PIXELS``/``SHRM_MAX_ELEMENTS``/``SHRM_MAX_MEMORY_BYTES`` or beyond what the
        file can hold (checked before any pixel is read), deep parts, no colour channels, an ambiguous or unknown
        part or layer, subsampled R/G/B or Y, chroma sampling other than 1 or 2, degenerate
        chromaticities.
    """
    path = Path(path)
    size = regular_file(path, "OpenEXR file")
    _check_magic(path)
    parts = _read_headers(path)
    _check_sizes(path, parts, size)
    chosen = _choose_part(path, parts, part)
    name, kind, names = _choose_layer(path, chosen, layer, len(parts) > 1)
    display = _box(chosen.header.get("displayWindow", chosen.header["dataWindow"]))
    check_pixels(path, *_box_size(display))
    check_memory(path, size + EXR_PEAK_BYTES_PER_PIXEL * math.prod(_box_size(chosen.data_window))
                 + 12 * math.prod(_box_size(display)), "reading the data and display windows")
    data_window = chosen.data_window
    envmap_kind = _envmap_kind(chosen.header.get("envmap"))
    if check_windows is not None:
        check_windows(_box_size(display), _box_size(data_window), envmap_kind)
    keys = ("R", "G", "B") if kind == "rgb" else ("Y", "RY", "BY") if kind == "yca" else ("Y",)
    for key in keys:
        if key in ("RY", "BY"):
            continue
        xs, ys = chosen.channels[names[key]]
        if (xs, ys) != (1, 1):
            raise BadInputError(path, f"channel {names[key]!r} is subsampled ({xs} x {ys}); not supported")
    planes, library_text = _read_planes(path, chosen, [names[k] for k in keys], len(parts))
    notes: list[str] = []
    h, w = _box_size(data_window)
    for key in keys:
        xs, ys = chosen.channels[names[key]]
        expected = (-(-h // ys), -(-w // xs))
        if planes[names[key]].shape != expected:
            raise BadInputError(
                path, f"channel {names[key]!r} has shape {planes[names[key]].shape}, expected {expected}"
            )
    if kind == "rgb":
        data = np.stack([planes[names[c]] for c in "RGB"], axis=-1).astype(np.float32, copy=False)
    elif kind == "yca":
        data = _yca_to_rgb(path, chosen, names, planes, notes)
    else:
        data = np.repeat(planes[names["Y"]].astype(np.float32)[..., None], 3, axis=-1)
        notes.append("luminance-only (Y) image read as grey")
    pixels = _place(data, data_window, display, notes)
    if library_text.strip():
        notes.append(f"OpenEXR library message: {_first_line(path, library_text)}")
    return ExrImage(
        pixels=pixels, data=data, data_window=data_window, display_window=display, envmap=envmap_kind,
        part=chosen.index, part_name=chosen.name, layer=name, colour=kind, notes=tuple(notes),
    )


def _envmap_kind(envmap: Any) -> str | None:
    """The ``envmap`` attribute as "latlong", "cube", "unknown(…)" or None (absent)."""
    if envmap is None:
        return None
    label = _enum_name(envmap)
    return {"ENVMAP_LATLONG": "latlong", "ENVMAP_CUBE": "cube"}.get(label, f"unknown({label})")


def _place(
    data: np.ndarray, data_window: tuple[int, int, int, int], display: tuple[int, int, int, int], notes: list[str]
) -> np.ndarray:
    """The data window placed on the display window: 0 outside it, cropped to it."""
    if data_window == display:
        return data
    dh, dw = _box_size(display)
    out = np.zeros((dh, dw, 3), dtype=np.float32)
    x0, y0 = max(data_window[0], display[0]), max(data_window[1], display[1])
    x1, y1 = min(data_window[2], display[2]), min(data_window[3], display[3])
    inside = 0
    if x0 <= x1 and y0 <= y1:
        out[y0 - display[1] : y1 - display[1] + 1, x0 - display[0] : x1 - display[0] + 1] = data[
            y0 - data_window[1] : y1 - data_window[1] + 1, x0 - data_window[0] : x1 - data_window[0] + 1
        ]
        inside = (y1 - y0 + 1) * (x1 - x0 + 1)
    cropped = data.shape[0] * data.shape[1] - inside
    notes.append(
        f"data window {data_window} placed in display window {display}"
        + (f"; {cropped} data pixel(s) outside the display window cropped" if cropped else "")
    )
    return out


def read_exr(path: str | Path, *, layer: str | None = None, part: int | str | None = None) -> np.ndarray:
    """Read an OpenEXR file's colour on its display window: :func:`read_exr_image` ``.pixels``.

    Returns
    -------
    numpy.ndarray
        ``(H, W, 3)`` float32 linear RGB, row 0 the top of the display window (0 outside the
        data window).

    Raises
    ------
    BadInputError
        As :func:`read_exr_image`.
    """
    return read_exr_image(path, layer=layer, part=part).pixels


def write_exr(path: str | Path, image: np.ndarray, half: bool = False) -> None:
    """Write an ``(H, W, 3)`` image as a ZIP-compressed scanline OpenEXR, atomically.

    Parameters
    ----------
    path
        Destination file.
    image
        Linear RGB, row 0 at the top.
    half
        Store 16-bit half floats (values above 65504 become infinite: refused) instead of
        32-bit floats (lossless for float32 input).
    """
    path = Path(path)
    image = check_rgb(path, image)
    dtype = np.float16 if half else np.float32
    if half and np.nanmax(np.abs(image)) > float(np.finfo(np.float16).max):
        raise BadInputError(path, "values above 65504 do not fit in half floats; write float32")
    pixels = np.ascontiguousarray(image, dtype=dtype)
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    with atomic_image_path(path) as tmp:
        with OpenEXR.File(header, {"RGB": pixels}) as exr:
            exr.write(str(tmp))
