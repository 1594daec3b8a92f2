"""Report previews with a mesh (``shrm report --mesh``): both thumbnails are rendered."""

from __future__ import annotations

import io

import numpy as np
import pytest
from PIL import Image

import shrmkit
from shrmkit.render.preview import render_previews


@pytest.mark.render
def test_mesh_preview_is_rendered_next_to_the_sphere(offscreen):
    env = shrmkit.load_env("builtin:studio,height=32")
    shrm = shrmkit.prefilter(env, "microfacet:sigma=0.3", eps=0.1, size=32)
    images, notes = render_previews(shrm, env, mode="gl", size=64, mesh="builtin:torus")
    assert [im.key for im in images] == ["sphere", "mesh"] and not notes
    pixels = [np.asarray(Image.open(io.BytesIO(im.png))) for im in images]
    assert all(p.shape[:2] == (64, 64) for p in pixels)
    # a torus and a sphere cover the frame differently: the thumbnails must differ
    assert np.abs(pixels[0].astype(float) - pixels[1].astype(float)).mean() > 1.0
