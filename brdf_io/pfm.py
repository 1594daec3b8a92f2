"""Portable FloatMap (``.pfm``) reader and writer.

Reference: https://www.pauldebevec.com/Research/HDR/PFM/
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .errors import BadInputError
from .image_common import atomic_image_path, check_rgb
from .limits import read_bytes

__all__ = ["read_pfm", "write_pfm"]


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
    data = read_bytes(path, "image")
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
    image = check_rgb(path, image)
    height, width = image.shape[:2]
    pixels = np.ascontiguousarray(image[::-1], dtype="<f4")
    with atomic_image_path(path) as tmp:
        tmp.write_bytes(f"PF\n{width} {height}\n-1.0\n".encode("ascii") + pixels.tobytes())
