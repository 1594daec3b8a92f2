"""Readers and writers of high-dynamic-range images: OpenEXR, Radiance RGBE (.hdr) and PFM.

Every reader returns a ``(H, W, 3)`` float32 array of linear RGB with row 0 the *top*
row of the image as displayed, and raises :class:`BadInputError` naming the file for a
missing, truncated or malformed file. Every writer is atomic: the image goes to a
temporary file in the destination folder, which then replaces the destination
(``os.replace``), so a failed write leaves no partial file. Value checks (NaN, Inf,
negative radiance) belong to the caller (:func:`shrmkit.brdf_io.envmap.load_env`).

Public objects: :func:`read_exr`, :func:`write_exr`, :func:`read_hdr`, :func:`write_hdr`,
:func:`read_pfm`, :func:`write_pfm`, :func:`read_image`, :func:`write_image`,
:data:`IMAGE_SUFFIXES`.

References
----------
- OpenEXR file layout, https://openexr.com/en/latest/OpenEXRFileLayout.html (read and
  written through the ``OpenEXR`` 3.x Python bindings).
- G. Ward, "Real Pixels", Graphics Gems II (1991) 80-83: the RGBE shared-exponent pixel.
- Radiance file formats, https://radiance-online.org/learning/documentation/manual-pages
  (``picture`` format: header, resolution string, new-style run-length encoding).
- Portable FloatMap, https://www.pauldebevec.com/Research/HDR/PFM/
"""

from __future__ import annotations

import contextlib
import re
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np
import OpenEXR

from .atomic import atomic_path
from .errors import BadInputError

__all__ = [
    "read_exr",
    "write_exr",
    "read_hdr",
    "write_hdr",
    "read_pfm",
    "write_pfm",
    "read_image",
    "write_image",
    "IMAGE_SUFFIXES",
]


# --------------------------------------------------------------------------------------
# atomic output
# --------------------------------------------------------------------------------------
@contextlib.contextmanager
def _atomic_path(path: Path) -> Iterator[Path]:
    """:func:`~shrmkit.brdf_io.atomic.atomic_path`, refusing a missing output folder."""
    path = Path(path)
    if not path.parent.is_dir():
        raise BadInputError(path, f"output folder {path.parent} does not exist")
    with atomic_path(path, suffix=".tmp" + path.suffix) as tmp:
        yield tmp


def _read_bytes(path: Path) -> bytes:
    """The whole file, or a BadInputError naming it when it is missing or unreadable."""
    if not path.is_file():
        raise BadInputError(path, "no such file")
    try:
        return path.read_bytes()
    except OSError as err:
        raise BadInputError(path, f"cannot read ({err.strerror or err})") from None


def _check_rgb(path: Path, image: np.ndarray) -> np.ndarray:
    image = np.asarray(image)
    if image.ndim != 3 or image.shape[2] != 3 or image.shape[0] < 1 or image.shape[1] < 1:
        raise BadInputError(path, f"image to write must have shape (H, W, 3), got {image.shape}")
    if not np.issubdtype(image.dtype, np.floating):
        raise BadInputError(path, f"image to write must be floating point, got {image.dtype}")
    return image


# --------------------------------------------------------------------------------------
# OpenEXR
# --------------------------------------------------------------------------------------
def read_exr(path: str | Path) -> np.ndarray:
    """Read the R, G, B channels of a single-part scanline or tiled OpenEXR file.

    Half, float and uint channels are accepted; an alpha channel is ignored; a file with
    only a luminance channel ``Y`` is read as grey. Channels may be named with a layer
    prefix (``"beauty.R"``) when the file has a single layer.

    Returns
    -------
    numpy.ndarray
        ``(H, W, 3)`` float32, row 0 the top of the data window.
    """
    path = Path(path)
    if not path.is_file():
        raise BadInputError(path, "no such file")
    try:
        with OpenEXR.File(str(path), separate_channels=True) as exr:
            channels = {name: np.asarray(ch.pixels) for name, ch in exr.channels().items()}
    except Exception as err:  # the bindings raise RuntimeError/OSError/... for bad files
        raise BadInputError(path, f"not a readable OpenEXR file ({err})") from None
    by_suffix: dict[str, np.ndarray] = {}
    for name, pixels in channels.items():
        by_suffix.setdefault(name.rsplit(".", 1)[-1].upper(), pixels)
    if all(c in by_suffix for c in "RGB"):
        planes = [by_suffix[c] for c in "RGB"]
    elif "Y" in by_suffix:
        planes = [by_suffix["Y"]] * 3
    else:
        raise BadInputError(path, f"OpenEXR file has no R, G, B (or Y) channels; channels: {sorted(channels)}")
    shapes = {p.shape for p in planes}
    if len(shapes) != 1 or len(planes[0].shape) != 2:
        raise BadInputError(path, f"OpenEXR colour channels have unequal or subsampled shapes {shapes}")
    image = np.stack(planes, axis=-1).astype(np.float32, copy=False)
    if image.size == 0:
        raise BadInputError(path, f"OpenEXR image is empty (shape {image.shape[:2]})")
    return image


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
    image = _check_rgb(path, image)
    dtype = np.float16 if half else np.float32
    if half and np.nanmax(np.abs(image)) > float(np.finfo(np.float16).max):
        raise BadInputError(path, "values above 65504 do not fit in half floats; write float32")
    pixels = np.ascontiguousarray(image, dtype=dtype)
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    with _atomic_path(path) as tmp:
        with OpenEXR.File(header, {"RGB": pixels}) as exr:
            exr.write(str(tmp))


# --------------------------------------------------------------------------------------
# Radiance RGBE
# --------------------------------------------------------------------------------------
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
    data = _read_bytes(path)
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
    image = _check_rgb(path, image)
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
    with _atomic_path(path) as tmp:
        tmp.write_bytes(header.encode("ascii") + bytes(body))


# --------------------------------------------------------------------------------------
# PFM
# --------------------------------------------------------------------------------------
def read_pfm(path: str | Path) -> np.ndarray:
    r"""Read a Portable FloatMap (``PF`` colour or ``Pf`` grey).

    The header is ``PF``/``Pf``, ``W H``, and a scale whose sign gives the byte order
    (negative: little-endian); the rows follow bottom to top, so they are reversed here.

    Returns
    -------
    numpy.ndarray
        ``(H, W, 3)`` float32, row 0 at the top.

    Examples
    --------
    A 2 × 2 little-endian grey map written byte by byte: the first stored row is the
    bottom one, and grey is repeated into R, G and B:

    >>> import pathlib, tempfile
    >>> import numpy as np
    >>> folder = tempfile.TemporaryDirectory()
    >>> path = pathlib.Path(folder.name) / "grey.pfm"
    >>> _ = path.write_bytes(b"Pf\n2 2\n-1.0\n" + np.array([1, 2, 3, 4], "<f4").tobytes())
    >>> image = read_pfm(path)
    >>> image.shape
    (2, 2, 3)
    >>> image[..., 0]
    array([[3., 4.],
           [1., 2.]], dtype=float32)
    >>> folder.cleanup()
    """
    path = Path(path)
    data = _read_bytes(path)
    tokens: list[bytes] = []
    pos = 0
    # three whitespace-separated header tokens: magic, "W H" (two tokens), scale; one
    # single whitespace byte then separates the header from the binary data
    while len(tokens) < 4:
        while pos < len(data) and data[pos : pos + 1].isspace():
            pos += 1
        end = pos
        while end < len(data) and not data[end : end + 1].isspace():
            end += 1
        if end >= len(data) or end == pos:
            raise BadInputError(path, "truncated PFM header")
        tokens.append(data[pos:end])
        pos = end
    pos += 1
    magic = tokens[0]
    if magic not in (b"PF", b"Pf"):
        raise BadInputError(path, f"not a PFM file (magic {magic[:8]!r}, expected b'PF' or b'Pf')")
    try:
        width, height, scale = int(tokens[1]), int(tokens[2]), float(tokens[3])
    except ValueError:
        raise BadInputError(path, f"bad PFM header values {b' '.join(tokens[1:])!r}") from None
    if width <= 0 or height <= 0:
        raise BadInputError(path, f"zero-size image ({width} x {height})")
    if scale == 0 or not np.isfinite(scale):
        raise BadInputError(path, f"bad PFM scale {scale}")
    channels = 3 if magic == b"PF" else 1
    count = width * height * channels
    if len(data) - pos < 4 * count:
        raise BadInputError(path, f"truncated PFM data: {len(data) - pos} bytes, expected {4 * count}")
    dtype = np.dtype("<f4") if scale < 0 else np.dtype(">f4")
    pixels = np.frombuffer(data, dtype=dtype, count=count, offset=pos).reshape(height, width, channels)
    pixels = pixels[::-1]  # PFM stores the bottom row first
    if channels == 1:
        pixels = np.repeat(pixels, 3, axis=2)
    return np.ascontiguousarray(pixels, dtype=np.float32)


def write_pfm(path: str | Path, image: np.ndarray) -> None:
    """Write a little-endian colour PFM (scale -1, rows bottom to top), atomically."""
    path = Path(path)
    image = _check_rgb(path, image)
    height, width = image.shape[:2]
    pixels = np.ascontiguousarray(image[::-1], dtype="<f4")
    with _atomic_path(path) as tmp:
        tmp.write_bytes(f"PF\n{width} {height}\n-1.0\n".encode("ascii") + pixels.tobytes())


# --------------------------------------------------------------------------------------
# dispatch
# --------------------------------------------------------------------------------------
_READERS: dict[str, Callable[[Path], np.ndarray]] = {".exr": read_exr, ".hdr": read_hdr, ".pfm": read_pfm}
IMAGE_SUFFIXES = tuple(_READERS)


def read_image(path: str | Path) -> np.ndarray:
    """Read an HDR image by extension (``.exr``, ``.hdr``, ``.pfm``) as ``(H, W, 3)`` float32."""
    path = Path(path)
    reader = _READERS.get(path.suffix.lower())
    if reader is None:
        raise BadInputError(path, f"unknown HDR image type {path.suffix!r}; known: {', '.join(IMAGE_SUFFIXES)}")
    return reader(path)


def write_image(path: str | Path, image: np.ndarray, half: bool = False) -> None:
    """Write an HDR image by extension; ``half`` selects 16-bit floats for ``.exr``."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix == ".exr":
        write_exr(path, image, half=half)
    elif suffix == ".hdr":
        write_hdr(path, image)
    elif suffix == ".pfm":
        write_pfm(path, image)
    else:
        raise BadInputError(path, f"unknown HDR image type {path.suffix!r}; known: {', '.join(IMAGE_SUFFIXES)}")
