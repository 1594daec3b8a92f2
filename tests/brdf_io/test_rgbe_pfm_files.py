"""Radiance .hdr and PFM files written by other tools, byte by byte, against known pixels.

Every file here is built from its bytes with values chosen by hand; the expected images
come from the format rules (Radiance ``color.c``, ``resolu.c``/``image.c``, ``header.c``,
``spec_rgb.c``, ``ra_xyze.c``; Debevec's PFM page), never from our own writer. Also: the
input limits of ``brdf_io/limits.py`` (pixel count, bytes present, regular files), and a
small seeded mutation fuzz (every outcome is an image or a BadInputError).
"""

from __future__ import annotations

import os
import re
import signal
import time
import tracemalloc
from contextlib import contextmanager

import numpy as np
import pytest

from shrmkit.brdf_io.errors import BadInputError
from shrmkit.brdf_io.pfm import read_pfm
from shrmkit.brdf_io.rgbe import read_hdr

HEADER = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n"


def _ward(pixel) -> np.ndarray:
    """Ward's rgbe2float: mantissa · 2^(e − 136), black for e = 0."""
    r, g, b, e = pixel
    return np.zeros(3) if e == 0 else np.array([r, g, b], dtype=float) * 2.0 ** (e - 136)


def _rle_scanline(pixels: list[tuple[int, int, int, int]]) -> bytes:
    """A new-style scanline written with literal chunks only (<= 128 bytes each)."""
    width = len(pixels)
    out = bytearray((2, 2, width >> 8, width & 255))
    for c in range(4):
        values = [p[c] for p in pixels]
        for i in range(0, width, 128):
            piece = values[i : i + 128]
            out.append(len(piece))
            out += bytes(piece)
    return bytes(out)


def _write(tmp_path, name: str, content: bytes):
    path = tmp_path / name
    path.write_bytes(content)
    return path


# --------------------------------------------------------------------------------- pre-1991 RLE, mixing
A, B, C = (200, 100, 50, 130), (10, 20, 30, 140), (128, 128, 128, 129)


def test_old_style_repeats_shift_and_mixed_scanlines(tmp_path):
    """color.c oldreadcolrs: (1,1,1,n) repeats n << 8k times for the k-th consecutive repeat;
    freadcolrs decides per scanline (old, new, old); repeats stop at the scanline end."""
    width = 300
    line0 = bytes(A) + bytes((1, 1, 1, 43)) + bytes((1, 1, 1, 1))  # A + 43 + 1·256 copies = 300
    line1 = bytes((2, 2, 1, 44))  # new-style, 300 = 0x12C
    for value in B:
        line1 += bytes((128 + 127, value, 128 + 127, value, 128 + 46, value))
    line2 = bytes((1, 1, 1, 10)) + bytes(C) + bytes((1, 1, 1, 255)) * 2  # 10 × B, C, then 65535 clipped
    path = _write(tmp_path, "old.hdr", HEADER + b"-Y 3 +X 300\n" + line0 + line1 + line2)
    image = read_hdr(path)
    assert image.shape == (3, width, 3)
    np.testing.assert_array_equal(image[0], np.broadcast_to(_ward(A), (width, 3)))
    np.testing.assert_array_equal(image[1], np.broadcast_to(_ward(B), (width, 3)))
    np.testing.assert_array_equal(image[2, :10], np.broadcast_to(_ward(B), (10, 3)))
    np.testing.assert_array_equal(image[2, 10:], np.broadcast_to(_ward(C), (width - 10, 3)))


def test_old_style_shift_restarts_on_pixels_and_scanlines(tmp_path):
    """rshift = 0 after a plain pixel and at every scanline (each oldreadcolrs call)."""
    row0 = bytes(A) + bytes((1, 1, 1, 3))  # A A A A
    row1 = bytes((1, 1, 1, 2)) + bytes(B) + bytes((1, 1, 1, 1))  # A A B B: not 2 << 8 copies
    row2 = bytes(C) + bytes((1, 1, 1, 1)) + bytes(A) + bytes((1, 1, 1, 1))  # C C A A
    image = read_hdr(_write(tmp_path, "s.hdr", HEADER + b"-Y 3 +X 4\n" + row0 + row1 + row2))
    expected = np.array([[_ward(p) for p in row] for row in ([A] * 4, [A, A, B, B], [C, C, A, A])])
    np.testing.assert_array_equal(image, expected.astype(np.float32))


@pytest.mark.parametrize("width", [5, 8, 40000])
def test_flat_scanlines_whose_first_pixel_starts_with_2(tmp_path, width):
    """A scanline is new-style only if it starts 2, 2, h, l with h < 128 and 8 <= width <= 32767:
    (2, 2, 0, 136) is a pixel for width 5 and 40000, and (2, 2, 200, 136) for width 8."""
    first = (2, 2, 200, 136) if width == 8 else (2, 2, 0, 136)
    pixels = [first] + [(i % 256, 7, 9, 137) for i in range(1, width)]
    data = HEADER + f"-Y 2 +X {width}\n".encode() + b"".join(bytes(p) for p in pixels) * 2
    image = read_hdr(_write(tmp_path, "f.hdr", data))
    expected = np.array([_ward(p) for p in pixels], dtype=np.float32)
    np.testing.assert_array_equal(image, np.stack([expected, expected]))


def _reference_decode(data: bytes, pos: int, scanlines: int, length: int) -> list[tuple[int, ...]]:
    """Byte-at-a-time transcription of Radiance color.c freadcolrs / oldreadcolrs (current
    version: repeats stop at the scanline end); the scanline buffer is the whole picture."""
    out: list[tuple[int, ...]] = []
    for _ in range(scanlines):
        if 8 <= length <= 32767 and data[pos] == 2 and data[pos + 1] == 2 and not data[pos + 2] & 128:
            assert data[pos + 2] << 8 | data[pos + 3] == length
            pos += 4
            planes = [[0] * length for _ in range(4)]
            for c in range(4):
                j = 0
                while j < length:
                    code = data[pos]
                    pos += 1
                    if code > 128:
                        for _ in range(code & 127):
                            planes[c][j] = data[pos]
                            j += 1
                        pos += 1
                    else:
                        for _ in range(code):
                            planes[c][j] = data[pos]
                            pos += 1
                            j += 1
            out.extend(zip(*planes, strict=True))
            continue
        rshift, n = 0, 0
        while n < length:
            pixel = tuple(data[pos : pos + 4])
            pos += 4
            if pixel[:3] == (1, 1, 1):
                count, full = pixel[3] << rshift, False
                while count > 0:
                    out.append(out[-1])
                    n, count = n + 1, count - 1
                    if n >= length:
                        full = True
                        break
                if full:
                    break
                rshift += 8
            else:
                out.append(pixel)
                n, rshift = n + 1, 0
    return out


def _random_scanline(rng: np.random.Generator, length: int, first: bool) -> bytes:
    """A new-style, flat or old-style (repeats, consecutive repeats, clipping, leading repeat)
    scanline of random pixels."""

    def pixel(at_start: bool) -> tuple[int, ...]:
        while True:
            p = tuple(int(v) for v in rng.integers(0, 256, 4))
            if p[:3] != (1, 1, 1) and not (at_start and p[0] == 2 and p[1] == 2 and p[2] < 128):
                return p

    kind = rng.choice(["new", "flat", "old"]) if 8 <= length <= 32767 else rng.choice(["flat", "old"])
    if kind == "new":
        pixels = [pixel(False) for _ in range(length)]
        out = bytearray((2, 2, length >> 8, length & 255))
        for c in range(4):
            j = 0
            while j < length:
                take = int(rng.integers(1, min(127, length - j) + 1))
                if rng.random() < 0.5:
                    out += bytes((128 + take, pixels[j][c]))
                else:
                    out += bytes((take,)) + bytes(p[c] for p in pixels[j : j + take])
                j += take
        return bytes(out)
    if kind == "flat":
        return b"".join(bytes(pixel(i == 0)) for i in range(length))
    out, n, rshift = bytearray(), 0, 0
    while n < length:
        if (n > 0 or not first) and rng.random() < 0.4:  # a repeat pixel
            e = int(rng.choice([0, 1, 2, 3, 255])) if rng.random() < 0.7 else int(rng.integers(0, 256))
            e = e if rshift < 24 else 0
            out += bytes((1, 1, 1, e))
            count = e << rshift
            if n + count >= length and count:
                break
            n, rshift = n + count, rshift + 8
        else:
            out += bytes(pixel(n == 0))
            n, rshift = n + 1, 0
    return bytes(out)


def test_random_mixed_scanlines_match_radiance_transcription(tmp_path):
    """Seeded: random widths and scanline kinds against the byte-at-a-time transcription."""
    rng = np.random.default_rng(7)
    path = tmp_path / "m.hdr"
    for trial in range(150):
        length = int(rng.choice([1, 2, 5, 7, 8, 9, 13, 40, 130, 300]))
        scanlines = int(rng.integers(1, 7))
        body = b"".join(_random_scanline(rng, length, i == 0) for i in range(scanlines))
        head = HEADER + f"-Y {scanlines} +X {length}\n".encode()
        path.write_bytes(head + body)
        expected = np.array([_ward(p) for p in _reference_decode(head + body, len(head), scanlines, length)])
        image = read_hdr(path)
        np.testing.assert_array_equal(image.reshape(-1, 3), expected.astype(np.float32), err_msg=f"trial {trial}")


def test_repeat_before_any_pixel_is_refused(tmp_path):
    data = HEADER + b"-Y 1 +X 3\n" + bytes((1, 1, 1, 2)) + bytes(A)
    with pytest.raises(BadInputError, match="repeat before the first pixel"):
        read_hdr(_write(tmp_path, "r.hdr", data))


# ---------------------------------------------------------------------------------------------- XYZE
def _radiance_xyz2rgb() -> np.ndarray:
    """spec_rgb.c xyz2rgbmat, transcribed, with color.h's default primaries and EE white."""
    xr, yr, xg, yg, xb, yb, xw, yw = 0.640, 0.330, 0.290, 0.600, 0.150, 0.060, 1 / 3, 1 / 3
    c_r = (1 / yw) * (xw * (yg - yb) - yw * (xg - xb) + xg * yb - xb * yg)
    c_g = (1 / yw) * (xw * (yb - yr) - yw * (xb - xr) - xr * yb + xb * yr)
    c_b = (1 / yw) * (xw * (yr - yg) - yw * (xr - xg) + xr * yg - xg * yr)
    return np.array(
        [
            [(yg - yb - xb * yg + yb * xg) / c_r, (xb - xg - xb * yg + xg * yb) / c_r, (xg * yb - xb * yg) / c_r],
            [(yb - yr - yb * xr + yr * xb) / c_g, (xr - xb - xr * yb + xb * yr) / c_g, (xb * yr - xr * yb) / c_g],
            [(yr - yg - yr * xg + yg * xr) / c_b, (xg - xr - xg * yr + xr * yg) / c_b, (xr * yg - xg * yr) / c_b],
        ]
    )


def _radiance_clipgamut(col: np.ndarray) -> np.ndarray:
    """spec_rgb.c clipgamut(col, bright(col), CGAMUT_LOWER, cblack, cwhite), transcribed."""
    xr, yr, xg, yg, xb, yb, xw, yw = 0.640, 0.330, 0.290, 0.600, 0.150, 0.060, 1 / 3, 1 / 3
    d = xr * (yg - yb) + xg * (yb - yr) + xb * (yr - yg)
    c_r = (1 / yw) * (xw * (yg - yb) - yw * (xg - xb) + xg * yb - xb * yg)
    c_g = (1 / yw) * (xw * (yb - yr) - yw * (xb - xr) - xr * yb + xb * yr)
    c_b = (1 / yw) * (xw * (yr - yg) - yw * (xr - xg) + xr * yg - xg * yr)
    brt = yr * c_r / d * col[0] + yg * c_g / d * col[1] + yb * c_b / d * col[2]  # color.h bright()
    if brt < 0:
        return np.zeros(3)
    grey = np.full(3, brt)
    vv = 1.0
    for i in range(3):
        if col[i] < 0:
            vv = min(vv, (0 - grey[i]) / (col[i] - grey[i]))
    return vv * col + (1 - vv) * grey


def test_xyze_pixels_convert_like_ra_xyze(tmp_path):
    """ra_xyze -r: RGB = xyz2rgbmat · XYZ, EXPOSURE × 179 (WHTEFFICACY), clipgamut; EE white -> grey."""
    pixels = [(128, 128, 128, 129), (96, 128, 112, 129), (32, 128, 32, 129)]  # XYZ (1,1,1), (.75,1,.875), (.25,1,.25)
    xyz = np.array([_ward(p) for p in pixels])
    data = b"#?RADIANCE\nFORMAT=32-bit_rle_xyze\nEXPOSURE=0.5\n\n-Y 1 +X 3\n" + b"".join(bytes(p) for p in pixels)
    image = read_hdr(_write(tmp_path, "xyz.hdr", data))
    rgb = xyz @ _radiance_xyz2rgb().T / (0.5 * 179.0)
    assert rgb[2, 0] < 0  # saturated green: outside the RGB gamut before clipping
    expected = np.array([rgb[0], rgb[1], _radiance_clipgamut(rgb[2])])
    np.testing.assert_allclose(image[0], expected, rtol=2e-6, atol=1e-9)
    np.testing.assert_allclose(image[0, 0], np.full(3, 1 / (0.5 * 179.0)), rtol=1e-6)
    assert image[0, 2].min() == 0.0


# ------------------------------------------------------------------------------------------ orientation
ORIENTATIONS = ["-Y {h} +X {w}", "-Y {h} -X {w}", "+Y {h} +X {w}", "+Y {h} -X {w}",
                "+X {w} -Y {h}", "+X {w} +Y {h}", "-X {w} -Y {h}", "-X {w} +Y {h}"]  # fmt: skip


def _oriented_file(resolution: str, width: int, height: int, rle: bool) -> bytes:
    """Pixel (x, y) (y up, image.c pix2loc) holds mantissas (10 + x, 20 + y, 0) at e = 136."""
    y_major = resolution.index("Y") < resolution.index("X")
    x_decr, y_decr = resolution[resolution.index("X") - 1] == "-", resolution[resolution.index("Y") - 1] == "-"
    scanlines, length = (height, width) if y_major else (width, height)
    body = b""
    for py in range(scanlines):
        line = []
        for px in range(length):
            x, y = (px, py) if y_major else (py, px)
            x = width - 1 - x if x_decr else x
            y = height - 1 - y if y_decr else y
            line.append((10 + x, 20 + y, 0, 136))
        body += _rle_scanline(line) if rle else b"".join(bytes(p) for p in line)
    return HEADER + resolution.format(w=width, h=height).encode() + b"\n" + body


@pytest.mark.parametrize("resolution", ORIENTATIONS)
@pytest.mark.parametrize(("width", "height", "rle"), [(3, 2, False), (9, 8, True)])
def test_all_eight_orientations(tmp_path, resolution, width, height, rle):
    """resolu.h: the first axis is the slow one; '-' = decreasing; y grows upward (row 0 = top)."""
    image = read_hdr(_write(tmp_path, "o.hdr", _oriented_file(resolution, width, height, rle)))
    assert image.shape == (height, width, 3)
    row, col = np.mgrid[0:height, 0:width]
    np.testing.assert_array_equal(image[..., 0], 10 + col)
    np.testing.assert_array_equal(image[..., 1], 20 + (height - 1 - row))


# ------------------------------------------------------------------------------------------- headers
@pytest.mark.parametrize("eol", [b"\n", b"\r\n"])
@pytest.mark.parametrize("blank", [b"\n", b"\r\n"])
def test_header_line_ends_and_scalings(tmp_path, eol, blank):
    """header.c getheader: the header ends at the first line that is empty or '\\r'. EXPOSURE
    lines multiply; COLORCORR divides per channel (pvalue -o); PIXASPECT changes nothing."""
    lines = [b"#?RADIANCE", b"# made elsewhere", b"FORMAT=32-bit_rle_rgbe", b"EXPOSURE=          2.0",
             b"EXPOSURE=0.25", b"COLORCORR= 1 2 4", b"PIXASPECT=0.5", b"SOFTWARE=x"]  # fmt: skip
    pixels = [(128, 64, 32, 129)] * 9  # (1, .5, .25)
    data = eol.join(lines) + eol + blank + b"-Y 1 +X 9" + eol + _rle_scanline(pixels)
    image = read_hdr(_write(tmp_path, "h.hdr", data))
    np.testing.assert_array_equal(image[0], np.broadcast_to([1 / 0.5, 0.5 / 1.0, 0.25 / 2.0], (9, 3)))


def test_primaries(tmp_path):
    """PRIMARIES (ra_xyze -r): standard primaries as Radiance prints them and Photoshop's
    all-zero line change nothing; XYZ primaries give xyz2rgbmat · pixel; a grey pixel of
    sRGB/D65 primaries stays grey (von Kries white adaptation)."""
    pixels = b"".join(bytes(p) for p in [(128, 64, 32, 129), (96, 128, 112, 129), (64, 64, 64, 130)])

    def read(primaries: bytes) -> np.ndarray:
        data = b"#?RADIANCE\n" + (primaries + b"\n" if primaries else b"") + b"\n-Y 1 +X 3\n" + pixels
        return read_hdr(_write(tmp_path, "p.hdr", data))[0]

    plain = read(b"")
    np.testing.assert_array_equal(read(b"PRIMARIES=0.6400 0.3300 0.2900 0.6000 0.1500 0.0600 0.3333 0.3333"), plain)
    np.testing.assert_array_equal(read(b"PRIMARIES=0 0 0 0 0 0 0 0"), plain)
    xyz_like = read(b"PRIMARIES=1 0 0 1 0 0 0.333333333 0.333333333")
    rgb = np.array([_ward(p) for p in [(128, 64, 32, 129), (96, 128, 112, 129)]]) @ _radiance_xyz2rgb().T
    assert rgb[0, 1] < 0  # (1, .5, .25) as XYZ lies outside the RGB gamut: clipgamut
    np.testing.assert_allclose(xyz_like[:2], [_radiance_clipgamut(rgb[0]), rgb[1]], rtol=1e-5, atol=1e-7)
    srgb = read(b"PRIMARIES=0.64 0.33 0.30 0.60 0.15 0.06 0.3127 0.3290")
    np.testing.assert_allclose(srgb[2], [1.0, 1.0, 1.0], rtol=1e-6)  # (64, 64, 64, 130) = grey 1
    assert not np.allclose(srgb[0], plain[0], rtol=1e-3)  # a coloured pixel does change


@pytest.mark.parametrize(
    ("header", "message"),
    [
        (b"#?RADIANCE\nEXPOSURE=abc\n\n-Y 1 +X 1\n", "bad EXPOSURE"),
        (b"#?RADIANCE\nEXPOSURE=0\n\n-Y 1 +X 1\n", "EXPOSURE product"),
        (b"#?RADIANCE\nCOLORCORR=1 1\n\n-Y 1 +X 1\n", "bad COLORCORR"),
        (b"#?RADIANCE\nCOLORCORR=1 -1 1\n\n-Y 1 +X 1\n", "COLORCORR product"),
        (b"#?RADIANCE\nEXPOSURE=1e-40\n\n-Y 1 +X 1\n", "overflow"),
        (b"#?RADIANCE\n\n-Y 1 +Y 1\n", "resolution"),
        (b"#?RADIANCE\n\n-Y 99999999999999 +X 1\n", "resolution"),
        (b"#?RADIANCE\n\n-Y 1 +X 1", "no resolution line"),
    ],
)
def test_bad_headers(tmp_path, header, message):
    with pytest.raises(BadInputError, match=message):
        read_hdr(_write(tmp_path, "b.hdr", header + bytes((255, 255, 255, 255))))


# -------------------------------------------------------------------------------------------- limits
def test_pixel_limit_from_environment(tmp_path, monkeypatch):
    data = HEADER + b"-Y 64 +X 64\n" + bytes(A) * 4096
    pfm = b"PF\n64 64\n-1\n" + bytes(64 * 64 * 12)
    assert read_hdr(_write(tmp_path, "ok.hdr", data)).shape == (64, 64, 3)
    monkeypatch.setenv("SHRM_MAX_PIXELS", "4000")
    with pytest.raises(BadInputError, match="4,096 pixels exceeds the 4,000-pixel limit"):
        read_hdr(tmp_path / "ok.hdr")
    with pytest.raises(BadInputError, match="exceeds the 4,000-pixel limit"):
        read_pfm(_write(tmp_path, "ok.pfm", pfm))


@pytest.mark.parametrize("start", [b"", bytes((2, 2, 117, 48)), bytes(A)])
def test_declared_size_beyond_the_bytes_is_refused_before_allocating(tmp_path, monkeypatch, start):
    """-Y 30000 +X 30000 (9·10⁸ pixels, within a raised limit) in a few bytes: every scanline
    needs >= 8 bytes (old-style: a pixel and a repeat), so this is truncated, said with numbers."""
    path = _write(tmp_path, "big.hdr", HEADER + b"-Y 30000 +X 30000\n" + start + bytes(64))
    monkeypatch.setenv("SHRM_MAX_PIXELS", str(10**9))
    tracemalloc.start()
    try:
        with pytest.raises(BadInputError, match=r"truncated RGBE data: \d+ bytes .* 30,000 scanlines .* 240,000"):
            read_hdr(path)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 2**20


def test_rle_bomb_decodes_in_proportion(tmp_path):
    """The densest new-style encoding (runs of 127: 2 bytes per 127 pixels and component):
    128 scanlines × 32767 pixels from 266 kB. Memory stays a small multiple of the output."""
    width, height = 32767, 128
    component = bytes((128 + 127, 140)) * 258 + bytes((128 + 1, 140))
    line = bytes((2, 2, width >> 8, width & 255)) + component * 4
    path = _write(tmp_path, "bomb.hdr", HEADER + f"-Y {height} +X {width}\n".encode() + line * height)
    start = time.perf_counter()
    tracemalloc.start()
    try:
        image = read_hdr(path)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    elapsed = time.perf_counter() - start
    out_bytes = image.nbytes  # 12 bytes per pixel
    assert np.all(image == np.float32(140 * 2.0**4))
    assert peak < out_bytes * 4 / 3 + 40 * 2**20, (peak, out_bytes)  # float result + RGBE bytes + blocks
    assert elapsed < 20  # seconds, generous for a shared machine (about 0.3 s alone)


def test_truncated_rle_scanline(tmp_path):
    """A new-style scanline cut short is refused as truncated, naming the scanline."""
    line = _rle_scanline([A] * 1000)
    path = _write(tmp_path, "cut.hdr", HEADER + b"-Y 3 +X 1000\n" + line * 2 + line[:2000])
    with pytest.raises(BadInputError, match="truncated run-length encoded RGBE data at scanline 2 of 3"):
        read_hdr(path)


# ----------------------------------------------------------------------------------------------- PFM
def test_pfm_byte_orders_and_non_finite_values(tmp_path):
    """Negative scale: little-endian; positive: big-endian (any magnitude); NaN/Inf come back."""
    values = np.array([[1.5, -2.0, np.nan], [np.inf, 0.25, -np.inf]], dtype=np.float64)  # bottom row first
    for scale, order in ((b"-1.0", "<f4"), (b"-7.5e-1", "<f4"), (b"1", ">f4"), (b"+2.", ">f4")):
        data = b"Pf\n3  2\n" + scale + b"\n" + values.astype(order).tobytes() + b"trailing bytes"
        image = read_pfm(_write(tmp_path, "g.pfm", data))
        np.testing.assert_array_equal(image[..., 1], values[::-1].astype(np.float32))
        assert image.shape == (2, 3, 3) and image.dtype == np.float32


def test_pfm_header_ended_by_crlf(tmp_path):
    """Windows writers end the header lines with CR LF; the data then fill the file exactly."""
    values = np.arange(6, dtype="<f4")
    image = read_pfm(_write(tmp_path, "w.pfm", b"PF\r\n1 2\r\n-1.0\r\n" + values.tobytes()))
    np.testing.assert_array_equal(image, values.reshape(2, 1, 3)[::-1])


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (b"PF\n1000000 1000000\n-1\n", "pixel limit"),  # 20 bytes declaring 10^12 pixels
        (b"PF\n99999999999999999999 1\n-1\n" + bytes(12), "pixel limit"),
        (b"PF\n" + b"9" * 40 + b" 1\n-1\n", "bad PFM header values"),
        (b"PF\nabc 2\n-1\n" + bytes(48), "bad PFM header values"),
        (b"PF\n1_0 2\n-1\n" + bytes(240), "bad PFM header values"),
        (b"PF\n-2 2\n-1\n" + bytes(48), "bad PFM header values"),
        (b"PF\n2 2\nnan\n" + bytes(48), "bad PFM header values"),
        (b"PF\n2 2\n1e999\n" + bytes(48), "scale"),
        (b"PF\n2 2\n-0.0\n" + bytes(48), "scale"),
        (b"PF\n2 2\n-1", "truncated PFM header"),
        (b"PF2 2 -1\n" + bytes(48), "not a PFM"),
        (b"Pf\n2 2\n-1\n" + bytes(15), "truncated PFM data"),
    ],
)
def test_bad_pfm(tmp_path, content, message):
    start = time.perf_counter()
    with pytest.raises(BadInputError, match=message):
        read_pfm(_write(tmp_path, "bad.pfm", content))
    assert time.perf_counter() - start < 1


# ------------------------------------------------------------------------------------- special files


def test_fifo_and_device_are_refused_at_once(tmp_path, finishes):
    """limits.read_bytes: only regular files; a FIFO would block, /dev/zero never ends."""
    fifo = tmp_path / "x.hdr"
    os.mkfifo(fifo)
    zero = tmp_path / "x.pfm"
    zero.symlink_to("/dev/zero")
    for path, reader, message in ((fifo, read_hdr, "FIFO"), (zero, read_pfm, "device")):
        finished, error = finishes(lambda p=path, r=reader: r(p))
        if not finished:  # unblock the reader before failing
            with open(path, "wb"):
                pass
        assert finished, f"{path.name} blocked"
        assert isinstance(error, BadInputError) and message in str(error), error


# ---------------------------------------------------------------------------------------------- fuzz
@contextmanager
def _time_limit(seconds: float):
    def alarm(_signum, _frame):
        raise TimeoutError

    previous = signal.signal(signal.SIGALRM, alarm)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


def _seed_files() -> list[tuple[str, bytes]]:
    pixels = [(i * 25 % 256, 128, 255 - i * 20, 129 + i % 3) for i in range(9)]
    rle = HEADER + b"-Y 3 +X 9\n" + b"".join(_rle_scanline(pixels[i:] + pixels[:i]) for i in range(3))
    old = HEADER + b"+X 4 -Y 3\n" + bytes(A) + bytes((1, 1, 1, 2)) + bytes(B) + bytes((1, 1, 1, 0)) + bytes(C) * 8
    xyz = b"#?RADIANCE\r\nFORMAT=32-bit_rle_xyze\r\nEXPOSURE=2\r\n\r\n-Y 2 -X 2\r\n" + bytes(B) * 4
    prims = b"#?RADIANCE\nPRIMARIES=0.64 0.33 0.3 0.6 0.15 0.06 0.3127 0.329\nCOLORCORR=1 2 3\n\n-Y 1 +X 3\n"
    prims += bytes(C) * 3
    pf = b"PF\n2 3\n-1.0\n" + np.arange(18, dtype="<f4").tobytes()
    grey = b"Pf\n3 1\n1\n" + np.arange(3, dtype=">f4").tobytes()
    return [("rle.hdr", rle), ("old.hdr", old), ("xyz.hdr", xyz), ("prims.hdr", prims), ("a.pfm", pf), ("g.pfm", grey)]


def _mutants(data: bytes, rng: np.random.Generator) -> list[bytes]:
    out = [data[:n] for n in range(len(data))]  # every truncation
    for _ in range(300):  # random byte changes
        mutant = bytearray(data)
        for pos in rng.integers(0, len(data), rng.integers(1, 4)):
            mutant[pos] = int(rng.integers(0, 256))
        out.append(bytes(mutant))
    header_end = data.find(b"\n", data.find(b"X") if data.startswith(b"#?") else 7) + 1
    head = data[:header_end]
    for token in (b"0", b"-1", b"1", b"65535", b"99999999999", b"2147483648", b"1e300", b"1e-300", b"x", b""):
        for number in set(re.findall(rb"\d+(?:\.\d+)?", head)):
            out.append(head.replace(number, token, 1) + data[header_end:])
    return out


def test_mutation_fuzz_raises_only_bad_input(tmp_path, monkeypatch):
    """Seeded: truncations, byte changes and header numbers set to 0/-1/huge. Every call ends
    within its time limit with a finite (H, W, 3) float32 image (.hdr; PFM may hold NaN as
    stored) or a BadInputError."""
    monkeypatch.setenv("SHRM_MAX_PIXELS", str(2**22))
    rng = np.random.default_rng(20240531)
    calls = 0
    for name, data in _seed_files():
        reader = read_pfm if name.endswith(".pfm") else read_hdr
        path = tmp_path / name
        handle = os.open(path, os.O_RDWR | os.O_CREAT)  # rewritten in place: fast on every file system
        try:
            for mutant in _mutants(data, rng):
                os.ftruncate(handle, len(mutant))
                os.pwrite(handle, mutant, 0)
                calls += 1
                try:
                    with _time_limit(2.0):
                        image = reader(path)
                except BadInputError:
                    continue
                assert image.dtype == np.float32 and image.ndim == 3 and image.shape[2] == 3, (name, mutant)
                if reader is read_hdr:
                    assert np.all(np.isfinite(image)), (name, mutant)
        finally:
            os.close(handle)
    assert calls > 1000
