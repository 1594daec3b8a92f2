"""Readers and writers of high-dynamic-range images: OpenEXR, Radiance RGBE (.hdr) and PFM.

Every reader returns a ``(H, W, 3)`` float32 array of linear RGB with row 0 the *top*
row of the image as displayed, and raises :class:`BadInputError` naming the file for a
missing, truncated or malformed file. Every writer is atomic: the image goes to a
temporary file in the destination folder, which then replaces the destination
(``os.replace``), so a failed write leaves no partial file. Value checks (NaN, Inf,
negative radiance) belong to the caller (:func:`shrmkit.brdf_io.envmap.load_env`).

The codecs live in :mod:`.exr`, :mod:`.rgbe` and :mod:`.pfm`; this module is the
registry by file suffix. Public objects: :func:`read_exr`, :func:`write_exr`, :func:`read_hdr`, :func:`write_hdr`,
:func:`read_pfm`, :func:`write_pfm`, :func:`read_image`, :func:`write_image`,
:data:`IMAGE_SUFFIXES`.

References: [OpenEXR] (read and written through the ``OpenEXR`` 3.x Python bindings); [Ward91]
(the RGBE shared-exponent pixel); [Radiance] (``picture`` format: header, resolution string,
new-style run-length encoding); [PFM].
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np

from .errors import BadInputError
from .exr import read_exr, write_exr
from .pfm import read_pfm, write_pfm
from .rgbe import read_hdr, write_hdr

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


_READERS: dict[str, Callable[..., np.ndarray]] = {".exr": read_exr, ".hdr": read_hdr, ".pfm": read_pfm}
IMAGE_SUFFIXES = tuple(_READERS)


def read_image(path: str | Path, check_shape: Callable[[int, int], None] | None = None) -> np.ndarray:
    """Read an HDR image by extension (``.exr``, ``.hdr``, ``.pfm``) as ``(H, W, 3)`` float32;
    ``check_shape(height, width)``, when given, runs on the header's size before any pixel is
    decoded (``.hdr``, ``.pfm``; an EXR's windows are checked by
    :func:`~shrmkit.brdf_io.exr.read_exr_image`'s ``check_windows``)."""
    path = Path(path)
    reader = _READERS.get(path.suffix.lower())
    if reader is None:
        raise BadInputError(path, f"unknown HDR image type {path.suffix!r}; known: {', '.join(IMAGE_SUFFIXES)}")
    if check_shape is not None and reader is not read_exr:
        return reader(path, check_shape)
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
