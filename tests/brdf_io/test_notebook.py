"""Notebook display of brdf_io objects: PNG bytes (checked by an independent reader, Pillow), the
environment map's and the BRDF's cards, and the tone mapping's new home."""

from __future__ import annotations

import base64
import io
import re

import numpy as np
import pytest
from PIL import Image

import shrmkit
from shrmkit.brdf_io import display, notebook
from shrmkit.brdf_io.envmap import EnvironmentMap
from shrmkit.render import output


def _pngs_in(html: str) -> list[np.ndarray]:
    return [np.asarray(Image.open(io.BytesIO(base64.b64decode(d))))
            for d in re.findall(r'src="data:image/png;base64,([A-Za-z0-9+/=]+)"', html)]


@pytest.mark.parametrize("channels", [3, 4])
def test_encode_png_round_trips_through_pillow(channels: int) -> None:
    """Reference: Pillow's PNG decoder reads back the exact pixels of the stdlib encoder."""
    rng = np.random.default_rng(3)
    image = rng.integers(0, 256, size=(7, 11, channels), dtype=np.uint8)
    back = np.asarray(Image.open(io.BytesIO(display.encode_png(image))))
    assert back.shape == image.shape and np.array_equal(back, image)
    with pytest.raises(ValueError, match="uint8"):
        display.encode_png(image.astype(np.float32))


def test_render_output_reexports_the_one_tone_mapping() -> None:
    assert output.tone_map is display.tone_map and output.to_8bit is display.to_8bit
    assert output.TONE_MAPS == display.TONE_MAPS


def test_middle_grey_exposure() -> None:
    """A constant grey of luminance 0.72 needs -2 stops to reach 0.18; black needs none."""
    assert display.middle_grey_exposure(np.full((4, 4, 3), 0.72)) == pytest.approx(-2.0)
    assert display.middle_grey_exposure(np.zeros((4, 4, 3))) == 0.0


def test_environment_map_card_and_png() -> None:
    """The card shows the thumbnail (64 x 128), the size, the orientation and ∫L dω equal to
    EnvironmentMap.integral (the independent sum over every pixel)."""
    env = shrmkit.load_env("builtin:sky")
    html = env._repr_html_()
    pictures = _pngs_in(html)
    assert len(pictures) == 1 and pictures[0].shape == (64, 128, 3)
    assert "256 × 512" in html and "orientation" in html and "dynamic range" in html
    shown = re.search(r"∫ L dω \(RGB\)</th><td[^>]*>([^<]*)<", html).group(1)
    assert np.allclose([float(v) for v in shown.split(",")], env.integral(), rtol=1e-3)
    png = np.asarray(Image.open(io.BytesIO(env._repr_png_())))
    assert np.array_equal(png, pictures[0])


def test_environment_thumbnail_of_a_small_map_and_orientation() -> None:
    env = EnvironmentMap(np.ones((4, 8, 3), np.float32), name="flat", source="x.hdr [latlong, up=y, flip]")
    assert notebook.env_thumbnail(env).shape == (4, 8, 3)
    assert notebook.env_orientation(env) == "latlong, up=y, flip"
    assert "project frame" in notebook.env_orientation(EnvironmentMap(np.ones((4, 8, 3), np.float32)))


def test_brdf_card_shows_a_lit_sphere() -> None:
    """The lit sphere: a white Lambertian surface facing the light is 1 before tone mapping
    (closed form: ρ = 1/π, irradiance π)."""
    brdf = shrmkit.load_brdf("lambert")
    radiance, hit = notebook.lit_sphere_radiance(brdf, size=33, light=(0.0, 0.0, 1.0))
    up = np.array([0.0, 0.0, 1.0])
    assert radiance[16, 16] == pytest.approx(brdf.eval(up, up) * np.pi)
    assert not hit[0, 0] and hit[16, 16]
    html = brdf._repr_html_()
    assert "lambert" in html and "analytic" in html
    (picture,) = _pngs_in(html)
    assert picture.shape == (notebook.SPHERE_PIXELS, notebook.SPHERE_PIXELS, 3)
    assert picture[notebook.SPHERE_PIXELS // 3, notebook.SPHERE_PIXELS // 3].mean() > picture[0, 0].mean()
