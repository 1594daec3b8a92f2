"""HDR image codecs: byte-level RGBE references, round trips, real files, bad input."""

from __future__ import annotations

import numpy as np
import pytest

from shrmkit.brdf_io.errors import BadInputError
from shrmkit.brdf_io.hdr_codecs import (
    read_exr,
    read_hdr,
    read_image,
    read_pfm,
    write_exr,
    write_hdr,
    write_image,
    write_pfm,
)

HEADER = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n"


def _reference_rle_decode(data: bytes, height: int, width: int, pos: int) -> np.ndarray:
    """Slow, literal transcription of the Radiance new-style RLE reader (one byte at a time)."""
    out = np.zeros((height, width, 4), dtype=np.uint8)
    for y in range(height):
        assert data[pos] == 2 and data[pos + 1] == 2
        pos += 4
        for c in range(4):
            x = 0
            while x < width:
                count = data[pos]
                pos += 1
                if count > 128:
                    value = data[pos]
                    pos += 1
                    for _ in range(count - 128):
                        out[y, x, c] = value
                        x += 1
                else:
                    for _ in range(count):
                        out[y, x, c] = data[pos]
                        pos += 1
                        x += 1
    return out


def _ward_decode(rgbe: np.ndarray) -> np.ndarray:
    """Ward's rgbe2float (Graphics Gems II): f = ldexp(1, e - 136); channel = mantissa * f."""
    out = np.zeros(rgbe.shape[:-1] + (3,))
    for idx in np.ndindex(rgbe.shape[:-1]):
        r, g, b, e = (int(v) for v in rgbe[idx])
        if e:
            out[idx] = np.array([r, g, b]) * np.ldexp(1.0, e - 136)
    return out


def test_flat_rgbe_bytes_match_ward(tmp_path):
    """Reference: hand-computed RGBE bytes (1.0 = 128·2^(129-136)); width < 8 is written flat."""
    image = np.array([[[1.0, 0.5, 0.25], [0.0, 0.0, 0.0]], [[3.0, 0.0, 1.5], [1e-3, 2e-3, 4e-3]]], np.float32)
    write_hdr(tmp_path / "a.hdr", image)
    data = (tmp_path / "a.hdr").read_bytes()
    body = data[data.index(b"+X 2\n") + 5 :]
    assert len(body) == 16
    assert body[:4] == bytes((128, 64, 32, 129))
    assert body[4:8] == bytes((0, 0, 0, 0))
    assert body[8:12] == bytes((192, 0, 96, 130))  # 3.0 = 0.75·2^2 -> 192·2^(130-136)
    back = read_hdr(tmp_path / "a.hdr")
    assert np.all(np.abs(back - image) <= image.max(axis=-1, keepdims=True) * 2**-8)


def test_hand_made_rle_file(tmp_path):
    """Reference: an RLE scanline written byte by byte (a run chunk and a literal chunk per component)."""
    width = 10
    line = bytes((2, 2, 0, width))
    line += bytes((128 + 10, 128))  # R: run of 10 × 128
    line += bytes((10,)) + bytes(range(10, 20))  # G: 10 literals
    line += bytes((128 + 4, 0, 6, 1, 2, 3, 4, 5, 6))  # B: run of 4 zeros + 6 literals
    line += bytes((128 + 10, 130))  # E: run of 10 × 130
    (tmp_path / "h.hdr").write_bytes(HEADER + f"-Y 1 +X {width}\n".encode() + line)
    image = read_hdr(tmp_path / "h.hdr")
    scale = 2.0 ** (130 - 136)
    assert np.allclose(image[0, :, 0], 128 * scale)
    assert np.allclose(image[0, :, 1], np.arange(10, 20) * scale)
    assert np.allclose(image[0, :, 2], np.array([0, 0, 0, 0, 1, 2, 3, 4, 5, 6]) * scale)


def test_real_rle_file_matches_slow_decoder(shared_data):
    """Reference: byte-at-a-time RLE decoding + Ward's rgbe2float on ict_small/grace.hdr."""
    path = shared_data / "env" / "ict_small" / "grace.hdr"
    data = path.read_bytes()
    pos = data.index(b"-Y 128 +X 256\n") + len(b"-Y 128 +X 256\n")
    expected = _ward_decode(_reference_rle_decode(data, 128, 256, pos)[::8, ::8])
    image = read_hdr(path)
    assert image.shape == (128, 256, 3)
    assert np.array_equal(image[::8, ::8], expected.astype(np.float32))
    assert image.max() == pytest.approx(3504.0)


@pytest.mark.parametrize("rle", [True, False])
def test_hdr_round_trip_within_rgbe_precision(tmp_path, rle):
    """Reference: RGBE keeps 8 mantissa bits of the largest channel (error <= 2^-8 of it)."""
    rng = np.random.default_rng(1)
    image = (rng.lognormal(0.0, 3.0, (16, 40, 3)) * (rng.random((16, 40, 1)) > 0.1)).astype(np.float32)
    image[3, 5:25] = 7.25  # long runs exercise run chunks
    write_hdr(tmp_path / "r.hdr", image, rle=rle)
    back = read_hdr(tmp_path / "r.hdr")
    peak = image.max(axis=-1, keepdims=True)
    assert np.all(np.abs(back - image) <= peak * 2**-8 + 1e-30)
    assert np.array_equal(back[3, 5:25], image[3, 5:25])


def test_pfm_and_exr_round_trips_exact(tmp_path):
    """Reference: the input array itself (float32 storage is lossless for float32 data)."""
    rng = np.random.default_rng(2)
    image = rng.lognormal(0.0, 2.0, (7, 14, 3)).astype(np.float32)
    write_pfm(tmp_path / "a.pfm", image)
    assert np.array_equal(read_pfm(tmp_path / "a.pfm"), image)
    write_exr(tmp_path / "a.exr", image)
    assert np.array_equal(read_exr(tmp_path / "a.exr"), image)
    write_exr(tmp_path / "h.exr", image, half=True)
    assert np.array_equal(read_exr(tmp_path / "h.exr"), image.astype(np.float16).astype(np.float32))


def test_pfm_layout_bottom_row_first(tmp_path):
    """Reference: PFM spec: little-endian for a negative scale, rows stored bottom to top."""
    image = np.arange(2 * 3 * 3, dtype=np.float32).reshape(2, 3, 3)
    write_pfm(tmp_path / "a.pfm", image)
    data = (tmp_path / "a.pfm").read_bytes()
    assert data.startswith(b"PF\n3 2\n-1.0\n")
    stored = np.frombuffer(data[len(b"PF\n3 2\n-1.0\n") :], "<f4").reshape(2, 3, 3)
    assert np.array_equal(stored[0], image[1])
    # a big-endian grey file written by hand
    grey = np.array([[1.0, 2.0], [3.0, 4.0]], ">f4")
    (tmp_path / "g.pfm").write_bytes(b"Pf\n2 2\n1.0\n" + grey.tobytes())
    back = read_pfm(tmp_path / "g.pfm")
    assert np.array_equal(back[..., 1], grey[::-1].astype(np.float32))


def test_real_files(shared_data):
    """Reference: data/README.md (grace_latlong max ≈ 18.4, mean ≈ 0.016; 1024×512 sizes)."""
    grace = read_image(shared_data / "env" / "grace_latlong.exr")
    assert grace.shape == (512, 1024, 3)
    assert grace.max() == pytest.approx(18.4, rel=0.01)
    assert grace.mean() == pytest.approx(0.016, rel=0.05)
    path = shared_data / "env" / "polyhaven_cc0" / "venice_sunset_1k.hdr"
    venice = read_image(path)
    assert venice.shape == (512, 1024, 3)
    cube_face = read_image(shared_data / "env" / "debevec1999_cubes" / "stpeters" / "px.exr")
    assert cube_face.shape == (256, 256, 3)


# ---------------------------------------------------------------------------------------------- bad input
def _hdr_rle_bytes() -> bytes:
    line = bytes((2, 2, 0, 8)) + bytes((128 + 8, 1)) * 3 + bytes((128 + 8, 129))
    return HEADER + b"-Y 2 +X 8\n" + line * 2


@pytest.mark.parametrize(
    ("name", "content", "message"),
    [
        ("magic.hdr", b"P6\n", "magic"),
        ("noend.hdr", b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n", "truncated Radiance header"),
        ("format.hdr", b"#?RADIANCE\nFORMAT=32-bit_rle_cmyk\n\n-Y 1 +X 1\n\0\0\0\0", "pixel format"),
        ("res.hdr", HEADER + b"+X 2 +X 2\n", "resolution"),  # all 8 [-+]Y/X orders are valid; X twice is not
        ("zero.hdr", HEADER + b"-Y 0 +X 8\n", "zero-size"),
        ("flat.hdr", HEADER + b"-Y 2 +X 2\n" + b"\x80" * 12, "truncated flat"),
        ("rle.hdr", _hdr_rle_bytes()[:-3], "truncated"),
        ("chunk.hdr", HEADER + b"-Y 1 +X 8\n" + bytes((2, 2, 0, 8, 0)), "zero-length chunk"),
        ("over.hdr", HEADER + b"-Y 1 +X 8\n" + bytes((2, 2, 0, 8, 128 + 9, 1)) + b"\0" * 20, "corrupt"),
        ("magic.pfm", b"P6\n2 2\n-1\n" + b"\0" * 48, "not a PFM"),
        ("short.pfm", b"PF\n2 2\n-1\n" + b"\0" * 40, "truncated PFM data"),
        ("zero.pfm", b"PF\n0 2\n-1\n", "zero-size"),
        ("header.pfm", b"PF\n2", "truncated PFM header"),
        ("scale.pfm", b"PF\n1 1\n0\n" + b"\0" * 12, "scale"),
        ("junk.exr", b"this is not an exr file at all" * 10, "OpenEXR"),
        ("x.png", b"\x89PNG", "unknown HDR image type"),
    ],
)
def test_bad_files(tmp_path, name, content, message):
    path = tmp_path / name
    path.write_bytes(content)
    with pytest.raises(BadInputError, match=message) as info:
        read_image(path)
    assert name in str(info.value)


def test_good_rle_fixture_reads(tmp_path):
    """The bytes the truncation case is cut from decode to 1·2^(129-136) everywhere."""
    (tmp_path / "ok.hdr").write_bytes(_hdr_rle_bytes())
    assert np.allclose(read_hdr(tmp_path / "ok.hdr"), 2.0**-7)


def test_truncated_exr(tmp_path, shared_data):
    data = (shared_data / "env" / "debevec1999_cubes" / "rnl" / "px.exr").read_bytes()
    (tmp_path / "cut.exr").write_bytes(data[: len(data) // 2])
    with pytest.raises(BadInputError, match="cut.exr"):
        read_exr(tmp_path / "cut.exr")


def test_missing_file(tmp_path):
    for suffix in (".exr", ".hdr", ".pfm"):
        with pytest.raises(BadInputError, match="no such file"):
            read_image(tmp_path / f"none{suffix}")


def test_writers_are_atomic(tmp_path):
    """A refused write leaves neither the destination nor a temporary file."""
    bad = np.full((4, 8, 3), np.nan, np.float32)
    with pytest.raises(BadInputError, match="non-finite"):
        write_image(tmp_path / "bad.hdr", bad)
    with pytest.raises(BadInputError, match="65504"):
        write_exr(tmp_path / "bad.exr", np.full((2, 4, 3), 1e6, np.float32), half=True)
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(BadInputError, match="does not exist"):
        write_pfm(tmp_path / "nofolder" / "a.pfm", np.zeros((2, 4, 3), np.float32))
    good = np.ones((2, 4, 3), np.float32)
    (tmp_path / "keep.pfm").write_bytes(b"old")
    write_pfm(tmp_path / "keep.pfm", good)
    assert np.array_equal(read_pfm(tmp_path / "keep.pfm"), good)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["keep.pfm"]
