"""Linear radiance to a display image: exposure, tone curve, sRGB encoding, 8 bits, PNG bytes.

The one home of the tone mapping that every picture of the toolkit uses (rendered frames,
previews, the notebook thumbnails of :mod:`~shrmkit.brdf_io.notebook`); ``render.output``
re-exports it for the image writers.

1. scale by 2^exposure (:func:`middle_grey_exposure` picks the exposure that brings a mean
   luminance to 0.18);
2. tone map (``srgb``: clip to [0, 1]; ``filmic``: the ACES fitted curve of [Narkowicz15],
   x(2.51x + 0.03) / (x(2.43x + 0.59) + 0.14));
3. encode with the sRGB transfer function [sRGB] and quantize to 8 bits;
4. :func:`encode_png`: an 8-bit RGB or RGBA image as PNG bytes ([PNG]:
   signature, IHDR, one zlib-compressed IDAT with filter type 0 per row, IEND), written with the
   standard library only, so that a notebook thumbnail imports nothing heavy.
"""

from __future__ import annotations

import struct
import zlib

import numpy as np

from .colour import REC709_LUMA
from .names import TONE_MAP_NAMES as TONE_MAPS  # numpy-free home, for the CLI's parsers

__all__ = ["TONE_MAPS", "tone_map", "srgb_encode", "to_8bit", "middle_grey_exposure", "encode_png"]

#: Exposures :func:`middle_grey_exposure` returns stay within ± this many stops.
MAX_AUTO_STOPS = 20.0


def tone_map(linear: np.ndarray, *, exposure: float = 0.0, curve: str = "filmic") -> np.ndarray:
    """Display-referred values in [0, 1] (before sRGB encoding) from linear radiance.

    Parameters
    ----------
    exposure
        Stops: values are multiplied by 2**exposure first.
    curve
        ``"srgb"`` (clip) or ``"filmic"`` (ACES fit, Narkowicz 2015).
    """
    if curve not in TONE_MAPS:
        raise ValueError(f"tone map must be one of {TONE_MAPS}, got {curve!r}")
    x = np.maximum(np.asarray(linear, dtype=np.float64) * 2.0 ** float(exposure), 0.0)
    x = np.nan_to_num(x, nan=0.0, posinf=1e30)
    if curve == "filmic":
        x = x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14)
    return np.clip(x, 0.0, 1.0)


def srgb_encode(x: np.ndarray) -> np.ndarray:
    """sRGB transfer function (IEC 61966-2-1) of values in [0, 1]."""
    x = np.clip(np.asarray(x, dtype=np.float64), 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1.0 / 2.4) - 0.055)


def to_8bit(
    linear: np.ndarray, alpha: np.ndarray | None = None, *, exposure: float = 0.0, curve: str = "filmic"
) -> np.ndarray:
    """uint8 (H, W, 3) or, with ``alpha``, (H, W, 4) display image."""
    rgb = np.round(srgb_encode(tone_map(linear, exposure=exposure, curve=curve)) * 255.0).astype(np.uint8)
    if alpha is None:
        return rgb
    a = np.round(np.clip(np.asarray(alpha, dtype=np.float64), 0.0, 1.0) * 255.0).astype(np.uint8)
    return np.concatenate([rgb, a[..., None]], axis=-1)


def middle_grey_exposure(linear: np.ndarray, weights: np.ndarray | None = None) -> float:
    """Stops that bring the (weighted) mean Rec. 709 luminance of ``linear`` (..., 3) to 0.18;
    0 for an all-black image; within ±:data:`MAX_AUTO_STOPS`.

    ``weights`` (broadcast against ``linear[..., 0]``): per-pixel weights, e.g. solid angles of a
    lat-long map's rows or the coverage of a rendered frame.
    """
    luma = np.asarray(linear, dtype=np.float64) @ np.asarray(REC709_LUMA, dtype=np.float64)
    w = np.ones_like(luma) if weights is None else np.broadcast_to(np.asarray(weights, np.float64), luma.shape)
    total = float(w.sum())
    mean = float((luma * w).sum() / total) if total > 0 else 0.0
    if not mean > 0 or not np.isfinite(mean):
        return 0.0
    return float(np.clip(np.log2(0.18 / mean), -MAX_AUTO_STOPS, MAX_AUTO_STOPS))


def _chunk(kind: bytes, data: bytes) -> bytes:
    # a PNG chunk: big-endian length, type, data, CRC-32 of type + data (PNG spec §5.3)
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)


def encode_png(image8: np.ndarray, *, level: int = 6) -> bytes:
    """PNG bytes of a uint8 (H, W, 3) RGB or (H, W, 4) RGBA image (8 bits per channel, no
    interlace, filter type 0 on every row; any PNG reader decodes it).

    Raises
    ------
    ValueError
        Not a uint8 array of shape (H, W, 3|4) with H, W >= 1.
    """
    img = np.asarray(image8)
    if img.dtype != np.uint8 or img.ndim != 3 or img.shape[2] not in (3, 4) or 0 in img.shape[:2]:
        raise ValueError(f"encode_png needs uint8 (H, W, 3|4), got {img.dtype} {img.shape}")
    h, w, c = img.shape
    colour_type = 2 if c == 3 else 6  # truecolour / truecolour with alpha (PNG spec table 11.1)
    header = struct.pack(">IIBBBBB", w, h, 8, colour_type, 0, 0, 0)
    # each scanline starts with its filter-type byte (0: None)
    rows = np.concatenate([np.zeros((h, 1), np.uint8), np.ascontiguousarray(img).reshape(h, w * c)], axis=1)
    return (b"\x89PNG\r\n\x1a\n" + _chunk(b"IHDR", header) + _chunk(b"IDAT", zlib.compress(rows.tobytes(), level))
            + _chunk(b"IEND", b""))
