"""Portable FloatMap (``.pfm``) reader and writer.

Reference: [PFM] (the reading rules are in ``data_specs/image_files.md``).
"""

from __future__ import annotations

import re
from collections.abc import Callable
from pathlib import Path

import numpy as np

from .errors import BadInputError
from .image_common import atomic_image_path, check_rgb
from .limits import check_memory, check_pixels, read_bytes

__all__ = ["read_pfm", "write_pfm"]

# magic, width, height, scale: whitespace-separated tokens; exactly one whitespace byte
# then ends the header. Searched in the first bytes only (a header is a few dozen bytes).
_HEADER_RE = re.compile(rb"(P[Ff])\s+(\S+)\s+(\S+)\s+(\S+)\s")
_HEADER_MAX_BYTES = 1024
_SIZE_RE = re.compile(rb"\d{1,30}")
_SCALE_RE = re.compile(rb"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")


#: Peak bytes per pixel of :func:`read_pfm` beside the file's own bytes (the float32 result).
PFM_PEAK_BYTES_PER_PIXEL = 16


def read_pfm(path: str | Path, check_shape: Callable[[int, int], None] | None = None) -> np.ndarray:
    r"""Read a Portable FloatMap (``PF`` colour or ``Pf`` grey).

    The header is ``PF``/``Pf``, width, height and a scale, separated by whitespace and
    ended by one whitespace byte; the sign of the scale gives the byte order (negative:
    little-endian, positive: big-endian), its magnitude is ignored. Width and height are
    decimal digits only, the scale a plain decimal number (no ``nan``/``inf``, no
    ``_``). The rows follow bottom to top, so they are reversed here; bytes after the
    last row are ignored. A header ended by CR LF is accepted when the data then fill the
    rest of the file exactly.

    Parameters
    ----------
    path
        A regular file (FIFOs and devices are refused without opening them).

    Returns
    -------
    numpy.ndarray
        ``(H, W, 3)`` float32, row 0 at the top; a grey map is repeated into R, G and B.
        Values are returned as stored, NaN and ±Inf included: callers that need finite
        data check it.

    Raises
    ------
    BadInputError
        Not a regular file or over ``SHRM_MAX_FILE_BYTES``; wrong magic; a malformed
        or truncated header; zero or non-numeric sizes; W·H over ``SHRM_MAX_PIXELS``;
        a planned peak over ``SHRM_MAX_MEMORY_BYTES``
        (checked before anything is allocated); a zero or non-finite scale; fewer data
        bytes than 4·W·H·channels.

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
    data = read_bytes(path, "image")
    if data[:2] not in (b"PF", b"Pf") or not data[2:3].isspace():
        raise BadInputError(path, f"not a PFM file (magic {data[:8]!r}, expected b'PF' or b'Pf')")
    match = _HEADER_RE.match(data, 0, min(len(data), _HEADER_MAX_BYTES))
    if match is None:
        raise BadInputError(
            path, f"truncated PFM header (need magic, width, height and scale, each followed by whitespace): "
            f"{data[:48]!r}"
        )
    magic, width_text, height_text, scale_text = match.groups()
    if not (_SIZE_RE.fullmatch(width_text) and _SIZE_RE.fullmatch(height_text) and _SCALE_RE.fullmatch(scale_text)):
        shown = b" ".join(token[:32] for token in (width_text, height_text, scale_text))
        raise BadInputError(path, f"bad PFM header values {shown!r} (need integer width and height, a number scale)")
    width, height, scale = int(width_text), int(height_text), float(scale_text)
    check_pixels(path, height, width)
    if check_shape is not None:  # ``check_shape(height, width)`` before the pixels are read (read_hdr's)
        check_shape(height, width)
    # the memory plan (data_specs/limits.md): the file's bytes and the float32 result (measured 24 B/px in all)
    check_memory(path, len(data) + PFM_PEAK_BYTES_PER_PIXEL * height * width, f"reading {width} x {height} pixels")
    if scale == 0 or not np.isfinite(scale):
        raise BadInputError(path, f"bad PFM scale {scale_text[:32].decode()!r} (must be a non-zero finite number)")
    pos = match.end()
    channels = 3 if magic == b"PF" else 1
    count = width * height * channels
    if data[pos - 1 : pos + 1] == b"\r\n" and len(data) - pos - 1 == 4 * count:
        pos += 1  # a header ended with CR LF (Windows writers), recognised when the size is exact
    if len(data) - pos < 4 * count:
        raise BadInputError(
            path, f"truncated PFM data: {len(data) - pos:,} bytes, expected {4 * count:,} for {width} x {height}"
        )
    dtype = np.dtype("<f4") if scale < 0 else np.dtype(">f4")
    pixels = np.frombuffer(data, dtype=dtype, count=count, offset=pos).reshape(height, width, channels)
    pixels = pixels[::-1]  # PFM stores the bottom row first
    if channels == 1:
        pixels = np.broadcast_to(pixels, (height, width, 3))
    return np.ascontiguousarray(pixels, dtype=np.float32)


def write_pfm(path: str | Path, image: np.ndarray) -> None:
    """Write a little-endian colour PFM (scale -1, rows bottom to top), atomically.

    Parameters
    ----------
    path
        Destination file; its folder must exist.
    image
        ``(H, W, 3)`` floating-point RGB, row 0 at the top; stored as float32.

    Raises
    ------
    BadInputError
        Wrong shape or dtype, missing folder.
    """
    path = Path(path)
    image = check_rgb(path, image)
    height, width = image.shape[:2]
    pixels = np.ascontiguousarray(image[::-1], dtype="<f4")
    with atomic_image_path(path) as tmp:
        tmp.write_bytes(f"PF\n{width} {height}\n-1.0\n".encode("ascii") + pixels.tobytes())
