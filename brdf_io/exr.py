"""OpenEXR reader and writer (through the ``OpenEXR`` 3.x Python bindings) [OpenEXR].

:func:`read_exr_image` reads the colour of one part and one layer of a scanline or tiled OpenEXR
file (single- or multi-part, any resolution level mode: level 0 is read) as an :class:`ExrImage`
on the display window, refusing what it cannot read with one :class:`BadInputError` line naming
the file; :func:`read_exr` returns the pixels only; :func:`write_exr` writes a ZIP scanline file
atomically. The rules (part, layer, colour, windows, size checks before any pixel is read):
``data_specs/environment_maps.md`` §2.1.
"""

from __future__ import annotations

import contextlib
import io
import math
import os
import sys
import tempfile
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import OpenEXR

from .errors import BadInputError
from .image_common import atomic_image_path, check_rgb
from .limits import check_elements, check_memory, check_pixels, regular_file

__all__ = ["ExrImage", "read_exr_image", "read_exr", "write_exr", "luminance_weights", "REC709_CHROMATICITIES"]

_MAGIC = b"\x76\x2f\x31\x01"

#: Rec. ITU-R BT.709 primaries and D65 white, (x, y) of red, green, blue, white: OpenEXR's
#: default ``Chromaticities`` (ImfChromaticities.h), used when a file has no attribute.
REC709_CHROMATICITIES = (0.6400, 0.3300, 0.3000, 0.6000, 0.1500, 0.0600, 0.3127, 0.3290)

# OpenEXR's chroma reconstruction filter (ImfRgbaYca.cpp, reconstructChromaHoriz/Vert):
# a missing sample at odd position p is Σ_m w_m (c(p − 1 − 2m) + c(p + 1 + 2m)), m = 0..6.
_CHROMA_TAPS = np.array([0.627123, -0.186077, 0.087929, -0.043159, 0.019597, -0.007540, 0.002128])

# scan lines per chunk by compression (OpenEXR file layout); unknown methods count as 256,
# which only weakens the lower bound on the file size
_LINES_PER_CHUNK = {
    "NO_COMPRESSION": 1, "RLE_COMPRESSION": 1, "ZIPS_COMPRESSION": 1, "ZIP_COMPRESSION": 16,
    "PIZ_COMPRESSION": 32, "PXR24_COMPRESSION": 16, "B44_COMPRESSION": 32, "B44A_COMPRESSION": 32,
    "DWAA_COMPRESSION": 32, "DWAB_COMPRESSION": 256,
}
# every chunk costs at least its 8-byte offset-table entry plus an 8-byte leader (y and size)
_MIN_BYTES_PER_CHUNK = 16
_MAX_CAPTURED_BYTES = 1 << 16


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
# library messages
# --------------------------------------------------------------------------------------
class _Captured:
    text = ""


@contextlib.contextmanager
def _library_output() -> Iterator[_Captured]:
    """Capture what the OpenEXR C library writes to file descriptor 2 and what the bindings
    print on Python's stdout, for the duration of the block; the text lands in ``.text``.

    fd 2 is process-wide: output of other threads during the block is captured too."""
    captured = _Captured()
    buffer = io.StringIO()
    with contextlib.suppress(AttributeError, ValueError, OSError):
        sys.stderr.flush()
    saved = tmp = None
    try:
        tmp = tempfile.TemporaryFile()
        saved = os.dup(2)
        os.dup2(tmp.fileno(), 2)
    except OSError:  # no fd 2 to redirect: let the library write where it writes
        if saved is not None:
            os.close(saved)
        if tmp is not None:
            tmp.close()
        saved = tmp = None
    try:
        with contextlib.redirect_stdout(buffer):
            yield captured
    finally:
        text = ""
        if saved is not None:
            os.dup2(saved, 2)
            os.close(saved)
        if tmp is not None:
            tmp.seek(0)
            text = tmp.read(_MAX_CAPTURED_BYTES).decode("utf-8", "replace")
            tmp.close()
        captured.text = text + buffer.getvalue()


def _first_line(path: Path, *texts: str) -> str:
    """First non-empty line of the first text that has one, without a leading "<path>: "."""
    for text in texts:
        for line in text.splitlines():
            line = line.strip()
            for prefix in (f"{path}: ", f"{path.name}: "):
                if line.startswith(prefix):
                    line = line[len(prefix) :]
            if line:
                return line if len(line) <= 300 else line[:297] + "..."
    return "unknown error"


# --------------------------------------------------------------------------------------
# header checks
# --------------------------------------------------------------------------------------
def _box(value: Any) -> tuple[int, int, int, int]:
    lo, hi = value
    return int(lo[0]), int(lo[1]), int(hi[0]), int(hi[1])


def _box_size(box: tuple[int, int, int, int]) -> tuple[int, int]:
    """(height, width) of an inclusive box (≤ 0 when empty)."""
    return box[3] - box[1] + 1, box[2] - box[0] + 1


def _enum_name(value: Any) -> str:
    return str(getattr(value, "name", value))


def _part_label(index: int, name: str) -> str:
    return f"part {index}" + (f" {name!r}" if name else "")


@dataclass(frozen=True)
class _Part:
    index: int
    name: str
    header: dict
    channels: dict[str, tuple[int, int]]  # name -> (xSampling, ySampling)

    @property
    def storage(self) -> str:
        return _enum_name(self.header.get("type", "scanlineimage"))

    @property
    def data_window(self) -> tuple[int, int, int, int]:
        return _box(self.header["dataWindow"])

    @property
    def label(self) -> str:
        return _part_label(self.index, self.name)


def _read_headers(path: Path) -> list[_Part]:
    try:
        with _library_output() as out, OpenEXR.File(str(path), header_only=True) as exr:
            parts = []
            for i, part in enumerate(exr.parts):
                header = dict(exr.header(i))
                channels = {
                    str(ch.name): (int(ch.xSampling), int(ch.ySampling)) for ch in header.get("channels", [])
                }
                name = str(header.get("name", "") or part.name() or "")
                parts.append(_Part(i, name, header, channels))
    except Exception as err:  # the bindings raise RuntimeError/ValueError/... for bad files
        raise BadInputError(path, f"not a readable OpenEXR file ({_first_line(path, out.text, str(err))})") from None
    if not parts:
        raise BadInputError(path, f"not a readable OpenEXR file ({_first_line(path, out.text, 'no parts')})")
    return parts


def _check_sizes(path: Path, parts: list[_Part], size: int) -> None:
    """Refuse, from the headers alone, deep parts and declared sizes beyond the limits or
    beyond what ``size`` bytes can hold (one offset entry + chunk leader per chunk)."""
    deep = [p for p in parts if p.storage.startswith("deep")]
    if deep:
        raise BadInputError(
            path, "deep OpenEXR images are not environment maps ("
            + ", ".join(f"{p.label} is {p.storage}" for p in deep) + ")",
        )
    elements = 0
    chunks = 0
    for p in parts:
        source = path if len(parts) == 1 else f"{path} ({p.label})"
        if "dataWindow" not in p.header:
            raise BadInputError(source, "OpenEXR header has no dataWindow")
        h, w = _box_size(p.data_window)
        check_pixels(source, h, w)
        for name, (xs, ys) in p.channels.items():
            if xs < 1 or ys < 1:
                raise BadInputError(source, f"channel {name!r} has sampling {xs} x {ys}")
            elements += -(-w // xs) * -(-h // ys)
        tiles = p.header.get("tiles")
        if p.storage == "tiledimage" and tiles is not None:
            tx, ty = max(int(tiles.xSize), 1), max(int(tiles.ySize), 1)
            chunks += -(-w // tx) * -(-h // ty)
        else:
            chunks += -(-h // _LINES_PER_CHUNK.get(_enum_name(p.header.get("compression")), 256))
    check_elements(path, (elements,), "OpenEXR pixel data (all parts and channels)")
    # the memory plan (data_specs/limits.md): the file, every channel decoded (float32 at most)
    check_memory(path, size + 4 * elements, f"decoding {elements:,} OpenEXR channel samples")
    if chunks * _MIN_BYTES_PER_CHUNK > size:
        raise BadInputError(
            path, f"file of {size:,} bytes is too small for the {chunks:,} chunks its header declares "
            f"(at least {chunks * _MIN_BYTES_PER_CHUNK:,} bytes): truncated or corrupt",
        )


# --------------------------------------------------------------------------------------
# part and layer choice
# --------------------------------------------------------------------------------------
def _layers(channels: dict[str, tuple[int, int]]) -> dict[str, dict[str, str]]:
    """layer prefix -> {upper-case suffix: full channel name}; ``""`` for unprefixed names."""
    layers: dict[str, dict[str, str]] = {}
    for name in sorted(channels):
        prefix, _, suffix = name.rpartition(".")
        layers.setdefault(prefix, {}).setdefault(suffix.upper(), name)
    return layers


def _colour_kind(suffixes: dict[str, str]) -> str | None:
    if all(c in suffixes for c in ("R", "G", "B")):
        return "rgb"
    if all(c in suffixes for c in ("Y", "RY", "BY")):
        return "yca"
    if "Y" in suffixes:
        return "y"
    return None


def _colour_layers(part: _Part) -> list[str]:
    return [name for name, suffixes in _layers(part.channels).items() if _colour_kind(suffixes)]


def _describe_layers(names: list[str]) -> str:
    return ", ".join(repr(n) if n else "'' (unprefixed)" for n in names)


def _choose_part(path: Path, parts: list[_Part], part: int | str | None) -> _Part:
    def listing() -> str:
        return "; ".join(
            f"{p.label}: " + (f"colour layers {_describe_layers(_colour_layers(p))}" if _colour_layers(p)
                              else f"channels {sorted(p.channels)}")
            for p in parts
        )

    if part is not None:
        if isinstance(part, bool) or not isinstance(part, (int, str, np.integer)):
            raise BadInputError(path, f"part={part!r}: give a part name or index")
        if isinstance(part, str):
            named = [p for p in parts if p.name == part]
            if named:
                return named[0]
            if not part.strip().lstrip("-").isdigit():
                raise BadInputError(path, f"no part named {part!r}; parts: {listing()}")
            part = int(part.strip())
        index = int(part)
        if not 0 <= index < len(parts):
            raise BadInputError(path, f"part index {index} out of range (file has {len(parts)} part(s)): {listing()}")
        return parts[index]
    colour = [p for p in parts if _colour_layers(p)]
    if len(colour) == 1:
        return colour[0]
    if not colour:
        raise BadInputError(path, f"OpenEXR file has no R, G, B (or Y) channels; {listing()}")
    raise BadInputError(
        path, f"OpenEXR file has {len(colour)} parts with colour channels; choose one with "
        f"part=NAME|INDEX: {listing()}",
    )


def _choose_layer(path: Path, part: _Part, layer: str | None, multipart: bool) -> tuple[str, str, dict[str, str]]:
    """(layer, colour kind, {suffix: channel name}) of the chosen layer."""
    layers = _layers(part.channels)
    colour = [name for name, suffixes in layers.items() if _colour_kind(suffixes)]
    where = f" in {part.label}" if multipart else ""
    if layer is not None:
        if not isinstance(layer, str):
            raise BadInputError(path, f"layer={layer!r}: give a layer name")
        wanted = layer[:-1] if layer.endswith(".") else layer
        if wanted not in layers:
            folded = [name for name in layers if name.lower() == wanted.lower()]
            if len(folded) != 1:
                raise BadInputError(
                    path, f"no layer {layer!r}{where}; layers with colour: {_describe_layers(colour) or 'none'}"
                )
            wanted = folded[0]
        kind = _colour_kind(layers[wanted])
        if kind is None:
            raise BadInputError(
                path, f"layer {layer!r}{where} has no R, G, B (or Y) channels: {sorted(layers[wanted].values())}"
            )
        return wanted, kind, layers[wanted]
    if "" in layers and _colour_kind(layers[""]):
        return "", _colour_kind(layers[""]) or "", layers[""]
    if len(colour) == 1:
        return colour[0], _colour_kind(layers[colour[0]]) or "", layers[colour[0]]
    if not colour:
        raise BadInputError(
            path, f"OpenEXR file has no R, G, B (or Y) channels{where}; channels: {sorted(part.channels)}"
        )
    raise BadInputError(
        path, f"OpenEXR file has no plain R, G, B channels{where} and {len(colour)} layers with colour: "
        f"{_describe_layers(colour)}; choose one with layer=NAME",
    )


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
