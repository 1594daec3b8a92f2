"""KTX 2.0 cube mip chains (brdf_io/ktx2.py).

References: the Khronos *KTX File Format Specification* 2.0 ("File Structure", "Level Index",
"Mip Level Array", "mipPadding", "Key/Value Data", "KTXorientation") and the *Khronos Data Format
Specification* 1.3 §5 (basic descriptor block), parsed here independently with ``struct`` at the
spec's byte offsets; the DDS file of the same chain (``brdf_io/dds.py``, Microsoft's layout),
whose texels must be the KTX2 file's byte for byte; ``ktx-parse`` 2.0.0 (npm, Don McCurdy's
KTX 2.0 parser and serializer used by three.js and glTF-Transform) reading the file and writing
it back, where ``node`` and the package are installed (``KTX_PARSE_MODULE`` = path of its
``dist/index.mjs``, or ``ktx-parse`` resolvable from the working folder).
"""

from __future__ import annotations

import base64
import json
import math
import os
import shutil
import struct
import subprocess

import numpy as np
import pytest

from shrmkit.brdf_io.dds import write_dds_cube
from shrmkit.brdf_io.errors import BadInputError
from shrmkit.brdf_io.ktx2 import read_ktx2_cube, write_ktx2_cube

#: per format: (VkFormat from the Vulkan spec's VkFormat enum, bytes per channel, numpy channel type)
FORMATS = {"rgba16f": (97, 2, "<f2"), "rgba32f": (109, 4, "<f4"), "rgba8": (37, 1, "u1")}


def _chain(size: int, seed: int = 0, top: float = 4.0) -> list[np.ndarray]:
    rng = np.random.default_rng(seed)
    return [rng.uniform(0, top, (6, max(1, size >> m), max(1, size >> m), 3)) for m in range(size.bit_length())]


def _parse_ktx2(data: bytes) -> dict:
    """An independent reader of a KTX 2.0 file: every offset below is the spec's ("File Structure":
    12-byte identifier, nine UInt32 from byte 12, the index from byte 48, the level index from
    byte 80, 24 bytes a level)."""
    assert data[:12] == bytes([0xAB, 0x4B, 0x54, 0x58, 0x20, 0x32, 0x30, 0xBB, 0x0D, 0x0A, 0x1A, 0x0A])
    names = ("vkFormat", "typeSize", "pixelWidth", "pixelHeight", "pixelDepth", "layerCount", "faceCount",
             "levelCount", "supercompressionScheme")
    h = dict(zip(names, struct.unpack("<9I", data[12:48]), strict=True))
    h.update(zip(("dfdByteOffset", "dfdByteLength", "kvdByteOffset", "kvdByteLength"),
                 struct.unpack("<4I", data[48:64]), strict=True))
    h["sgdByteOffset"], h["sgdByteLength"] = struct.unpack("<2Q", data[64:80])
    h["levels"] = [struct.unpack("<3Q", data[80 + 24 * p : 104 + 24 * p]) for p in range(h["levelCount"])]
    d = data[h["dfdByteOffset"] : h["dfdByteOffset"] + h["dfdByteLength"]]
    first, second = struct.unpack("<2I", d[4:12])
    h["dfd"] = dict(total=struct.unpack("<I", d[:4])[0], vendor=first & 0x1FFFF, type=first >> 17,
                    version=second & 0xFFFF, block_size=second >> 16, model=d[12], primaries=d[13],
                    transfer=d[14], flags=d[15], block_dim=list(d[16:20]), bytes_plane=list(d[20:28]),
                    samples=[])
    for at in range(28, len(d), 16):
        word, position, lower, upper = struct.unpack("<I4sII", d[at : at + 16])
        h["dfd"]["samples"].append(dict(bit_offset=word & 0xFFFF, bit_length=(word >> 16) & 0xFF,
                                        channel=(word >> 24) & 0xF, qualifiers=word >> 28,
                                        position=position, lower=lower, upper=upper))
    kv, at, end = [], h["kvdByteOffset"], h["kvdByteOffset"] + h["kvdByteLength"]
    while at < end:
        n = struct.unpack("<I", data[at : at + 4])[0]
        key, _, value = data[at + 4 : at + 4 + n].partition(b"\0")
        kv.append((key.decode(), value))
        pad = -(at + 4 + n) % 4
        assert data[at + 4 + n : at + 4 + n + pad] == bytes(pad)  # valuePadding: zeros to a multiple of 4
        at += 4 + n + pad
    assert at == end
    h["kv"] = kv
    return h


def _float_bits(x: float) -> int:
    return struct.unpack("<I", struct.pack("<f", x))[0]


@pytest.mark.parametrize("fmt", list(FORMATS))
def test_ktx2_layout_by_the_spec_and_the_dds_texels(tmp_path, fmt):
    """Header, DFD, key/value data, level index (largest first) and mip level array (smallest
    first, each level on a multiple of lcm(texel size, 4), zero padding) as the spec lays them
    out; every face of every level equal, byte for byte, to the same surface of the DDS file of
    the same chain (face-major there, level-major here)."""
    vk, type_size, dtype = FORMATS[fmt]
    texel = 4 * type_size
    chain = _chain(8, seed=1, top=1.0 if fmt == "rgba8" else 4.0)
    data = write_ktx2_cube(tmp_path / "c.ktx2", chain, fmt=fmt).read_bytes()
    h = _parse_ktx2(data)
    assert (h["vkFormat"], h["typeSize"], h["pixelWidth"], h["pixelHeight"]) == (vk, type_size, 8, 8)
    assert (h["pixelDepth"], h["layerCount"], h["faceCount"], h["levelCount"]) == (0, 0, 6, 4)
    assert h["supercompressionScheme"] == 0 and (h["sgdByteOffset"], h["sgdByteLength"]) == (0, 0)
    assert h["dfdByteOffset"] == 80 + 24 * 4 and h["kvdByteOffset"] == h["dfdByteOffset"] + h["dfdByteLength"]
    dfd = h["dfd"]
    assert dfd["total"] == h["dfdByteLength"] == 4 + 24 + 16 * 4
    assert (dfd["vendor"], dfd["type"], dfd["version"], dfd["block_size"]) == (0, 0, 2, 24 + 16 * 4)
    assert (dfd["model"], dfd["primaries"], dfd["transfer"], dfd["flags"]) == (1, 1, 1, 0)  # RGBSDA, BT709, linear
    assert dfd["block_dim"] == [0, 0, 0, 0] and dfd["bytes_plane"] == [texel] + [0] * 7
    is_float = fmt != "rgba8"
    for c, (sample, channel) in enumerate(zip(dfd["samples"], (0, 1, 2, 15), strict=True)):
        assert (sample["bit_offset"], sample["bit_length"], sample["channel"]) == (8 * type_size * c,
                                                                                  8 * type_size - 1, channel)
        assert sample["qualifiers"] == (0b1100 if is_float else 0)  # FLOAT | SIGNED in the high nibble
        assert (sample["lower"], sample["upper"]) == ((_float_bits(-1.0), _float_bits(1.0)) if is_float else (0, 255))
    keys = [k for k, _ in h["kv"]]
    assert keys == sorted(keys) == ["KTXorientation", "KTXwriter"]
    assert dict(h["kv"])["KTXorientation"] == b"rd\0" and dict(h["kv"])["KTXwriter"].startswith(b"shrmkit ")
    align = math.lcm(texel, 4)
    offsets = [off for off, _, _ in h["levels"]]
    assert offsets == sorted(offsets, reverse=True)  # the smallest level lies first in the file
    expected_end = h["kvdByteOffset"] + h["kvdByteLength"]
    for p in reversed(range(4)):
        off, length, unpacked = h["levels"][p]
        s = 8 >> p
        assert length == unpacked == 6 * s * s * texel and off % align == 0
        assert off - expected_end < align and data[expected_end:off] == bytes(off - expected_end)  # mipPadding
        expected_end = off + length
    assert len(data) == expected_end
    dds = write_dds_cube(tmp_path / "c.dds", chain, fmt=fmt).read_bytes()
    at = 148  # the DDS surfaces: face by face, each face's levels largest first
    for face in range(6):
        for p in range(4):
            n = (8 >> p) ** 2 * texel
            off = h["levels"][p][0] + face * n
            assert data[off : off + n] == dds[at : at + n]
            at += n
    decoded = np.frombuffer(data, dtype=dtype, count=8 * 8 * 4, offset=offsets[0]).reshape(8, 8, 4)
    scale = 255.0 if fmt == "rgba8" else 1.0
    assert np.allclose(decoded[..., :3] / scale, chain[0][0], atol=2.5e-3 if fmt != "rgba32f" else 1e-6)
    assert np.all(decoded[..., 3] / scale == 1.0)
    back, name = read_ktx2_cube(tmp_path / "c.ktx2")
    assert name == fmt and [b.shape for b in back] == [c.shape for c in chain]
    assert all(np.allclose(b, c, atol=2.5e-3, rtol=1e-3) for b, c in zip(back, chain, strict=True))


def _ktx_parse() -> list[str]:
    """The node command that imports ktx-parse, or skip."""
    node = shutil.which("node")
    if node is None:
        pytest.skip("node is not installed")
    module = os.environ.get("KTX_PARSE_MODULE", "ktx-parse")
    probe = subprocess.run([node, "--input-type=module", "-e", f"await import({json.dumps(module)})"],
                           capture_output=True, timeout=60)
    if probe.returncode:
        pytest.skip("the npm package ktx-parse is not installed (set KTX_PARSE_MODULE)")
    return [node, "--input-type=module", "-e", f"""
import {{ read, write }} from {json.dumps(module)};
import {{ readFileSync }} from 'fs';
const data = new Uint8Array(readFileSync(process.argv[1]));
const c = read(data);
const again = write(c, {{ keepWriter: true }});
console.log(JSON.stringify({{
  vkFormat: c.vkFormat, typeSize: c.typeSize, size: [c.pixelWidth, c.pixelHeight, c.pixelDepth],
  layers: c.layerCount, faces: c.faceCount, scheme: c.supercompressionScheme, kv: c.keyValue,
  model: c.dataFormatDescriptor[0].colorModel, transfer: c.dataFormatDescriptor[0].transferFunction,
  levels: c.levels.map(l => Buffer.from(l.levelData).toString('base64')),
  identical: again.length === data.length && again.every((b, i) => b === data[i]) }}));
"""]


@pytest.mark.parametrize("fmt", ["rgba16f", "rgba32f"])
def test_ktx_parse_reads_it_and_writes_it_back_identically(tmp_path, fmt):
    """ktx-parse (an outside reader and writer of KTX 2.0) reads the header, DFD, key/value data
    and every level's texels as written, and its serializer, given what it read, writes the same
    bytes (levels smallest first, the same paddings)."""
    command = _ktx_parse()
    chain = _chain(8, seed=2)
    path = write_ktx2_cube(tmp_path / "c.ktx2", chain, fmt=fmt)
    doc = json.loads(subprocess.run([*command, str(path)], capture_output=True, check=True, timeout=60).stdout)
    vk, type_size, dtype = FORMATS[fmt]
    assert (doc["vkFormat"], doc["typeSize"], doc["size"], doc["layers"], doc["faces"], doc["scheme"]) == (
        vk, type_size, [8, 8, 0], 0, 6, 0)
    assert doc["kv"]["KTXorientation"] == "rd" and doc["model"] == 1 and doc["transfer"] == 1
    assert doc["identical"]
    for p, level in enumerate(doc["levels"]):
        s = 8 >> p
        texels = np.frombuffer(base64.b64decode(level), dtype=dtype).reshape(6, s, s, 4).astype(np.float64)
        assert np.allclose(texels[..., :3], chain[p], rtol=1e-3, atol=1e-6) and np.all(texels[..., 3] == 1)


def test_ktx2_refusals(tmp_path):
    """Bad chains are refused before a byte is written; the reader refuses a truncated file, a
    file that is not KTX 2.0 and an orientation other than rd."""
    chain = _chain(4)
    with pytest.raises(BadInputError, match="mip level 1 has shape"):
        write_ktx2_cube(tmp_path / "a.ktx2", [chain[0], chain[0]])
    with pytest.raises(BadInputError, match="float16"):
        write_ktx2_cube(tmp_path / "a.ktx2", [np.full((6, 1, 1, 3), 1e5)])
    with pytest.raises(BadInputError, match="unknown KTX2 format"):
        write_ktx2_cube(tmp_path / "a.ktx2", chain, fmt="bc6h")
    assert not list(tmp_path.iterdir())
    path = write_ktx2_cube(tmp_path / "b.ktx2", chain)
    good = path.read_bytes()
    path.write_bytes(good[:-8])
    with pytest.raises(BadInputError, match="level 0"):
        read_ktx2_cube(path)
    path.write_bytes(b"\xabKTX 11\xbb\r\n\x1a\n" + good[12:])
    with pytest.raises(BadInputError, match="not a KTX 2.0 file"):
        read_ktx2_cube(path)
    path.write_bytes(good.replace(b"KTXorientation\0rd", b"KTXorientation\0ru"))
    with pytest.raises(BadInputError, match="KTXorientation 'ru'"):
        read_ktx2_cube(path)


def test_docstring_example_runs():
    """The Examples section of write_ktx2_cube (a round trip in a temporary folder) passes as a doctest."""
    import doctest

    from shrmkit.brdf_io import ktx2

    result = doctest.testmod(ktx2, optionflags=doctest.NORMALIZE_WHITESPACE, report=False)
    assert result.attempted >= 5 and result.failed == 0
