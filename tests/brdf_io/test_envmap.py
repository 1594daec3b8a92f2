"""EnvironmentMap geometry, resampling, built-ins and save/load, against closed forms."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import integrate

from shrmkit.brdf_io.envmap import EnvironmentMap, load_env, save_env
from shrmkit.brdf_io.errors import BadInputError


def _brightest_direction(env: EnvironmentMap) -> np.ndarray:
    lum = env.radiance.mean(axis=-1)
    return env.directions()[np.unravel_index(np.argmax(lum), lum.shape)]


def _mean_direction(env: EnvironmentMap) -> np.ndarray:
    """Flux-weighted mean direction Σ L Ω ω / |...| (the centre of a symmetric disc)."""
    weight = env.radiance.mean(axis=-1) * env.solid_angles()[:, None]
    m = (weight[..., None] * env.directions()).sum(axis=(0, 1))
    return m / np.linalg.norm(m)


def test_pixel_centres_and_solid_angles():
    """Reference: DESIGN §2 formulas by hand, and scipy dblquad of sin θ over each row band."""
    env = EnvironmentMap(np.zeros((4, 8, 3)))
    d = env.directions()
    theta, phi = np.pi / 8, 2 * np.pi * 0.5 / 8
    assert np.allclose(d[0, 0], [np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)])
    assert np.allclose(np.linalg.norm(d, axis=-1), 1.0)
    omega = env.solid_angles()
    for i in range(4):
        ref, _ = integrate.dblquad(
            lambda t, p: np.sin(t), 0.0, 2 * np.pi / 8, i * np.pi / 4, (i + 1) * np.pi / 4
        )
        assert omega[i] == pytest.approx(ref, rel=1e-12)
    assert omega.sum() * 8 == pytest.approx(4 * np.pi, rel=1e-14)


def test_lookup_bilinear_wraps_and_clamps():
    """Reference: hand-computed bilinear weights between known pixel centres."""
    rng = np.random.default_rng(3)
    env = EnvironmentMap(rng.random((6, 12, 3)))
    d = env.directions()
    assert np.allclose(env.lookup(d), env.radiance)
    # halfway across the φ = 0 seam, row 2: mean of the last and first column
    theta = 2.5 * np.pi / 6
    seam = np.array([np.sin(theta), 0.0, np.cos(theta)])
    assert np.allclose(env.lookup(seam * 3.0), 0.5 * (env.radiance[2, 0] + env.radiance[2, -1]))
    # the pole itself: clamped to row 0, mean over the two nearest columns at φ = 0
    assert np.allclose(env.lookup(np.array([0.0, 0.0, 1.0])), 0.5 * (env.radiance[0, 0] + env.radiance[0, -1]))
    # a point a quarter of the way between two row centres
    t = (1.5 + 0.25) * np.pi / 6
    p = 2 * np.pi * 3.5 / 12
    q = np.array([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)])
    assert np.allclose(env.lookup(q), 0.75 * env.radiance[1, 3] + 0.25 * env.radiance[2, 3])
    with pytest.raises(BadInputError):
        env.lookup(np.zeros(3))


@pytest.mark.parametrize("height", [64, 48, 100, 256])
def test_sky_integral_closed_form_and_resizing(height):
    """Reference: ∫ sky = 2π(h + (z − h)/2) + 2π g + ratio·z·2π(1 − cos r) (builtin_env docstring)."""
    env = load_env(f"builtin:sky,height={height},sun_elevation=35,sun_azimuth=120")
    z, h, g = np.array([0.3, 0.5, 1.0]), np.array([0.8, 0.85, 0.9]), np.array([0.1, 0.09, 0.08])
    expected = 2 * np.pi * (h + (z - h) / 2) + 2 * np.pi * g + 1e4 * z * 2 * np.pi * (1 - np.cos(np.radians(1.0)))
    assert np.allclose(env.integral(), expected, rtol=1e-12)
    for new_height in (32, 37, 2 * height):
        assert np.allclose(env.resized(new_height).integral(), expected, rtol=1e-12)
    # the sun: brightest pixel within a pixel of (elevation 35°, azimuth 120°)
    sun = np.array([np.cos(np.radians(35)) * np.cos(np.radians(120)),
                    np.cos(np.radians(35)) * np.sin(np.radians(120)), np.sin(np.radians(35))])  # fmt: skip
    assert np.degrees(np.arccos(_brightest_direction(env) @ sun)) < 2 * 180 / height


def test_resize_integer_factor_is_weighted_block_mean():
    """Reference: a 2×2 block mean weighted by the exact row solid angles, written out."""
    rng = np.random.default_rng(4)
    env = EnvironmentMap(rng.random((8, 16, 3)))
    small = env.resized(4)
    w = env.solid_angles()
    block = env.radiance[2:4, 6:8]
    expected = (w[2] * block[0].sum(0) + w[3] * block[1].sum(0)) / (2 * (w[2] + w[3]))
    assert np.allclose(small.radiance[1, 3], expected)
    assert np.allclose(load_env("builtin:constant,value=2.5,height=9").resized(4).radiance, 2.5)


def test_constant_spot_sun_builtins():
    """References: 4π·value; cap flux value·2π(1 − cos r); one pixel at ratio × sky."""
    const = load_env("builtin:constant,value=1/2/3,height=16")
    assert const.radiance.shape == (16, 32, 3)
    assert np.allclose(const.integral(), 4 * np.pi * np.array([1.0, 2.0, 3.0]), rtol=1e-13)
    spot = load_env("builtin:spot,dir=-y,radius=10,value=50")
    assert np.allclose(spot.integral(), 50 * 2 * np.pi * (1 - np.cos(np.radians(10))), rtol=1e-12)
    assert np.degrees(np.arccos(-_mean_direction(spot)[1])) < 0.1
    sun = load_env("builtin:sun,height=64,elevation=30,azimuth=200")
    lum = sun.radiance[..., 0]
    assert np.count_nonzero(lum > 0.011) == 1
    assert lum.max() == pytest.approx(1e5 * 0.01)
    d = _brightest_direction(sun)
    assert np.degrees(np.arcsin(d[2])) == pytest.approx(30, abs=180 / 64)
    assert np.degrees(np.arctan2(d[1], d[0])) % 360 == pytest.approx(200, abs=180 / 64)
    studio = load_env("builtin:studio,height=32")
    assert studio.radiance.min() >= 0.02 and studio.radiance.max() > 5.0


@pytest.mark.parametrize(
    ("spec", "message"),
    [
        ("builtin:moon", "valid: sky, studio, constant, spot, sun"),
        ("builtin:sky,sun_size=3", "valid: height, zenith"),
        ("builtin:sky,height=0", "height=0 outside"),
        ("builtin:sky,height=10.5", "not an integer"),
        ("builtin:spot,dir=w", "choose one of x"),
        ("builtin:spot,dir=x,elevation=3", "either dir"),
        ("builtin:constant,value=-1", "outside"),
        ("builtin:constant,value=abc", "not a number"),
        ("builtin:constant,value", "key=value"),
        ("builtin:sun,ratio=nan", "finite"),
    ],
)
def test_builtin_bad_specs(spec, message):
    with pytest.raises(BadInputError, match=message):
        load_env(spec)


def test_rotated_z_and_azimuth():
    """Reference: a spot at azimuth 0 rotated by +90° lies along +y; flux unchanged (closed form)."""
    spot = load_env("builtin:spot,elevation=0,azimuth=0,radius=6,height=90")
    flux = 100 * 2 * np.pi * (1 - np.cos(np.radians(6)))
    turned = load_env("builtin:spot,elevation=0,azimuth=0,radius=6,height=90", azimuth=90.0)
    for env in (spot.rotated_z(np.pi / 2), turned):
        assert np.degrees(np.arccos(_mean_direction(env)[1])) < 0.1
        assert env.integral()[0] == pytest.approx(flux, rel=1e-12)
    frac = spot.rotated_z(np.radians(91.3))
    assert frac.integral()[0] == pytest.approx(flux, rel=1e-12)
    mean_dir = _mean_direction(frac)
    assert np.degrees(np.arctan2(mean_dir[1], mean_dir[0])) == pytest.approx(91.3, abs=0.1)


def test_dataclass_validation_and_read_only():
    radiance = np.ones((2, 4, 3))
    env = EnvironmentMap(radiance, "x", "test")
    radiance[0, 0, 0] = 5.0
    assert env.radiance[0, 0, 0] == 1.0
    with pytest.raises(ValueError):
        env.radiance[0, 0, 0] = 2.0
    bad = np.ones((2, 4, 3))
    bad[0, 0, 1] = np.nan
    bad[1, 1] = -1.0
    with pytest.raises(BadInputError, match=r"test: 1 pixel\(s\) with NaN.*1 pixel\(s\) with negative"):
        EnvironmentMap(bad, "x", "test")
    with pytest.raises(BadInputError, match="shape"):
        EnvironmentMap(np.ones((4, 3)))
    with pytest.raises(BadInputError, match="float32 or float64"):
        EnvironmentMap(np.ones((2, 4, 3), dtype=np.int32))


@pytest.mark.parametrize(("suffix", "half", "rtol"), [(".exr", False, 0), (".pfm", False, 0),
                                                      (".exr", True, 2**-11), (".hdr", False, 2**-8)])  # fmt: skip
def test_save_load_round_trip(tmp_path, suffix, half, rtol):
    """Reference: the saved map itself, within the storage precision (float32 exact; half; RGBE)."""
    env = load_env("builtin:sky,height=32,sun_ratio=100")
    env32 = EnvironmentMap(env.radiance.astype(np.float32), env.name, env.source)
    path = tmp_path / f"sky{suffix}"
    save_env(path, env32, half=half)
    back = load_env(path)
    peak = env32.radiance.max(axis=-1, keepdims=True)
    assert np.all(np.abs(back.radiance - env32.radiance) <= rtol * peak)
    assert back.name == "sky" and str(path) in back.source
    assert [p.name for p in tmp_path.iterdir()] == [path.name]


def test_bad_lat_long_files(tmp_path):
    """NaN/Inf/negative pixels are counted and refused with the file named; shapes are checked."""
    from shrmkit.brdf_io.hdr_codecs import write_pfm

    image = np.ones((4, 8, 3), np.float32)
    image[0, 0] = np.nan
    image[1, 1, 2] = np.inf
    image[2, 2:5, 0] = -0.5
    write_pfm(tmp_path / "bad.pfm", image)
    with pytest.raises(BadInputError) as info:
        load_env(tmp_path / "bad.pfm")
    text = str(info.value)
    assert "bad.pfm" in text and "1 pixel(s) with NaN" in text and "1 pixel(s) with infinite" in text
    assert "3 pixel(s) with negative" in text
    write_pfm(tmp_path / "wide.pfm", np.ones((4, 12, 3), np.float32))
    with pytest.raises(BadInputError, match="2:1"):
        load_env(tmp_path / "wide.pfm")
    write_pfm(tmp_path / "square.pfm", np.ones((4, 4, 3), np.float32))
    with pytest.raises(BadInputError, match="2:1"):
        load_env(tmp_path / "square.pfm")
    with pytest.raises(BadInputError, match="no such file"):
        load_env(tmp_path / "absent.exr")
    with pytest.raises(BadInputError, match="up="):
        load_env("builtin:sky", up="x")
    with pytest.raises(BadInputError, match="do not apply"):
        load_env("builtin:sky", flip=True)


def _zero_rle_hdr(path, height: int, width: int) -> None:
    """A new-style run-length Radiance file of zeros: ~2 bytes per 127 pixels and channel."""
    line = bytes([2, 2, width >> 8, width & 255])
    chan, left = b"", width
    while left:
        n = min(127, left)
        chan, left = chan + bytes([128 + n, 0]), left - n
    header = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y %d +X %d\n" % (height, width)
    path.write_bytes(header + (line + chan * 4) * height)


@pytest.mark.parametrize("suffix", [".hdr", ".pfm"])
def test_map_shape_is_checked_from_the_header_before_decoding(tmp_path, monkeypatch, suffix):
    """A small file declaring a large non-2:1 image (issue 30: a 17 MB RLE .hdr of 16384² pixels took
    15 s and 4.3 GB before the 2:1 rule refused it): refused on the header, no scanline decoded."""
    from shrmkit.brdf_io import pfm, rgbe

    path = tmp_path / f"square{suffix}"
    if suffix == ".hdr":
        _zero_rle_hdr(path, 1024, 1024)
        monkeypatch.setattr(rgbe, "_Decoder", None)  # decoding would raise TypeError
    else:
        path.write_bytes(b"PF\n1024 1024\n-1.0\n" + bytes(1024 * 1024 * 12))
        monkeypatch.setattr(pfm.np, "frombuffer", None)
    with pytest.raises(BadInputError, match="must be 2:1") as raised:
        load_env(path)
    assert str(path) in str(raised.value)
