"""Radiance RGBE (``.hdr``) reader and writer.

The reader returns ``(H, W, 3)`` float32 linear RGB, row 0 at the top, and raises
:class:`BadInputError` naming the file for a missing, truncated or malformed file; the
writer is atomic.

References
----------
- G. Ward, "Real Pixels", Graphics Gems II (1991) 80-83: the RGBE shared-exponent pixel.
- Radiance file formats, https://radiance-online.org/learning/documentation/manual-pages
  (``picture`` format: header, resolution string, run-length encodings).
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from .errors import BadInputError
from .image_common import atomic_image_path, check_rgb
from .limits import read_bytes

__all__ = ["read_hdr", "write_hdr"]


_RESOLUTION_RE = re.compile(rb"^([-+])Y (\d+) ([-+])X (\d+)$")
_RLE_MIN_WIDTH, _RLE_MAX_WIDTH = 8, 32767


def _rgbe_to_float(rgbe: np.ndarray) -> np.ndarray:
    """Decode RGBE pixels: channel = mantissa * 2**(e - 136), zero where e == 0.

    This is Ward's (and stb_image's, OpenCV's) decoding without the half-step offset
    that the Radiance tools add; :func:`_float_to_rgbe` rounds to nearest to match it.
    """
    exponent = rgbe[..., 3].astype(np.int32)
    scale = np.where(exponent > 0, np.ldexp(np.float32(1.0), exponent - 136), 0.0).astype(np.float32)
    return rgbe[..., :3].astype(np.float32) * scale[..., None]


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


def _parse_hdr_header(path: Path, data: bytes) -> tuple[int, int, bool, bool, float, int]:
    """Return (height, width, flip_rows, flip_cols, exposure, data offset)."""
    if not (data.startswith(b"#?RADIANCE") or data.startswith(b"#?RGBE")):
        raise BadInputError(path, "not a Radiance .hdr file (missing '#?RADIANCE' magic)")
    end = data.find(b"\n\n")
    if end < 0:
        raise BadInputError(path, "truncated Radiance header (no blank line ending the header)")
    exposure = 1.0
    for line in data[:end].split(b"\n")[1:]:
        if line.startswith(b"FORMAT=") and line.strip() != b"FORMAT=32-bit_rle_rgbe":
            raise BadInputError(path, f"unsupported Radiance pixel format {line.decode(errors='replace')!r}")
        if line.startswith(b"EXPOSURE="):
            try:
                exposure *= float(line[9:])
            except ValueError:
                raise BadInputError(path, f"bad EXPOSURE line {line.decode(errors='replace')!r}") from None
    res_end = data.find(b"\n", end + 2)
    if res_end < 0:
        raise BadInputError(path, "truncated Radiance file (no resolution line)")
    match = _RESOLUTION_RE.match(data[end + 2 : res_end].strip())
    if not match:
        line = data[end + 2 : res_end][:40].decode(errors="replace")
        raise BadInputError(path, f"unsupported Radiance resolution line {line!r} (need '[-+]Y H [-+]X W')")
    height, width = int(match.group(2)), int(match.group(4))
    if height == 0 or width == 0:
        raise BadInputError(path, f"zero-size image ({width} x {height})")
    if not (np.isfinite(exposure) and exposure > 0):
        raise BadInputError(path, f"EXPOSURE product {exposure} is not positive")
    return height, width, match.group(1) == b"+", match.group(3) == b"-", exposure, res_end + 1


def _decode_rle(path: Path, buf: bytes, pos: int, height: int, width: int) -> np.ndarray:
    """Decode new-style run-length-encoded scanlines into (height, width, 4) uint8.

    Each scanline starts with the bytes 2, 2, width >> 8, width & 255; then the four
    components follow one after another, each as chunks: a count byte c > 128 followed
    by one value repeated c - 128 times, or 0 < c <= 128 followed by c literal bytes.
    The Python loop only walks the chunk headers; the bytes are gathered with numpy.
    """
    n_total = len(buf)
    starts: list[int] = []  # source offset of each chunk's first value byte
    counts: list[int] = []  # output bytes of each chunk
    runs: list[bool] = []
    for row in range(height):
        if pos + 4 > n_total:
            raise BadInputError(path, f"truncated RLE data at scanline {row} of {height}")
        if buf[pos] != 2 or buf[pos + 1] != 2 or (buf[pos + 2] << 8 | buf[pos + 3]) != width:
            raise BadInputError(path, f"corrupt RLE data: bad scanline header at scanline {row}")
        pos += 4
        for _component in range(4):
            filled = 0
            while filled < width:
                if pos >= n_total:
                    raise BadInputError(path, f"truncated RLE data at scanline {row} of {height}")
                c = buf[pos]
                if c > 128:
                    c -= 128
                    starts.append(pos + 1)
                    runs.append(True)
                    pos += 2
                elif c > 0:
                    starts.append(pos + 1)
                    runs.append(False)
                    pos += 1 + c
                else:
                    raise BadInputError(path, f"corrupt RLE data: zero-length chunk at scanline {row}")
                counts.append(c)
                filled += c
            if filled != width or pos > n_total:
                raise BadInputError(path, f"corrupt or truncated RLE data at scanline {row}")
    start = np.asarray(starts, dtype=np.int64)
    count = np.asarray(counts, dtype=np.int64)
    chunk_of = np.repeat(np.arange(len(count)), count)
    first_out = np.cumsum(count) - count
    offset = np.arange(chunk_of.size, dtype=np.int64) - first_out[chunk_of]
    offset[np.asarray(runs, dtype=bool)[chunk_of]] = 0  # a run repeats its one value byte
    source = np.frombuffer(buf, dtype=np.uint8)
    planes = source[start[chunk_of] + offset].reshape(height, 4, width)
    return planes.transpose(0, 2, 1)


def read_hdr(path: str | Path) -> np.ndarray:
    """Read a Radiance RGBE picture (new-style run-length encoded or flat).

    The resolution line may be ``-Y H +X W`` (standard: top row first) or have either
    axis reversed; transposed layouts (``+X ... Y ...``) and the pre-1991 run-length
    scheme are refused. Pixel values are divided by the product of the ``EXPOSURE``
    header lines (Radiance semantics; 1 when absent); ``COLORCORR`` is ignored.

    Returns
    -------
    numpy.ndarray
        ``(H, W, 3)`` float32, row 0 at the top.

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
    height, width, flip_rows, flip_cols, exposure, pos = _parse_hdr_header(path, data)
    n_bytes = height * width * 4
    is_rle = (
        _RLE_MIN_WIDTH <= width <= _RLE_MAX_WIDTH
        and len(data) >= pos + 4
        and data[pos] == 2
        and data[pos + 1] == 2
        and data[pos + 2] < 128
    )
    if is_rle:
        rgbe = _decode_rle(path, data, pos, height, width)
    else:
        if len(data) < pos + n_bytes:
            raise BadInputError(
                path, f"truncated flat RGBE data: {len(data) - pos} bytes, expected {n_bytes} for {width}x{height}"
            )
        rgbe = np.frombuffer(data, dtype=np.uint8, count=n_bytes, offset=pos).reshape(height, width, 4)
    image = _rgbe_to_float(rgbe)
    if flip_rows:
        image = image[::-1]
    if flip_cols:
        image = image[:, ::-1]
    if exposure != 1.0:
        image = image / np.float32(exposure)
    return np.ascontiguousarray(image)


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
    """Write a Radiance RGBE picture (``-Y H +X W``), atomically.

    Parameters
    ----------
    path
        Destination file.
    image
        Non-negative linear RGB, row 0 at the top; each pixel keeps about 8 bits of
        mantissa relative to its largest channel (relative error <= 0.4 % there).
    rle
        Use new-style run-length encoding (only possible for widths 8..32767; other
        widths are written flat).
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
