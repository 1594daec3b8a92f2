"""OpenEXR reader and writer (through the ``OpenEXR`` 3.x Python bindings).

The reader returns ``(H, W, 3)`` float32 linear RGB, row 0 the top row as displayed, and
raises :class:`BadInputError` naming the file for a missing, malformed or unusable file;
the writer is atomic. Reference: OpenEXR file layout,
https://openexr.com/en/latest/OpenEXRFileLayout.html
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import OpenEXR

from .errors import BadInputError
from .image_common import atomic_image_path, check_rgb

__all__ = ["read_exr", "write_exr"]


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
    image = check_rgb(path, image)
    dtype = np.float16 if half else np.float32
    if half and np.nanmax(np.abs(image)) > float(np.finfo(np.float16).max):
        raise BadInputError(path, "values above 65504 do not fit in half floats; write float32")
    pixels = np.ascontiguousarray(image, dtype=dtype)
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    with atomic_image_path(path) as tmp:
        with OpenEXR.File(header, {"RGB": pixels}) as exr:
            exr.write(str(tmp))
