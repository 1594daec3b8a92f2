"""Camera rays and image output (no OpenGL needed).

References: closed forms (pixel-centre spacing, field-of-view geometry, the sRGB transfer
function of IEC 61966-2-1 and the ACES fit of Narkowicz 2015 evaluated by hand), and files
read back with the OpenEXR and Pillow readers.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import OpenEXR
import pytest
from PIL import Image

from shrmkit.brdf_io.errors import BadInputError
from shrmkit.render.camera import Camera, orbit_camera
from shrmkit.render.output import (
    composite,
    environment_background,
    srgb_encode,
    to_8bit,
    tone_map,
    turntable_paths,
    write_exr,
    write_gif,
    write_png,
)


def test_ortho_rays_span_the_unit_sphere() -> None:
    """--camera ortho: pixel centres evenly spaced, the square image spans [-1, 1] exactly."""
    cam = Camera.looking_at(view=(0.0, -1.0, 0.0), up=(0.0, 0.0, 1.0), projection="ortho")
    origins, dirs = cam.rays(8, 8)
    np.testing.assert_allclose(dirs, np.broadcast_to([0.0, 1.0, 0.0], dirs.shape))
    # looking along +y with z up: image right is +x
    centers = (2.0 * np.arange(8) + 1.0) / 8 - 1.0
    np.testing.assert_allclose(origins[0, :, 0], centers, atol=1e-12)
    np.testing.assert_allclose(origins[:, 0, 2], centers[::-1], atol=1e-12)


def test_perspective_frames_the_bounding_sphere() -> None:
    """The extreme rays of the vertical field of view are tangent to the unit sphere."""
    cam = Camera.looking_at(view=(1.0, 1.0, 0.0), projection="perspective", distance=4.0)
    assert np.sin(cam.fov_y / 2) == pytest.approx(0.25)
    np.testing.assert_allclose(cam.eye, 4.0 * np.array([1.0, 1.0, 0.0]) / np.sqrt(2.0))
    _, dirs = cam.rays(5, 5)
    np.testing.assert_allclose(dirs[2, 2], cam.forward, atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(dirs, axis=-1), 1.0)


def test_orbit_and_bad_up() -> None:
    cam = Camera.looking_at(view=(1.0, 0.0, 0.0), projection="ortho")
    quarter = orbit_camera(cam, np.zeros(3), np.pi / 2)
    np.testing.assert_allclose(quarter.view_direction(np.zeros(3)), [0.0, 1.0, 0.0], atol=1e-12)
    with pytest.raises(ValueError, match="parallel"):
        Camera.looking_at(view=(0.0, 0.0, 2.0), up=(0.0, 0.0, 1.0))


def test_tone_curves_closed_form() -> None:
    assert srgb_encode(np.array(0.5)) == pytest.approx(1.055 * 0.5 ** (1 / 2.4) - 0.055)
    assert srgb_encode(np.array(0.001)) == pytest.approx(0.01292)
    x = 0.7
    aces = x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14)
    assert tone_map(np.array(0.35), exposure=1.0, curve="filmic") == pytest.approx(aces)
    assert tone_map(np.array(3.0), curve="srgb") == 1.0
    img = to_8bit(np.full((1, 1, 3), 0.5), np.ones((1, 1)), curve="srgb")
    assert img.shape == (1, 1, 4) and img[0, 0, 0] == round(255 * (1.055 * 0.5 ** (1 / 2.4) - 0.055))


def test_composite_and_background() -> None:
    """An environment bright only near +x shows behind the object where the rays point to +x."""
    env = np.zeros((16, 32, 3))
    env[:, [0, 31]] = 5.0  # columns next to φ = 0 (the +x direction)
    cam = Camera.looking_at(view=(-1.0, 0.0, 0.0), projection="ortho")  # camera looks along +x
    bg = environment_background(env, cam, 4, 4)
    np.testing.assert_allclose(bg[1, 1], [5.0, 5.0, 5.0], rtol=1e-6)
    rad = np.ones((4, 4, 3), np.float32)
    alpha = np.zeros((4, 4), np.float32)
    alpha[0, 0] = 1.0
    out = composite(rad, alpha, bg)
    np.testing.assert_allclose(out[0, 0], 1.0)
    np.testing.assert_allclose(out[1, 1], 5.0, rtol=1e-6)


def test_exr_holds_float32_exactly(tmp_path: Path) -> None:
    rng = np.random.default_rng(3)
    rad = (rng.random((5, 7, 3)) * 1e4).astype(np.float32)
    rad[0, 0] = [1e-6, 3.14159, 65504.0 * 4]
    alpha = (rng.random((5, 7)) > 0.5).astype(np.float32)
    path = tmp_path / "a.exr"
    write_exr(path, rad, alpha)
    with OpenEXR.File(str(path), separate_channels=True) as f:
        ch = {k: np.asarray(v.pixels) for k, v in f.channels().items()}
    assert sorted(ch) == ["A", "B", "G", "R"]
    assert ch["R"].dtype == np.float32
    np.testing.assert_array_equal(np.stack([ch["R"], ch["G"], ch["B"]], -1), rad)
    np.testing.assert_array_equal(ch["A"], alpha)


def test_writers_are_atomic(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A failing write leaves neither the target nor a temporary file behind, and is one error naming
    the target (the CLI's one line, exit 2)."""

    def boom(*args, **kwargs):
        raise OSError("disk full")

    monkeypatch.setattr(Image.Image, "save", boom)
    with pytest.raises(BadInputError, match="cannot write .disk full.") as raised:
        write_png(tmp_path / "x.png", np.zeros((2, 2, 3), np.uint8))
    assert str(tmp_path / "x.png") in str(raised.value)
    assert list(tmp_path.iterdir()) == []


def test_png_gif_and_turntable_names(tmp_path: Path) -> None:
    frames, gif = turntable_paths(tmp_path / "spin.png", 3)
    assert [p.name for p in frames] == ["spin_0000.png", "spin_0001.png", "spin_0002.png"]
    assert gif.name == "spin.gif"
    imgs = [np.full((4, 4, 3), 60 * k, np.uint8) for k in range(3)]
    write_png(frames[0], imgs[1])
    np.testing.assert_array_equal(np.asarray(Image.open(frames[0])), imgs[1])
    write_gif(gif, imgs)
    with Image.open(gif) as g:
        assert g.n_frames == 3
