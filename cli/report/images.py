"""Pictures composed with Pillow for the report (no matplotlib): a row of titled images."""

from __future__ import annotations

import io

import numpy as np
from PIL import Image, ImageDraw, ImageFont

__all__ = ["image_row_plot"]


def image_row_plot(images: list[np.ndarray], titles: list[str]) -> bytes:
    """8-bit images (H, W, 3) side by side on white with a title above each (the explorer's lit
    spheres), as PNG bytes. Composed with Pillow (its bundled FreeType font): a matplotlib figure
    cost a quick report ~0.3 s CPU for the same picture."""
    if not images:
        return b""
    font = ImageFont.load_default(size=12)
    gap, top, edge = 12, 20, 6
    height = max(int(im.shape[0]) for im in images)
    width = sum(int(im.shape[1]) for im in images) + gap * (len(images) - 1) + 2 * edge
    canvas = Image.new("RGB", (width, height + top + edge), (255, 255, 255))
    draw = ImageDraw.Draw(canvas)
    x = edge
    for image, title in zip(images, titles, strict=True):
        tile = Image.fromarray(np.ascontiguousarray(np.asarray(image, np.uint8)[..., :3]))
        canvas.paste(tile, (x, top))
        text_width = draw.textlength(title, font=font)
        draw.text((x + (tile.width - text_width) / 2.0, 3), title, fill=(0, 0, 0), font=font)
        x += tile.width + gap
    buf = io.BytesIO()
    canvas.save(buf, format="PNG", compress_level=6)
    return buf.getvalue()
