"""Radiance RGBE / XYZE (``.hdr``) reader and RGBE writer.

The reader returns ``(H, W, 3)`` float32 linear RGB, row 0 at the top, and raises
:class:`BadInputError` naming the file for a missing, truncated, malformed or oversized
file; the writer is atomic. The reading rules (header, resolution line, the three pixel
encodings, colour handling, size checks) are documented in ``data_specs/image_files.md``; the
scanline decoder is in ``_rgbe_decoder.py``.

References
----------
- [Ward91]: the RGBE shared-exponent pixel.
- [Radiance]: ``doc/notes/picture.format`` and the Radiance sources (``src/common``): ``header.c`` (``getheader``: the
  header ends at the first line that is empty or ``"\\r"``; ``formatval``), ``resolu.h`` /
  ``resolu.c`` (resolution line, ``YMAJOR``/``XDECR``/``YDECR``), ``image.c``
  (``pix2loc``: pixel positions), ``color.c`` (``freadcolrs``: new-style run-length
  scanlines; ``oldreadcolrs``: flat and pre-1991 run-length scanlines, chosen per
  scanline), ``color.h`` / ``spec_rgb.c`` (standard primaries, ``xyz2rgbmat``,
  von Kries white balance, ``clipgamut``), ``src/px/ra_xyze.c`` (XYZE and ``PRIMARIES``
  conversion), ``src/px/pvalue.c`` (``-o``: original values divide by ``EXPOSURE`` and
  ``COLORCORR``).
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from pathlib import Path

import numpy as np

from ._rgbe_decoder import _BLOCK_BYTES, _RLE_MAX_WIDTH, _RLE_MIN_WIDTH, _Decoder, _smallest_encoding
from .errors import BadInputError
from .image_common import atomic_image_path, check_rgb
from .limits import check_memory, check_pixels, read_bytes

__all__ = ["read_hdr", "write_hdr"]


#: Peak bytes per pixel while a Radiance picture is decoded, beside the file's own bytes (the RGBE
#: bytes, the float32 result, the decoder's run tables; measured 38 on a 2048 x 1024 map): the
#: memory plan of data_specs/limits.md, checked on the resolution line.
HDR_PEAK_BYTES_PER_PIXEL = 40
_HEADER_END_RE = re.compile(rb"\n\r?\n")  # an empty line, "\n" or "\r\n" (header.c getheader)
_RESOLUTION_RE = re.compile(rb"^\s*([-+])([XY])\s+(\d{1,12})\s+([-+])([XY])\s+(\d{1,12})\s*$")
_NUMBER_RE = re.compile(rb"\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)")
_RESOLUTION_MAX_BYTES = 64  # Radiance reads it into a 32-byte buffer (resolu.h RESOLU_BUFLEN)

# Radiance's standard RGB primaries (color.h "nominal CRT primaries", CIE xy of R, G, B and
# white): Rec.709 red and blue, green x 0.290 (Rec.709: 0.300), equal-energy white.
STANDARD_PRIMARIES = ((0.640, 0.330), (0.290, 0.600), (0.150, 0.060), (1.0 / 3.0, 1.0 / 3.0))
WHITE_EFFICACY = 179.0  # lm/W, color.h WHTEFFICACY: XYZE luminance <-> RGBE radiance
_CEPS = 1e-4  # spec_rgb.c CEPS: chromaticities this close are equal
_VON_KRIES = np.array(  # spec_rgb.c vkmat ("Sharp" primaries), XYZ -> cone-like space
    [[1.2694, -0.0988, -0.1706], [-0.8364, 1.8006, 0.0357], [0.0297, -0.0315, 1.0018]]
)

# mantissa * 2**(e - 136) for e = 1..255 (e = 0: black); exact in float32 (2**-135 is a
# float32 subnormal, and 8 mantissa bits above it stay exact)
_EXPONENT_SCALE = np.concatenate(([0.0], np.ldexp(1.0, np.arange(1, 256) - 136))).astype(np.float32)


def _rgbe_to_float(rgbe: np.ndarray) -> np.ndarray:
    """Decode RGBE pixels: channel = mantissa * 2**(e - 136), zero where e == 0.

    This is Ward's (and stb_image's, OpenCV's) decoding without the half-step offset
    that the Radiance tools add; :func:`_float_to_rgbe` rounds to nearest to match it.
    """
    out = rgbe[..., :3].astype(np.float32)
    out *= _EXPONENT_SCALE[rgbe[..., 3]][..., None]
    return out


def _float_to_rgbe(image: np.ndarray) -> np.ndarray:
    """Encode float RGB as RGBE, mantissas rounded to nearest (relative error <= 2**-8)."""
    rgb = np.maximum(np.asarray(image, dtype=np.float64), 0.0)
    peak = rgb.max(axis=-1)
    _, exponent = np.frexp(peak)  # peak = f * 2**exponent, f in [0.5, 1)
    mantissa = np.rint(np.ldexp(rgb, (8 - exponent)[..., None]))
    bump = mantissa.max(axis=-1) >= 256  # rounding carried into the next binade
    exponent = exponent + bump
    mantissa = np.where(bump[..., None], np.rint(np.ldexp(rgb, (8 - exponent)[..., None])), mantissa)
    biased = exponent + 128
    zero = (peak < 2.0**-128) | (biased <= 0)
    out = np.empty(rgb.shape[:-1] + (4,), dtype=np.uint8)
    out[..., :3] = np.where(zero[..., None], 0, np.clip(mantissa, 0, 255)).astype(np.uint8)
    out[..., 3] = np.where(zero, 0, np.clip(biased, 0, 255)).astype(np.uint8)
    return out


# ------------------------------------------------------------------------------------------- colour
def _white_xyz(xy: tuple[float, float]) -> np.ndarray:
    x, y = xy
    return np.array([x / y, 1.0, (1.0 - x - y) / y])


def _rgb_to_xyz_matrix(primaries) -> np.ndarray:
    """RGB -> XYZ for primaries ((xr, yr), (xg, yg), (xb, yb), (xw, yw)); RGB (1, 1, 1) maps
    to the white with Y = 1 (the same matrix as spec_rgb.c ``comprgb2xyzmat``)."""
    chroma = np.array([[x, y, 1.0 - x - y] for x, y in primaries[:3]]).T  # columns: R, G, B
    return chroma * np.linalg.solve(chroma, _white_xyz(primaries[3]))[None, :]


def _von_kries(white_from, white_to) -> np.ndarray:
    """XYZ -> XYZ von Kries adaptation between two white points (spec_rgb.c ``compxyzWBmat``,
    with the exact inverse of ``vkmat`` where Radiance uses a 4-digit table)."""
    ratio = (_VON_KRIES @ _white_xyz(white_to)) / (_VON_KRIES @ _white_xyz(white_from))
    return np.linalg.solve(_VON_KRIES, ratio[:, None] * _VON_KRIES)


_XYZ_TO_STANDARD = np.linalg.inv(_rgb_to_xyz_matrix(STANDARD_PRIMARIES))  # color.h/spec_rgb.c xyz2rgbmat
_STANDARD_BRIGHTNESS = _rgb_to_xyz_matrix(STANDARD_PRIMARIES)[1]  # color.h CIE_rf, CIE_gf, CIE_bf


def _primaries_matrix(primaries) -> np.ndarray | None:
    """File RGB -> standard RGB (ra_xyze: ``comprgb2rgbWBmat``, then ``clipgamut``).

    None (no conversion) when the primaries are the standard ones within Radiance's
    tolerance 1e-4 (Radiance writes them with 4 decimals), and when they do not define a
    colour space (spec_rgb.c ``colorprimsOK`` fails, e.g. Photoshop's ``PRIMARIES=0 0 0 0 0
    0 0 0``): such a line says nothing, and the pixels are taken as standard RGB.
    """
    points = np.array(primaries, dtype=np.float64)
    if np.abs(points - np.array(STANDARD_PRIMARIES)).max() <= _CEPS:
        return None
    (xw, yw), rgb = points[3], points[:3]
    distinct = all(np.abs(points[i] - points[j]).max() > _CEPS for i in range(4) for j in range(i + 1, 4))
    sane = (
        _CEPS < xw < 1 - _CEPS
        and _CEPS < yw < 1 - _CEPS
        and bool(np.all((rgb > -2) & (rgb < 3) & (rgb.sum(axis=1)[:, None] > -2) & (rgb.sum(axis=1)[:, None] < 3)))
    )
    if not (distinct and sane):
        return None
    try:
        with np.errstate(all="ignore"):
            matrix = _XYZ_TO_STANDARD @ _von_kries(primaries[3], STANDARD_PRIMARIES[3]) @ _rgb_to_xyz_matrix(primaries)
    except np.linalg.LinAlgError:  # primaries on one line
        return None
    return matrix if np.all(np.isfinite(matrix)) else None


def _clip_gamut(block: np.ndarray) -> None:
    """Radiance ``clipgamut(col, bright(col), CGAMUT_LOWER, cblack, cwhite)`` in place: a colour
    with a negative channel is desaturated toward the grey of the same brightness until its
    lowest channel is 0 (brightness = luminance kept); negative brightness becomes black."""
    r, g, b = block[..., 0], block[..., 1], block[..., 2]  # (channel-wise: reductions over 3 are slow)
    outside = (r < 0) | (g < 0) | (b < 0)
    if not outside.any():
        return
    weight = _STANDARD_BRIGHTNESS.astype(np.float32)
    brightness = weight[0] * r + weight[1] * g + weight[2] * b
    keep = np.ones_like(brightness)
    with np.errstate(divide="ignore", invalid="ignore"):
        for channel in (r, g, b):
            np.minimum(keep, np.where(channel < 0, brightness / (brightness - channel), 1.0), out=keep)
    np.clip(keep, 0.0, 1.0, out=keep)
    keep[brightness <= 0] = 0.0  # black: below brtmin
    brightness[brightness <= 0] = 0.0
    for channel in (r, g, b):
        clipped = np.maximum(keep * channel + (1 - keep) * brightness, 0.0)
        np.copyto(channel, clipped, where=outside)


# ------------------------------------------------------------------------------------------- header
class _Header:
    """What the header and resolution line of a Radiance picture say."""

    __slots__ = ("xyz", "exposure", "colorcorr", "primaries", "ymajor", "xdecr", "ydecr", "width", "height", "pos")
    xyz: bool  # pixels are XYZE (FORMAT=32-bit_rle_xyze), not RGBE
    exposure: float  # product of the EXPOSURE= lines
    colorcorr: list[float]  # product of the COLORCORR= lines, per channel
    primaries: tuple[tuple[float, float], ...] | None  # PRIMARIES= (x, y) of R, G, B, white
    ymajor: bool  # resolution line starts with Y: scanlines run along X
    xdecr: bool
    ydecr: bool
    width: int
    height: int
    pos: int  # byte offset of the first scanline

    @property
    def scanlines(self) -> int:
        return self.height if self.ymajor else self.width

    @property
    def scanline_length(self) -> int:
        return self.width if self.ymajor else self.height


def _numbers(path: Path, line: bytes, key: str, count: int) -> list[float]:
    """``count`` leading numbers of a header value, read like C ``atof``/``sscanf``."""
    values, pos = [], len(key)
    for _ in range(count):
        match = _NUMBER_RE.match(line, pos)
        if not match:
            raise BadInputError(path, f"bad {key[:-1]} line {line[:80].decode(errors='replace')!r}")
        values.append(float(match.group(1)))
        pos = match.end()
    return values


def _parse_header(path: Path, data: bytes) -> _Header:
    """The header (magic, FORMAT, EXPOSURE, COLORCORR, PRIMARIES) and the resolution line."""
    if not data.startswith(b"#?"):
        raise BadInputError(path, "not a Radiance .hdr file (missing '#?RADIANCE' magic)")
    end = _HEADER_END_RE.search(data)
    if end is None:
        raise BadInputError(path, "truncated Radiance header (no empty line ending the header)")
    head = _Header()
    head.xyz = False
    head.exposure = 1.0
    head.colorcorr = [1.0, 1.0, 1.0]
    head.primaries = None
    for raw in data[: end.start()].split(b"\n")[1:]:
        _header_line(path, raw.rstrip(b"\r"), head)
    if not (math.isfinite(head.exposure) and head.exposure > 0):
        raise BadInputError(path, f"EXPOSURE product {head.exposure:g} is not a positive number")
    if not all(math.isfinite(c) and c > 0 for c in head.colorcorr):
        raise BadInputError(path, f"COLORCORR product {' '.join(f'{c:g}' for c in head.colorcorr)} is not positive")
    _resolution_line(path, data, end.end(), head)
    return head


def _header_line(path: Path, line: bytes, head: _Header) -> None:
    """One header line into ``head``: FORMAT (RGBE or XYZE), EXPOSURE and COLORCORR (products),
    PRIMARIES (a line Radiance cannot read is ignored); other lines do not change pixel values."""
    if line.startswith(b"FORMAT="):
        value = line[7:].split()
        fmt = value[0] if value else b""
        if fmt in (b"32-bit_rle_rgbe", b"32-bit_rle_xyze"):
            head.xyz = fmt == b"32-bit_rle_xyze"
        else:
            raise BadInputError(
                path,
                f"unsupported Radiance pixel format {line[:60].decode(errors='replace')!r} "
                "(need 32-bit_rle_rgbe or 32-bit_rle_xyze)",
            )
    elif line.startswith(b"EXPOSURE="):
        head.exposure *= _numbers(path, line, "EXPOSURE=", 1)[0]
    elif line.startswith(b"COLORCORR="):
        head.colorcorr = [a * b for a, b in zip(head.colorcorr, _numbers(path, line, "COLORCORR=", 3), strict=True)]
    elif line.startswith(b"PRIMARIES="):
        try:
            values = _numbers(path, line, "PRIMARIES=", 8)
        except BadInputError:  # Radiance's primsval() fails: the line is ignored
            return
        head.primaries = tuple(zip(values[0::2], values[1::2], strict=True))
    # PIXASPECT=, VIEW=, SOFTWARE=, CAPDATE=, GAMMA= ... do not change pixel values


def _resolution_line(path: Path, data: bytes, start: int, head: _Header) -> None:
    """The resolution line at ``start`` into ``head``: size, scanline axis, axis directions and the
    offset of the first scanline (any of the eight orientations, ``resolu.c``)."""
    stop = data.find(b"\n", start, start + _RESOLUTION_MAX_BYTES)
    if stop < 0:
        if len(data) - start < _RESOLUTION_MAX_BYTES:
            raise BadInputError(path, "truncated Radiance file (no resolution line after the header)")
        stop = start + _RESOLUTION_MAX_BYTES
    match = _RESOLUTION_RE.match(data[start:stop])
    if not match or match.group(2) == match.group(5):
        text = data[start:stop][:40].decode(errors="replace")
        raise BadInputError(
            path, f"unsupported Radiance resolution line {text!r} (need e.g. '-Y H +X W' or '+X W -Y H')"
        )
    first = (match.group(1), match.group(2), int(match.group(3)))
    second = (match.group(4), match.group(5), int(match.group(6)))
    x_axis, y_axis = (second, first) if first[1] == b"Y" else (first, second)
    head.ymajor = first[1] == b"Y"  # resolu.c str2resolu: Y first -> scanlines run along X
    head.xdecr = x_axis[0] == b"-"
    head.ydecr = y_axis[0] == b"-"
    head.width, head.height = x_axis[2], y_axis[2]
    head.pos = stop + 1

# ------------------------------------------------------------------------------------------- reading
def read_hdr(path: str | Path, check_shape: Callable[[int, int], None] | None = None) -> np.ndarray:
    """Read a Radiance picture (RGBE or XYZE; new-style run-length, pre-1991 run-length or flat).

    Follows the Radiance library (``header.c``, ``resolu.c``, ``color.c``):

    - Header: starts with ``#?`` and ends at the first empty line, ``\\n`` or ``\\r\\n``.
      ``FORMAT=32-bit_rle_rgbe`` (default) or ``32-bit_rle_xyze``; pixel values are
      divided by the product of the ``EXPOSURE=`` lines and, per channel, of the
      ``COLORCORR=`` lines (``pvalue -o``: original values). ``PRIMARIES=`` (RGBE only)
      converts from the given primaries to Radiance's standard ones, with von Kries white
      adaptation; XYZE converts with Radiance's ``xyz2rgbmat`` and divides by the white
      luminous efficacy 179 lm/W (both as ``ra_xyze -r``), then colours outside the RGB
      gamut are desaturated to it (``clipgamut``). ``PIXASPECT=`` and other lines are
      ignored.
    - Resolution line: any of the eight orientations ``±Y H ±X W`` / ``±X W ±Y H``; the
      first axis is the slow one, ``-`` means decreasing (Y grows upward).
    - Scanlines: new-style run-length, pre-1991 run-length (repeat pixels ``1 1 1 n``) or
      flat, decided per scanline.

    Pixels decode as mantissa · 2^(e − 136) (Ward; no ½ offset). The standard RGB is
    Rec.709 red and blue, green at x = 0.290 and equal-energy white (Radiance ``color.h``).

    Parameters
    ----------
    path
        A regular file (FIFOs and devices are refused without opening them).
    check_shape
        Optional ``check_shape(height, width)`` called on the resolution line, before a scanline is
        decoded (an environment map's 2:1 rule: a 17 MB run-length file may declare 2²⁸ pixels).

    Returns
    -------
    numpy.ndarray
        ``(H, W, 3)`` float32 linear RGB, finite; row 0 at the top, column 0 at the left.
        Units as stored (Radiance: W·sr⁻¹·m⁻² per channel) after the header scalings.

    Raises
    ------
    BadInputError
        Not a regular file or over ``SHRM_MAX_FILE_BYTES``; not a Radiance picture; an
        unsupported ``FORMAT``, unreadable ``EXPOSURE``/``COLORCORR``/``PRIMARIES`` or
        resolution line; W·H over ``SHRM_MAX_PIXELS``; a planned peak over
        ``SHRM_MAX_MEMORY_BYTES`` (:data:`HDR_PEAK_BYTES_PER_PIXEL`); fewer bytes than the most compact
        encoding of the declared size (checked before anything is allocated); truncated
        or corrupt scanlines; values that overflow float32 after the scalings.

    Examples
    --------
    ``tests/resources/tiny_4x8.hdr`` (4 × 8, run-length encoded, ``-Y 4 +X 8``) holds
    pixel (i, j) = ((j + 1)/8, (i + 1)/4, (i + j + 1)/16), values RGBE stores exactly:

    >>> image = read_hdr("tests/resources/tiny_4x8.hdr")
    >>> image.shape, image.dtype
    ((4, 8, 3), dtype('float32'))
    >>> image[1, 6]
    array([0.875, 0.5  , 0.5  ], dtype=float32)
    >>> image[3, 0]
    array([0.125, 1.   , 0.25 ], dtype=float32)
    """
    path = Path(path)
    data = read_bytes(path, "image")
    head = _parse_header(path, data)
    _check_size(path, head, len(data), check_shape)
    rgbe = _Decoder(path, data, head.pos, head.scanlines, head.scanline_length).run()
    del data
    matrix, transform = _pixel_transform(path, head)
    image = np.empty((head.height, head.width, 3), dtype=np.float32)
    target = image if head.ydecr else image[::-1]  # pix2loc: row 0 of the result is the top
    if head.xdecr:
        target = target[:, ::-1]
    if not head.ymajor:
        target = target.transpose(1, 0, 2)  # scanlines are columns
    _scale_into(path, target, rgbe, matrix, transform)
    return image


def _check_size(path: Path, head: _Header, n_bytes: int, check_shape: Callable[[int, int], None] | None) -> None:
    """The declared size against the pixel limit, ``check_shape``, the bytes the file holds after
    the header (the most compact encoding of every scanline) and the memory limit."""
    check_pixels(path, head.height, head.width)
    if check_shape is not None:
        check_shape(head.height, head.width)
    scanlines, length = head.scanlines, head.scanline_length
    available, needed = n_bytes - head.pos, scanlines * _smallest_encoding(length)
    if available < needed:
        raise BadInputError(
            path,
            f"truncated RGBE data: {available:,} bytes after the header, but {scanlines:,} scanlines of "
            f"{length:,} pixels need at least {needed:,} in any encoding",
        )
    check_memory(path, n_bytes + HDR_PEAK_BYTES_PER_PIXEL * head.height * head.width,
                 f"decoding {head.width} x {head.height} pixels")


def _pixel_transform(path: Path, head: _Header) -> tuple[np.ndarray | None, np.ndarray | np.float32 | None]:
    """The header's scalings as (colour matrix or None, transform): per-channel division by
    EXPOSURE × COLORCORR, then the XYZE or PRIMARIES matrix; the transform is the float32 (3, 3)
    matrix over the divisors, one divisor for all channels, three divisors, or None (none to apply)."""
    divisor = [head.exposure * c for c in head.colorcorr]
    if not all(math.isfinite(d) and d > 0 for d in divisor):
        raise BadInputError(path, f"EXPOSURE x COLORCORR = {' '.join(f'{d:g}' for d in divisor)} is not finite and > 0")
    matrix = None
    if head.xyz:
        matrix = _XYZ_TO_STANDARD / WHITE_EFFICACY
    elif head.primaries is not None:
        matrix = _primaries_matrix(head.primaries)
    with np.errstate(over="ignore", under="ignore"):  # overflow shows as non-finite pixels below
        if matrix is not None:
            transform = (matrix / np.array(divisor)[None, :]).T.astype(np.float32)
        elif divisor[0] == divisor[1] == divisor[2]:
            transform = None if divisor[0] == 1.0 else np.float32(divisor[0])
        else:
            transform = np.array(divisor, dtype=np.float32)
    return matrix, transform


def _scale_into(path: Path, target: np.ndarray, rgbe: np.ndarray, matrix: np.ndarray | None,
                transform: np.ndarray | np.float32 | None) -> None:
    """Decoded RGBE scanlines (n, length, 4) uint8 into ``target`` (n, length, 3) float32, block by
    block, with the header's scalings (:func:`_pixel_transform`); BadInputError on overflow."""
    scanlines, length = rgbe.shape[:2]
    step = max(1, _BLOCK_BYTES // (4 * length))
    for s0 in range(0, scanlines, step):
        pixels = rgbe[s0 : s0 + step]
        if transform is None:  # straight into the result
            rows = target[s0 : s0 + step]
            rows[...] = pixels[..., :3]
            rows *= _EXPONENT_SCALE[pixels[..., 3]][..., None]
            continue
        block = _rgbe_to_float(pixels)
        with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
            if matrix is not None:
                block = block @ transform
                _clip_gamut(block)
            else:
                block /= transform
        if not np.all(np.isfinite(block)):
            raise BadInputError(path, "pixel values overflow float32 after EXPOSURE / COLORCORR / colour conversion")
        target[s0 : s0 + step] = block


# ------------------------------------------------------------------------------------------- writing
def _encode_rle_component(values: np.ndarray, out: bytearray) -> None:
    """Append one component of one scanline as RLE chunks (runs of >= 4 equal bytes)."""
    n = values.size
    boundaries = np.flatnonzero(values[1:] != values[:-1]) + 1
    run_start = np.concatenate(([0], boundaries))
    run_len = np.diff(np.concatenate((run_start, [n])))
    long_runs = np.flatnonzero(run_len >= 4)
    raw = values.tobytes()
    cursor = 0
    for k in long_runs:
        s, length = int(run_start[k]), int(run_len[k])
        for lit in range(cursor, s, 128):  # literal stretch before the run
            piece = raw[lit : min(lit + 128, s)]
            out.append(len(piece))
            out += piece
        while length > 0:
            take = min(length, 127)
            out.append(128 + take)
            out.append(raw[s])
            length -= take
        cursor = s + int(run_len[k])
    for lit in range(cursor, n, 128):
        piece = raw[lit : min(lit + 128, n)]
        out.append(len(piece))
        out += piece


def write_hdr(path: str | Path, image: np.ndarray, rle: bool = True) -> None:
    """Write a Radiance RGBE picture (``-Y H +X W``, ``FORMAT=32-bit_rle_rgbe``), atomically.

    Parameters
    ----------
    path
        Destination file; its folder must exist.
    image
        ``(H, W, 3)`` non-negative finite linear RGB, row 0 at the top; each pixel keeps
        about 8 bits of mantissa relative to its largest channel (relative error <= 0.4 %
        there). Values must stay below 2**127.
    rle
        Use new-style run-length encoding (only possible for widths 8..32767; other
        widths are written flat).

    Raises
    ------
    BadInputError
        Wrong shape or dtype, negative / non-finite / too large values, missing folder.
    """
    path = Path(path)
    image = check_rgb(path, image)
    if not np.all(np.isfinite(image)) or np.any(image < 0):
        raise BadInputError(path, "RGBE cannot store negative or non-finite values")
    if np.max(image) >= 2.0**127:
        raise BadInputError(path, f"value {np.max(image):g} exceeds the RGBE range")
    height, width = image.shape[:2]
    rgbe = _float_to_rgbe(image)
    body = bytearray()
    if rle and _RLE_MIN_WIDTH <= width <= _RLE_MAX_WIDTH:
        line_header = bytes((2, 2, width >> 8, width & 255))
        for row in range(height):
            body += line_header
            for component in range(4):
                _encode_rle_component(rgbe[row, :, component], body)
    else:
        body += rgbe.tobytes()
    header = f"#?RADIANCE\n# written by shrmkit\nFORMAT=32-bit_rle_rgbe\n\n-Y {height} +X {width}\n"
    with atomic_image_path(path) as tmp:
        tmp.write_bytes(header.encode("ascii") + bytes(body))
