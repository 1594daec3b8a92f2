"""Notebook card of a render: the picture is the first frame (decoded by Pillow, an independent PNG
reader) and the card carries the model's description lines and the timings."""

from __future__ import annotations

import io

import numpy as np
import pytest
from PIL import Image

import shrmkit


@pytest.mark.render
def test_scene_render_card_and_png(offscreen) -> None:
    result = shrmkit.render_scene("builtin:sphere:subdivisions=3", "builtin:sky,height=32", "phong:s=8", size=32,
                                  fps_frames=0)
    html = result._repr_html_()
    for line in result.built.description:
        assert line.split(":")[0] in html
    assert result.timings.backend in html and "first frame" in html
    picture = np.asarray(Image.open(io.BytesIO(result._repr_png_())))
    assert picture.shape == (32, 32, 3)
    # brighter where the frame's radiance is brighter (a monotone tone curve)
    luma = result.frames[0].linear.sum(axis=2)
    assert picture.sum(axis=2).ravel()[np.argmax(luma)] >= picture.sum(axis=2).ravel()[np.argmin(luma)]
