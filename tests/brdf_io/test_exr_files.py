"""OpenEXR files written by other tools: layers (AOVs), parts, luminance/chroma, data windows,
deep images, the ``envmap`` attribute, slightly negative photographs, truncated and hostile files.

References are independent of our reader: files built here with the OpenEXR bindings from known
pixel values, published colour-space numbers, and OpenEXR's own test images
(../shared/data/env/openexr_images, whose content marks the environment's axes).
"""

from __future__ import annotations

import argparse
import os
import struct
import subprocess
import sys
from pathlib import Path

import numpy as np
import OpenEXR
import pytest

from shrmkit.brdf_io.envmap import (
    NEGATIVE_CLAMP_FRACTION,
    OPENEXR_TO_PROJECT,
    EnvironmentMap,
    load_env,
    white_level,
)
from shrmkit.brdf_io.errors import BadInputError
from shrmkit.brdf_io.exr import luminance_weights, read_exr, read_exr_image
from shrmkit.cli.common import add_env_orientation, load_env_arg

REC709_YW = np.array([0.2126, 0.7152, 0.0722])  # ITU-R BT.709-6, Table item 3.2
# ACES AP1 (S-2014-004 / TB-2014-004): primaries, ACES white, and the Y row of its NPM
AP1 = (0.713, 0.293, 0.165, 0.830, 0.128, 0.044, 0.32168, 0.33767)
AP1_YW = np.array([0.2722287168, 0.6740817658, 0.0536895174])
# ACES AP0 (SMPTE ST 2065-1): its blue primary has y < 0, so the blue weight is negative
AP0 = (0.7347, 0.2653, 0.0, 1.0, 0.0001, -0.0770, 0.32168, 0.33767)
AP0_YW = np.array([0.3439664498, 0.7281660966, -0.0721325464])


def _box(x0: int, y0: int, x1: int, y1: int) -> tuple[np.ndarray, np.ndarray]:
    return np.array([x0, y0], np.int32), np.array([x1, y1], np.int32)


def _write(path: Path, channels: dict, **header) -> Path:
    """A single-part file; arrays are made contiguous (the 3.5 bindings write a strided view's
    raw memory, not its values)."""
    head = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage, **header}
    channels = {k: np.ascontiguousarray(v) if isinstance(v, np.ndarray) else v for k, v in channels.items()}
    with OpenEXR.File(head, channels) as exr:
        exr.write(str(path))
    return path


def _rgb(prefix: str, value, shape=(4, 8)) -> dict:
    values = np.broadcast_to(np.asarray(value, np.float32), (3,))
    return {f"{prefix}{c}": np.full(shape, v, np.float32) for c, v in zip("RGB", values, strict=True)}


# --------------------------------------------------------------------------------------
# 1. layers
# --------------------------------------------------------------------------------------
def test_plain_rgb_wins_over_an_aov_layer(tmp_path):
    """Plain R, G, B = 2 beside an AO layer = 0.5 (sorted first: 'AO.B' < 'B'): the plain RGB is read."""
    path = _write(tmp_path / "aov.exr", {**_rgb("", 2.0), **_rgb("AO.", 0.5)})
    assert np.all(read_exr(path) == 2.0)
    assert np.all(load_env(path).radiance == 2.0)
    assert np.all(read_exr(path, layer="AO") == 0.5)
    image = read_exr_image(path, layer="AO.")
    assert image.layer == "AO" and np.all(image.pixels == 0.5)


def test_several_layers_without_plain_rgb_need_a_choice(tmp_path):
    path = _write(tmp_path / "layers.exr", {**_rgb("diffuse.", (1, 2, 3)), **_rgb("specular.", (4, 5, 6))})
    with pytest.raises(BadInputError, match=r"layers.exr.*'diffuse', 'specular'.*layer="):
        read_exr(path)
    with pytest.raises(BadInputError, match="layer"):
        load_env(path)
    assert np.all(read_exr(path, layer="specular") == [4, 5, 6])
    assert np.all(load_env(path, layer="diffuse").radiance == [1, 2, 3])
    with pytest.raises(BadInputError, match=r"no layer 'albedo'.*'diffuse', 'specular'"):
        read_exr(path, layer="albedo")
    # the CLI option reaches the loader
    parser = argparse.ArgumentParser()
    add_env_orientation(parser)
    args = parser.parse_args(["--env-layer", "specular"])
    assert np.all(load_env_arg(str(path), args).radiance == [4, 5, 6])
    with pytest.raises(BadInputError, match="--env-layer/--env-part"):
        load_env_arg("builtin:constant,height=4", args)


def test_a_single_layer_is_read_as_before(tmp_path):
    path = _write(tmp_path / "beauty.exr", {**_rgb("beauty.", (1, 2, 3)), "beauty.A": np.ones((4, 8), np.float32)})
    image = read_exr_image(path)
    assert image.layer == "beauty" and image.colour == "rgb"
    assert np.all(image.pixels == [1, 2, 3])


def test_layer_without_colour_and_no_colour_at_all(tmp_path):
    path = _write(tmp_path / "depth.exr", {**_rgb("", 1.0), "depth.Z": np.ones((4, 8), np.float32)})
    with pytest.raises(BadInputError, match=r"layer 'depth' has no R, G, B"):
        read_exr(path, layer="depth")
    path = _write(tmp_path / "z.exr", {"Z": np.ones((4, 8), np.float32)})
    with pytest.raises(BadInputError, match=r"no R, G, B \(or Y\) channels.*Z"):
        read_exr(path)
    with pytest.raises(BadInputError, match="OpenEXR files only"):
        load_env("tests/resources/tiny_4x8.hdr", layer="beauty")


# --------------------------------------------------------------------------------------
# 2. luminance / chroma
# --------------------------------------------------------------------------------------
def test_luminance_weights_match_published_values():
    """computeYw against the published Y rows of the RGB→XYZ matrices (Rec. 709, ACES AP1, AP0)."""
    assert np.allclose(luminance_weights(), REC709_YW, atol=1e-4)
    assert np.allclose(luminance_weights(AP1), AP1_YW, atol=1e-6)
    assert np.allclose(luminance_weights(AP0), AP0_YW, atol=1e-6)
    with pytest.raises(ValueError, match="degenerate"):
        luminance_weights((0.3, 0.3, 0.3, 0.3, 0.3, 0.3, 0.3127, 0.329))


def _packed(samples: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """The OpenEXR 3.5 bindings write a 2 × 2 subsampled channel from an array of the full
    image shape, storing its first h/2 · w/2 values in row-major order (the read-back of every
    file built here is checked against the intended samples)."""
    packed = np.zeros(shape, samples.dtype)
    packed.reshape(-1)[: samples.size] = samples.reshape(-1)
    return packed


def _write_yca(path: Path, rgb: np.ndarray, yw: np.ndarray, **header) -> tuple[np.ndarray, np.ndarray]:
    """Encode ``rgb`` as OpenEXR's Y, RY, BY (ImfRgbaYca: Y = yw · RGB, RY = (R − Y)/Y,
    BY = (B − Y)/Y), half floats, chroma point-sampled at even x and y; returns the chroma samples."""
    h, w = rgb.shape[:2]
    y = rgb @ yw
    ry = ((rgb[..., 0] - y) / y)[::2, ::2].astype(np.float16)
    by = ((rgb[..., 2] - y) / y)[::2, ::2].astype(np.float16)
    try:  # a binding that takes the subsampled shape as it is
        _write(path, {"Y": OpenEXR.Channel("Y", y.astype(np.float16), 1, 1), "RY": OpenEXR.Channel("RY", ry, 2, 2),
                      "BY": OpenEXR.Channel("BY", by, 2, 2)}, **header)  # fmt: skip
    except ValueError:  # 3.5: "channel shapes differ"
        _write(path, {"Y": OpenEXR.Channel("Y", y.astype(np.float16), 1, 1),
                      "RY": OpenEXR.Channel("RY", _packed(ry, (h, w)), 2, 2),
                      "BY": OpenEXR.Channel("BY", _packed(by, (h, w)), 2, 2)}, **header)  # fmt: skip
    with OpenEXR.File(str(path), separate_channels=True) as exr:  # the file holds what we meant
        assert np.array_equal(exr.channels()["RY"].pixels, ry)
        assert np.array_equal(exr.channels()["BY"].pixels, by)
    return ry, by


def _smooth_rgb(h: int, w: int, period: float = 64.0) -> np.ndarray:
    y, x = np.mgrid[0:h, 0:w].astype(np.float64)
    return np.stack([
        1.0 + 0.6 * np.sin(2 * np.pi * x / period + 0.3) * np.cos(2 * np.pi * y / period),
        0.8 + 0.3 * np.cos(2 * np.pi * (x + y) / (1.5 * period)),
        0.6 + 0.4 * np.sin(2 * np.pi * y / period + 1.0),
    ], axis=-1)  # fmt: skip


@pytest.mark.parametrize(("chroma", "yw"), [(None, REC709_YW), (AP1, AP1_YW)])
def test_luminance_chroma_file_comes_back_as_its_rgb(tmp_path, chroma, yw):
    """A known smooth RGB image (period 64 px) encoded as Y + 2 × 2 subsampled RY, BY.

    Stated errors (relative, per channel): at the stored chroma samples (even x and y) only
    half-float rounding of Y, RY, BY (2⁻¹¹ each): < 2·10⁻³; elsewhere in the interior (≥ 14 px
    from the border, beyond the filter's reach) plus the reconstruction of the odd pixels by
    OpenEXR's interpolation filter: < 5·10⁻³ (measured 3·10⁻³); a constant colour: < 10⁻³
    everywhere. Within 14 px of the border the filter repeats the edge samples (as OpenEXR's
    RgbaInputFile does), which costs up to ~5 % on this content: bounded at 0.1. With AP1
    chromaticities the AP1 weights must be used (Rec. 709 weights put G off by > 5 %)."""
    rgb = _smooth_rgb(64, 128)
    header = {} if chroma is None else {"chromaticities": chroma}
    path = tmp_path / "yca.exr"
    _write_yca(path, rgb, yw, **header)
    image = read_exr_image(path)
    assert image.colour == "yca" and image.pixels.shape == (64, 128, 3)
    rel = np.abs(image.pixels - rgb) / rgb
    assert rel[::2, ::2].max() < 2e-3, rel[::2, ::2].max()
    assert rel[14:-14, 14:-14].max() < 5e-3, rel[14:-14, 14:-14].max()
    assert rel.max() < 0.1, rel.max()
    env = load_env(path, up="z")  # the file's own pixel grid (read as stored)
    assert np.allclose(env.radiance, image.pixels)
    colour = np.ones((32, 64, 3)) * [0.2, 1.5, 0.7]
    _write_yca(tmp_path / "constant.exr", colour, yw, **header)
    assert (np.abs(read_exr(tmp_path / "constant.exr") - colour) / colour).max() < 1e-3
    if chroma is not None:  # the attribute matters
        y = colour @ yw
        wrong_g = (y - colour[..., 0] * REC709_YW[0] - colour[..., 2] * REC709_YW[2]) / REC709_YW[1]
        assert np.abs(wrong_g / colour[..., 1] - 1).min() > 0.05


def test_grey_luminance_chroma_is_exact_and_luminance_only_is_grey(tmp_path, shared_data):
    """OpenEXR's special case: RY = BY = 0 gives R = G = B = Y exactly. Garden.exr (a tiled
    luminance-only file) reads as grey equal to its Y channel."""
    grey = np.linspace(0.1, 4.0, 32 * 64).reshape(32, 64)
    rgb = np.repeat(grey[..., None], 3, axis=-1)
    path = tmp_path / "grey.exr"
    _write_yca(path, rgb, REC709_YW)
    y = grey.astype(np.float16).astype(np.float32)
    assert np.array_equal(read_exr(path), np.repeat(y[..., None], 3, axis=-1))
    garden = shared_data / "env" / "openexr_images" / "Garden.exr"
    with OpenEXR.File(str(garden), separate_channels=True) as exr:
        y = exr.channels()["Y"].pixels.astype(np.float32)
    image = read_exr_image(garden)
    assert image.colour == "y" and image.pixels.shape == y.shape + (3,)
    assert all(np.array_equal(image.pixels[..., c], y) for c in range(3))


# --------------------------------------------------------------------------------------
# 3. data and display windows
# --------------------------------------------------------------------------------------
def test_centred_data_window_lights_a_quarter(tmp_path):
    """32 × 16 data window centred in a 64 × 32 display window: exactly columns 16..47 and rows
    8..23 (a quarter of the pixels) are lit, the rest is 0; the map is 2:1 on the display window."""
    path = _write(tmp_path / "bbox.exr", _rgb("", 2.0, (16, 32)),
                  dataWindow=_box(16, 8, 47, 23), displayWindow=_box(0, 0, 63, 31))  # fmt: skip
    env = load_env(path, up="z")  # read as stored: display pixel (i, j) is map pixel (i, j)
    assert env.radiance.shape == (32, 64, 3)
    lit = env.radiance.max(axis=-1) > 0
    assert lit.sum() == 32 * 64 // 4
    expected = np.zeros((32, 64), bool)
    expected[8:24, 16:48] = True
    assert np.array_equal(lit, expected) and np.all(env.radiance[lit] == 2.0)


def test_upper_hemisphere_data_window_loads(tmp_path):
    path = _write(tmp_path / "sky.exr", _rgb("", 1.0, (16, 64)),
                  dataWindow=_box(0, 0, 63, 15), displayWindow=_box(0, 0, 63, 31))  # fmt: skip
    env = load_env(path)
    assert env.radiance.shape == (32, 64, 3)
    assert np.all(env.radiance[:16] == 1.0) and np.all(env.radiance[16:] == 0.0)
    # the flux is the upper hemisphere's: 2π per channel
    assert np.allclose(env.integral(), 2 * np.pi)


def test_data_window_with_negative_origin_is_cropped(tmp_path):
    """Data window (−5, −3)–(26, 12) in a (0, 0)–(63, 31) display window: display pixel (y, x)
    holds data pixel (y + 3, x + 5); data outside the display window is dropped."""
    value = np.arange(16 * 32, dtype=np.float32).reshape(16, 32)
    channels = {"R": value, "G": value + 1, "B": value + 2}
    path = _write(tmp_path / "neg.exr", channels, dataWindow=_box(-5, -3, 26, 12), displayWindow=_box(0, 0, 63, 31))
    image = read_exr_image(path)
    assert image.pixels.shape == (32, 64, 3) and image.data.shape == (16, 32, 3)
    expected = np.zeros((32, 64), np.float32)
    expected[0:13, 0:27] = value[3:16, 5:32]
    assert np.array_equal(image.pixels[..., 0], expected)
    assert np.array_equal(image.pixels[..., 2][0:13, 0:27], expected[0:13, 0:27] + 2)
    assert any("cropped" in note for note in image.notes)
    # a display window with its own offset: only the offset between the two windows matters
    path = _write(tmp_path / "offset.exr", channels, dataWindow=_box(95, 197, 126, 212),
                  displayWindow=_box(100, 200, 163, 231))  # fmt: skip
    assert np.array_equal(read_exr(path)[..., 0], expected)


# --------------------------------------------------------------------------------------
# 4. parts, 6. deep parts
# --------------------------------------------------------------------------------------
def _parts(path: Path, parts: list[tuple[str, dict]]) -> Path:
    def head() -> dict:  # one dict per part: the bindings write the part name into it
        return {"type": OpenEXR.scanlineimage, "compression": OpenEXR.ZIP_COMPRESSION}

    with OpenEXR.File([OpenEXR.Part(head(), channels, name) for name, channels in parts]) as exr:
        exr.write(str(path))
    return path


def test_the_part_with_rgb_is_read(tmp_path):
    path = _parts(tmp_path / "mp.exr", [("depth", {"Z": np.full((4, 8), 7.0, np.float32)}),
                                       ("beauty", _rgb("", (1, 2, 3)))])  # fmt: skip
    image = read_exr_image(path)
    assert (image.part, image.part_name) == (1, "beauty") and np.all(image.pixels == [1, 2, 3])
    assert np.all(load_env(path).radiance == [1, 2, 3])


def test_several_rgb_parts_need_a_choice(tmp_path):
    path = _parts(tmp_path / "stereo.exr", [("left", _rgb("", 1.0)), ("right", _rgb("", 2.0))])
    with pytest.raises(BadInputError, match=r"2 parts with colour.*part 0 'left'.*part 1 'right'"):
        read_exr(path)
    assert np.all(read_exr(path, part="right") == 2.0)
    assert np.all(read_exr(path, part=0) == 1.0)
    assert np.all(load_env(path, part="1").radiance == 2.0)
    with pytest.raises(BadInputError, match=r"no part named 'centre'"):
        read_exr(path, part="centre")
    with pytest.raises(BadInputError, match="out of range"):
        read_exr(path, part=2)
    parser = argparse.ArgumentParser()
    add_env_orientation(parser)
    assert np.all(load_env_arg(str(path), parser.parse_args(["--env-part", "left"])).radiance == 1.0)


def _deep_part(name: str) -> OpenEXR.Part:
    samples = np.empty((4, 8), dtype=object)
    for i in range(4):
        for j in range(8):
            samples[i, j] = np.full((i + j) % 3, 0.5, np.float32)
    channels = {c: samples for c in ("R", "G", "B", "Z")}
    return OpenEXR.Part({"type": OpenEXR.deepscanline, "compression": OpenEXR.ZIPS_COMPRESSION}, channels, name)


def test_deep_images_are_refused(tmp_path):
    path = tmp_path / "deep.exr"
    with OpenEXR.File([_deep_part("deep")]) as exr:
        exr.write(str(path))
    with OpenEXR.File(str(path), header_only=True) as exr:  # the file is what we meant
        assert exr.header()["type"] == OpenEXR.deepscanline
    with pytest.raises(BadInputError, match="deep OpenEXR images are not environment maps"):
        read_exr(path)
    with pytest.raises(BadInputError, match="deep.exr: deep OpenEXR images are not environment maps"):
        load_env(path)
    # beside a flat RGB part: still refused (reading the file would decode the deep part)
    flat = OpenEXR.Part({"type": OpenEXR.scanlineimage}, _rgb("", 1.0), "flat")
    with OpenEXR.File([flat, _deep_part("deep")]) as exr:
        exr.write(str(tmp_path / "mixed.exr"))
    with pytest.raises(BadInputError, match=r"deep OpenEXR.*part 1 'deep' is deepscanline"):
        read_exr(tmp_path / "mixed.exr")


# --------------------------------------------------------------------------------------
# 5. the envmap attribute
# --------------------------------------------------------------------------------------
AXES = {"+X": (1, 0, 0), "-X": (-1, 0, 0), "+Y": (0, 1, 0), "-Y": (0, -1, 0), "+Z": (0, 0, 1), "-Z": (0, 0, -1)}


def _dark_fraction(env: EnvironmentMap, a, b, start=3.0, stop=12.0) -> float:
    """Fraction of the great-circle arc from axis a toward b (start..stop degrees) that is dark."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    t = np.radians(np.linspace(start, stop, 40))
    return float((env.lookup(np.cos(t)[:, None] * a + np.sin(t)[:, None] * b).max(axis=-1) < 0.5).mean())


def _line_offset_deg(env: EnvironmentMap, a, b, c, along=6.0) -> float:
    """Angular offset toward c of the dark line running from axis a toward b, `along` degrees out."""
    a, b, c = (np.asarray(v, float) for v in (a, b, c))
    p = np.cos(np.radians(along)) * a + np.sin(np.radians(along)) * b
    offsets = np.linspace(-3.0, 3.0, 601)
    o = np.radians(offsets)[:, None]
    darkness = np.clip(0.5 - env.lookup(np.cos(o) * p + np.sin(o) * c).max(axis=-1), 0, None)
    return float((offsets * darkness).sum() / darkness.sum())


@pytest.mark.parametrize("name", ["OrientationLatLong.exr", "OrientationCube.exr"])
def test_openexr_orientation_markers_land_on_our_axes(shared_data, name):
    """OpenEXR's Orientation images draw, at each axis ±x_e, ±y_e, ±z_e, a black 'L' whose corner
    is the axis and whose arms run toward the positive axes of the other two (seen in the cube
    file, face by face). OPENEXR_TO_PROJECT (X = x_e, Y = −z_e, Z = y_e) puts the corners on our
    ±X, ±Y, ±Z and the arms toward +X (from x_e), +Z (from y_e) and −Y (from z_e)."""
    path = shared_data / "env" / "openexr_images" / name
    env = load_env(path, height=256)
    assert env.radiance.shape == (256, 512, 3) and "openexr-" in env.source
    arm_of = {"x": "+X", "y": "+Z", "z": "-Y"}
    for e_axis in ("+x", "-x", "+y", "-y", "+z", "-z"):
        ours = "".join(str(int(v)) for v in OPENEXR_TO_PROJECT @ np.array(AXES[e_axis.upper()]))
        corner = next(k for k, v in AXES.items() if "".join(str(v_) for v_ in v) == ours)
        arms = [arm_of[o] for o in "xyz" if o != e_axis[1]]
        away = [("-" if a[0] == "+" else "+") + a[1] for a in arms]
        for arm, other in zip(arms, reversed(arms), strict=True):
            assert _dark_fraction(env, AXES[corner], AXES[arm]) > 0.9, (e_axis, corner, arm)
            # the line passes through the corner: within 0.3° (a pixel here is 0.7°)
            assert abs(_line_offset_deg(env, AXES[corner], AXES[arm], AXES[other])) < 0.3, (e_axis, arm)
        for arm in away:
            assert _dark_fraction(env, AXES[corner], AXES[arm]) < 0.1, (e_axis, corner, arm)


def test_openexr_cube_and_latlong_agree(shared_data):
    """The lat-long and the cube version of each OpenEXR test map give the same map: relative
    RMS difference at 64 × 128 (measured 1.0 % for both pairs), same flux, same sun pixel."""
    folder = shared_data / "env" / "openexr_images"
    for pair in (("OrientationLatLong.exr", "OrientationCube.exr"), ("KernerEnvLatLong.exr", "KernerEnvCube.exr")):
        maps = [load_env(folder / name, height=64) for name in pair]
        a, b = (m.radiance.astype(np.float64) for m in maps)
        rel = np.sqrt(np.mean((a - b) ** 2) / np.mean(a**2))
        assert rel < 0.03, (pair, rel)
        # the flux agrees (measured within 0.3 %) and Kerner's sun is in the same pixel
        assert np.allclose(maps[0].integral(), maps[1].integral(), rtol=0.01), pair
        assert a.max(axis=-1).argmax() == b.max(axis=-1).argmax() or "Orientation" in pair[0]


def test_openexr_cube_faces_by_construction(tmp_path):
    """Six constant faces (value = face index + 1, OpenEXR order +X, −X, +Y, −Y, +Z, −Z): our
    map looks up value k + 1 in the project direction OPENEXR_TO_PROJECT · axis_k."""
    n = 8
    values = np.repeat(np.arange(1.0, 7.0), n)[:, None].repeat(n, axis=1).astype(np.float32)  # (6n, n)
    path = _write(tmp_path / "cube.exr", {"R": values, "G": values, "B": values}, envmap=OpenEXR.ENVMAP_CUBE)
    env = load_env(path, height=32)
    for k, name in enumerate(("+X", "-X", "+Y", "-Y", "+Z", "-Z")):
        direction = OPENEXR_TO_PROJECT @ np.array(AXES[name], float)
        assert np.allclose(env.lookup(direction), k + 1), name
    assert np.isclose(np.linalg.det(OPENEXR_TO_PROJECT), 1.0)


def test_envmap_attribute_options(tmp_path, shared_data):
    path = shared_data / "env" / "openexr_images" / "KernerEnvLatLong.exr"
    with pytest.raises(BadInputError, match="up='z' does not apply"):
        load_env(path, up="z")
    with pytest.raises(BadInputError, match="flip and probe do not apply"):
        load_env(path, flip=True)
    base = load_env(path, height=16)
    assert np.allclose(load_env(path, height=16, up="y").radiance, base.radiance)
    assert np.allclose(load_env(path, height=16, azimuth=90).radiance, base.rotated_z(np.pi / 2).radiance)
    bad = _write(tmp_path / "badcube.exr", _rgb("", 1.0, (8, 8)), envmap=OpenEXR.ENVMAP_CUBE)
    with pytest.raises(BadInputError, match="six stacked square faces"):
        load_env(bad)


# --------------------------------------------------------------------------------------
# 7. slightly negative pixels
# --------------------------------------------------------------------------------------
def test_desk_photograph_negatives_are_clamped_with_a_count(shared_data):
    """Desk.exr: 9,354 pixels have a channel below 0 (down to −0.012, counted here from the
    bindings' own read) against a white level of 181: clamped, with a warning that counts them."""
    path = shared_data / "env" / "openexr_images" / "Desk.exr"
    with OpenEXR.File(str(path), separate_channels=True) as exr:
        raw = np.stack([exr.channels()[c].pixels.astype(np.float32) for c in "RGB"], axis=-1)
    count = int((raw < 0).any(axis=-1).sum())
    assert count == 9354
    with pytest.warns(UserWarning, match=rf"clamped {count} negative pixel\(s\) to 0 \(min -0.0119"):
        env = EnvironmentMap(read_exr(path), "desk", str(path))
    assert env.radiance.min() == 0.0
    assert np.array_equal(env.radiance, np.maximum(raw, 0))


def test_negative_threshold(tmp_path):
    """Negatives down to NEGATIVE_CLAMP_FRACTION × the white level (99.9th percentile of the
    per-pixel largest channel) are clamped with a warning; beyond it the map is refused."""
    image = np.full((64, 128, 3), 4.0, np.float32)
    image[0, 0, 1] = 1000.0  # a 'sun' in one pixel (0.012 %) does not raise the white level
    assert white_level(image) == 4.0
    limit = NEGATIVE_CLAMP_FRACTION * 4.0
    image[5, 5, 0] = -0.9 * limit
    _write(tmp_path / "ok.exr", {"R": image[..., 0], "G": image[..., 1], "B": image[..., 2]})
    with pytest.warns(UserWarning, match=r"ok.exr: clamped 1 negative pixel"):
        env = load_env(tmp_path / "ok.exr", up="z")  # read as stored: pixel (5, 5) stays (5, 5)
    assert env.radiance[5, 5, 0] == 0.0 and env.radiance[5, 5, 1] == 4.0
    image[5, 5, 0] = -1.1 * limit
    _write(tmp_path / "bad.exr", {"R": image[..., 0], "G": image[..., 1], "B": image[..., 2]})
    with pytest.raises(BadInputError, match=r"bad.exr: 1 pixel\(s\) with negative radiance.*refused"):
        load_env(tmp_path / "bad.exr")


# --------------------------------------------------------------------------------------
# 8. truncated and hostile files
# --------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["KernerEnvLatLong.exr", "Desk.exr"])
def test_truncated_file_gives_one_line(tmp_path, shared_data, capfd, name):
    """A truncated tiled (Kerner) or scanline (Desk) file: the C library writes up to hundreds of
    lines to fd 2 and the bindings print a warning; the user gets one BadInputError, nothing else."""
    data = (shared_data / "env" / "openexr_images" / name).read_bytes()
    for cut in (len(data) // 1000, len(data) // 2, len(data) - 100):
        path = tmp_path / f"cut{cut}.exr"
        path.write_bytes(data[:cut])
        capfd.readouterr()
        with pytest.raises(BadInputError) as info:
            read_exr(path)
        out, err = capfd.readouterr()
        assert (out, err) == ("", ""), (out[:300], err[:300])
        text = str(info.value)
        assert text.startswith(f"{path}: ") and "\n" not in text and len(text) < 600, text


def test_truncated_file_through_the_cli(tmp_path, shared_data):
    data = (shared_data / "env" / "openexr_images" / "KernerEnvCube.exr").read_bytes()
    path = tmp_path / "cut.exr"
    path.write_bytes(data[: len(data) // 3])
    proc = subprocess.run(
        [sys.executable, "-m", "shrmkit.cli.main", "orders", "phong:s=8", "--env", str(path)],
        capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert proc.returncode == 2, proc.stderr[-2000:]
    assert len(proc.stderr.strip().splitlines()) == 1 and "cut.exr" in proc.stderr, proc.stderr[-2000:]
    assert "Traceback" not in proc.stderr and proc.stdout == ""


def _patched(path: Path, **boxes: tuple[int, int, int, int]) -> Path:
    """Rewrite box2i attributes (dataWindow, displayWindow) of a small file in place."""
    data = bytearray(path.read_bytes())
    for name, box in boxes.items():
        key = name.encode() + b"\x00box2i\x00"
        at = data.index(key) + len(key)
        assert struct.unpack("<i", data[at : at + 4])[0] == 16
        data[at + 4 : at + 20] = struct.pack("<4i", *box)
    path.write_bytes(bytes(data))
    return path


def test_declared_sizes_are_checked_before_reading(tmp_path):
    """A 1 KB file declaring 10⁹ pixels, or 8192² (under the size limits, but a chunk table
    the file cannot hold), or a huge display window: refused from the header alone."""
    small = _write(tmp_path / "small.exr", _rgb("", 1.0), compression=OpenEXR.NO_COMPRESSION)
    assert small.stat().st_size < 1024
    big = (0, 0, 39999, 24999)
    for name, boxes, match in [
        ("bomb.exr", {"dataWindow": big, "displayWindow": big}, "pixel limit"),
        ("square.exr", {"dataWindow": (0, 0, 8191, 8191), "displayWindow": (0, 0, 8191, 8191)}, "too small"),
        ("display.exr", {"displayWindow": big}, "pixel limit"),
    ]:
        path = tmp_path / name
        path.write_bytes(small.read_bytes())
        _patched(path, **boxes)
        with pytest.raises(BadInputError, match=match):
            read_exr(path)


def test_special_and_foreign_files(tmp_path):
    fifo = tmp_path / "fifo.exr"
    os.mkfifo(fifo)
    with pytest.raises(BadInputError, match="FIFO"):
        read_exr(fifo)
    (tmp_path / "zero.exr").symlink_to("/dev/zero")
    with pytest.raises(BadInputError, match="device"):
        load_env(tmp_path / "zero.exr")
    (tmp_path / "text.exr").write_bytes(b"#?RADIANCE\n")
    with pytest.raises(BadInputError, match="magic"):
        read_exr(tmp_path / "text.exr")
    (tmp_path / "empty.exr").write_bytes(b"")
    with pytest.raises(BadInputError, match="magic"):
        read_exr(tmp_path / "empty.exr")
    (tmp_path / "header.exr").write_bytes(b"\x76\x2f\x31\x01\x02\x00\x00\x00channels\x00chlist\x00")
    with pytest.raises(BadInputError, match="not a readable OpenEXR file"):
        read_exr(tmp_path / "header.exr")


# --------------------------------------------------------------------------------------
# 8. windows that declare far more than the file holds, refused before they are allocated
# --------------------------------------------------------------------------------------
def _peak_bytes(call) -> tuple[int, BaseException | None]:
    """Peak traced allocation (numpy's included) of ``call()`` and what it raised."""
    import tracemalloc

    tracemalloc.start()
    try:
        call()
        raised = None
    except BaseException as err:  # noqa: BLE001 - returned to the test
        raised = err
    finally:
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
    return peak, raised


def test_huge_display_window_of_a_small_file_is_refused_before_it_is_allocated(tmp_path):
    """An 8 × 16 data window on a 16 × 4,194,305 display window (a few hundred bytes, found by the
    fuzz harness: ``--seed 20261130 --cases 20 --show exr:7``): not a 2:1 lat-long map, refused from
    the header. Before, the display window was filled first (16 × 4,194,305 × 3 float32 = 805 MB)."""
    path = _write(tmp_path / "tall.exr", _rgb("", 1.0, (8, 16)), displayWindow=((0, 0), (15, 4194304)))
    peak, raised = _peak_bytes(lambda: load_env(path))
    assert isinstance(raised, BadInputError) and "2:1" in str(raised) and "tall.exr" in str(raised)
    assert peak < 16 << 20, f"{peak / 2**20:.0f} MiB allocated before the refusal"


def test_envmap_latlong_output_beyond_the_pixel_limit_is_refused_from_the_header(tmp_path):
    """envmap=latlong on a 20,000-row, 1-column data window: its default lat-long output would be
    20,000 × 40,000 pixels (issue 30: 24-149 GiB asked for); refused by the pixel limit before the
    pixels are read, naming the file."""
    path = _write(tmp_path / "strip.exr", _rgb("", 1.0, (20000, 1)), envmap=OpenEXR.ENVMAP_LATLONG)
    peak, raised = _peak_bytes(lambda: load_env(path))
    assert isinstance(raised, BadInputError) and "SHRM_MAX_PIXELS" in str(raised) and "strip.exr" in str(raised)
    assert peak < 16 << 20
    assert load_env(path, height=16).radiance.shape == (16, 32, 3)  # a size the user asks for is read
