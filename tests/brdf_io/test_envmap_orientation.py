"""The default orientation of lat-long map files: y-up, as the tools that read panoramas place them.

Independent references, each written here from the tool's own source (not from ``brdf_io``):

- three.js ``equirectUv`` (src/renderers/shaders/ShaderChunk/common.glsl.js): u = atan2(d_z, d_x)/2π + ½,
  v = asin(d_y)/π + ½ with the texture's top row at v = 1 (``flipY``), in three.js' y-up world; mapped
  to our z-up frame by (X, Y, Z) = (x, −z, y) (the y-up → z-up convention of glTF and Blender);
- Blender Cycles ``direction_to_equirectangular`` (kernel/camera/projection.h): u = ½ − atan2(d_y, d_x)/2π,
  v = 1 − acos(d_z)/π in Blender's own z-up, right-handed world (our frame), v = 1 the picture's top;
- Mitsuba 3 ``envmap`` (src/emitters/envmap.cpp, ``direction_to_uv``): u = atan2(d_x, −d_z)/2π,
  v = acos(d_y)/π in its y-up world (image centre toward +z, like OpenEXR's ``LatLongMap``): the same
  placement once its direction (x, y, z) is our (z, x, y); under three.js' axis mapping above it
  would sit a quarter turn away. Its emitter itself is evaluated where Mitsuba is installed;
- OpenEXR's ``KernerEnvLatLong.exr``, a real probe whose ``envmap`` attribute states its orientation
  (read by ImfEnvmap's convention, data_specs/environment_maps.md §2.2).
"""

from __future__ import annotations

import numpy as np
import pytest

from shrmkit.brdf_io.envmap import load_env, save_env
from shrmkit.brdf_io.exr import read_exr_image
from shrmkit.brdf_io.hdr_codecs import read_image, write_image

H, W = 8, 16


def _file_pixel_directions_three_js(h: int, w: int) -> np.ndarray:
    """Our-frame direction of each file pixel centre by three.js' ``equirectUv`` inverted:
    atan2(z, x) = 2π(u − ½), asin(y) = π(v − ½), u = (j + ½)/w, v = 1 − (i + ½)/h."""
    u = (np.arange(w) + 0.5) / w
    v = 1.0 - (np.arange(h) + 0.5) / h
    psi, lat = np.meshgrid(2 * np.pi * (u - 0.5), np.pi * (v - 0.5))
    x, y, z = np.cos(lat) * np.cos(psi), np.sin(lat), np.cos(lat) * np.sin(psi)
    return np.stack([x, -z, y], axis=-1)  # (X, Y, Z) = (x, −z, y)


def _blender_pixel(d: np.ndarray, h: int, w: int) -> tuple[np.ndarray, np.ndarray]:
    """(row from the top, column) of the file pixel Cycles' equirectangular mapping reads for the
    z-up direction d."""
    u = 0.5 - np.arctan2(d[..., 1], d[..., 0]) / (2 * np.pi)
    v = 1.0 - np.arccos(np.clip(d[..., 2], -1, 1)) / np.pi
    return np.floor((1.0 - v) * h).astype(int), np.floor(np.mod(u, 1.0) * w).astype(int) % w


def _mitsuba_uv(d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Mitsuba 3's (u, v) of our direction d, its world direction being (Y, Z, X)."""
    m = np.stack([d[..., 1], d[..., 2], d[..., 0]], axis=-1)
    return np.mod(np.arctan2(m[..., 0], -m[..., 2]) / (2 * np.pi), 1.0), np.arccos(np.clip(m[..., 1], -1, 1)) / np.pi


@pytest.fixture
def y_up_file(tmp_path):
    """A small panorama of distinct values (our writer), with one bright pixel: the one that
    three.js' mapping puts at the zenith-side row straight ahead (+x, file column W/2)."""
    rng = np.random.default_rng(3)
    image = rng.uniform(0.1, 1.0, size=(H, W, 3)).astype(np.float32)
    image[2, W // 2] = 50.0
    path = tmp_path / "pano.exr"
    write_image(path, image)
    return path, image


def test_default_is_y_up_as_three_js_blender_and_mitsuba_read_it(y_up_file):
    """At every file pixel centre, as three.js places it in our frame, the default reading holds that
    pixel's value exactly; Cycles' mapping finds the same pixel for that direction, and so does
    Mitsuba's with its world direction (Y, Z, X). The bright pixel lands ahead (+X) and up."""
    path, image = y_up_file
    env = load_env(path)
    d = _file_pixel_directions_three_js(H, W)
    assert np.array_equal(env.lookup(d).astype(np.float32), image)  # bilinear at pixel centres: exact
    rows, cols = _blender_pixel(d, H, W)
    assert np.array_equal(rows, np.repeat(np.arange(H)[:, None], W, 1))
    assert np.array_equal(cols, np.repeat(np.arange(W)[None, :], H, 0))
    u_m, v_m = _mitsuba_uv(d)
    assert np.allclose(u_m, ((np.arange(W) + 0.5) / W)[None, :], atol=1e-12)
    assert np.allclose(v_m, ((np.arange(H) + 0.5) / H)[:, None], atol=1e-12)
    bright = env.directions()[np.unravel_index(np.argmax(env.radiance[..., 0]), (H, W))]
    assert bright[0] > 0.6 and bright[2] > 0.5 and abs(bright[1]) < 0.2  # ahead (+X), above the horizon
    assert env.source.endswith("[latlong, up=y]")


def test_up_z_reads_the_file_literally_and_differs_from_the_default(y_up_file):
    """``up="z"``: file pixel (i, j) is map pixel (i, j) at θ = (i + ½)π/H, φ = 2π(j + ½)/W (DESIGN §2);
    the default is that map mirrored in azimuth (φ → π − φ), not a rotation of it."""
    path, image = y_up_file
    literal = load_env(path, up="z")
    assert np.array_equal(literal.radiance, image) and literal.source.endswith("[latlong, up=z]")
    theta = (np.arange(H) + 0.5) * np.pi / H
    phi = 2 * np.pi * (np.arange(W) + 0.5) / W
    t, p = np.meshgrid(theta, phi, indexing="ij")
    d = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], axis=-1)
    assert np.array_equal(literal.lookup(d).astype(np.float32), image)
    default = load_env(path)
    mirrored = np.stack([-d[..., 0], d[..., 1], d[..., 2]], axis=-1)  # φ → π − φ
    assert np.array_equal(default.lookup(mirrored).astype(np.float32), image)
    assert all(not np.array_equal(np.roll(literal.radiance, k, axis=1), default.radiance) for k in range(W))


def test_save_env_writes_the_y_up_convention(tmp_path):
    """A saved map read with three.js' mapping shows each direction's radiance (so it opens unmirrored
    where panoramas are read); loading it back with the defaults gives the map itself."""
    env = load_env("builtin:sun,height=8,elevation=20,azimuth=60,ratio=1000")
    path = tmp_path / "sun.pfm"
    save_env(path, env)
    stored = read_image(path)
    d = _file_pixel_directions_three_js(8, 16)
    assert np.allclose(stored, env.lookup(d), rtol=1e-6)
    assert np.array_equal(load_env(path).radiance, env.radiance.astype(np.float32))
    assert not np.allclose(stored, env.radiance)  # the file is not the map's own grid


def test_real_probe_matches_its_own_stated_orientation(shared_data, tmp_path):
    """KernerEnvLatLong.exr read by its ``envmap`` attribute (OpenEXR's convention) against the same
    pixels saved without the attribute and read with the default: the same map turned by −90°
    (Mitsuba's quarter turn; relative log RMS 0.002 at 32 rows), its sun in the same pixel; the
    literal reading matches at no azimuth (≥ 0.4, mirrored)."""
    source = shared_data / "env" / "openexr_images" / "KernerEnvLatLong.exr"
    stated = load_env(source, height=32).radiance
    plain = tmp_path / "kerner_plain.exr"
    write_image(plain, read_exr_image(source).data.astype(np.float32))
    default = load_env(plain, height=32, azimuth=-90.0).radiance
    literal = load_env(plain, height=32, up="z").radiance

    def rel_log_rms(a: np.ndarray) -> float:
        b = np.log1p(stated)
        return float(np.sqrt(np.mean((np.log1p(a) - b) ** 2) / np.mean(b**2)))

    assert rel_log_rms(default) < 0.01
    assert np.argmax(default.sum(-1)) == np.argmax(stated.sum(-1))
    assert min(rel_log_rms(np.roll(literal, k, axis=1)) for k in range(64)) > 0.2


def test_mitsuba_envmap_emitter_sees_the_default_reading(tmp_path):
    """Mitsuba 3 (3.9.1, scalar_rgb) loads a y-up file written by our writer whose radiance depends on
    the azimuth only (2 + cos φ + ½ sin φ, so that Mitsuba's rows, sampled pole to pole, do not
    matter); its emitter's radiance toward its direction (Y, Z, X) equals the default reading's toward
    (X, Y, Z): both interpolate the same columns the same way (measured 4e-7, float32); the literal
    reading (mirrored) is off by more than 20 % (measured 213 %)."""
    mi = pytest.importorskip("mitsuba")
    mi.set_variant("scalar_rgb")
    h, w = 32, 64
    d = _file_pixel_directions_three_js(h, w)
    phi = np.arctan2(d[..., 1], d[..., 0])
    value = 2.0 + np.cos(phi) + 0.5 * np.sin(phi)
    path = tmp_path / "azimuthal.exr"
    write_image(path, np.repeat(value[..., None], 3, axis=-1).astype(np.float32))
    emitter = mi.load_dict({"type": "envmap", "filename": str(path)})
    rng = np.random.default_rng(5)
    dirs = rng.normal(size=(100, 3))
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    theirs = []
    for x, y, z in dirs:
        si = mi.SurfaceInteraction3f()
        si.wi = mi.Vector3f(-y, -z, -x)  # wi points back, away from the environment
        theirs.append(np.array(emitter.eval(si))[0])
    theirs = np.array(theirs)
    ours = load_env(path).lookup(dirs)[:, 0]
    literal = load_env(path, up="z").lookup(dirs)[:, 0]
    assert np.max(np.abs(ours / theirs - 1)) < 1e-5
    assert np.max(np.abs(literal / theirs - 1)) > 0.2
