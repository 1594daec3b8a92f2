"""Shared pieces of the HDR image writers: atomic output and the (H, W, 3) check."""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from .atomic import atomic_path
from .errors import BadInputError

__all__ = ["atomic_image_path", "check_rgb"]


@contextlib.contextmanager
def atomic_image_path(path: Path) -> Iterator[Path]:
    """:func:`~shrmkit.brdf_io.atomic.atomic_path`, refusing a missing output folder."""
    path = Path(path)
    if not path.parent.is_dir():
        raise BadInputError(path, f"output folder {path.parent} does not exist")
    with atomic_path(path, suffix=".tmp" + path.suffix) as tmp:
        yield tmp


def check_rgb(path: Path, image: np.ndarray) -> np.ndarray:
    image = np.asarray(image)
    if image.ndim != 3 or image.shape[2] != 3 or image.shape[0] < 1 or image.shape[1] < 1:
        raise BadInputError(path, f"image to write must have shape (H, W, 3), got {image.shape}")
    if not np.issubdtype(image.dtype, np.floating):
        raise BadInputError(path, f"image to write must be floating point, got {image.dtype}")
    return image
