"""Khronos KTX 2.0 (``.ktx2``) cube maps with mip chains: writer and reader ([KTX2], [KDFS13]).

:func:`write_ktx2_cube` writes a cube map's mip chain in the layout engines load, all little-endian:
the 80-byte header (faceCount 6, no supercompression), the level index (**largest level first**),
one Khronos basic Data Format Descriptor (linear RGBA, as KTX-Software's ``createDFDUnpacked``
writes it), the key/value data sorted by key (``KTXorientation`` = ``"rd"``, ``KTXwriter``), and
the mip level array (**smallest level first**, each level padded to lcm(texel size, 4) bytes; inside
a level the faces +X, −X, +Y, −Y, +Z, −Z, rows top to bottom, texels R, G, B, A).
:func:`read_ktx2_cube` reads such files back. The byte table: ``data_specs/export.md`` §3 ("KTX2
layout").

Pixel formats (:data:`KTX2_FORMATS`, the names of ``brdf_io/dds.py``'s :data:`DDS_FORMATS`):
``rgba16f`` (``VK_FORMAT_R16G16B16A16_SFLOAT``, 97, the engines' HDR format), ``rgba32f``
(``VK_FORMAT_R32G32B32A32_SFLOAT``, 109) and ``rgba8`` (``VK_FORMAT_R8G8B8A8_UNORM``, 37: values
clipped to [0, 1] and rounded; linear, not sRGB). Alpha is written as 1. The texels are
byte-for-byte those of the DDS writer: only the container differs.

References: [KTX2] ("File Structure", "Level Index", "Mip Level Array", "mipPadding", "Key/Value
Data", "KTXorientation", "KTXwriter", appendix "Cubemap Orientation"); [KDFS13] §5 and
KTX-Software's ``lib/dfdutils/createdfd.c`` (sample bounds). Citation keys:
``data_specs/bibliography.md``.
"""

from __future__ import annotations

import math
import os
import struct
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from .._version import __version__
from .atomic import atomic_path
from .dds import DDS_FORMATS, check_cube_chain, pack_rgba
from .errors import BadInputError
from .limits import read_bytes, regular_file

__all__ = ["KTX2_FORMATS", "write_ktx2_cube", "read_ktx2_cube"]

#: format name -> (VkFormat value, typeSize = bytes of one channel)
KTX2_FORMATS: dict[str, tuple[int, int]] = {"rgba16f": (97, 2), "rgba32f": (109, 4), "rgba8": (37, 1)}

_IDENTIFIER = b"\xabKTX 20\xbb\r\n\x1a\n"
_HEADER_BYTES = 12 + 9 * 4 + 4 * 4 + 2 * 8  # identifier, nine UInt32 fields, the index
_LEVEL_BYTES = 3 * 8  # one level index entry: byteOffset, byteLength, uncompressedByteLength
_MODEL_RGBSDA, _PRIMARIES_BT709, _TRANSFER_LINEAR = 1, 1, 1
_DFD_VERSION = 2  # KHR_DF_VERSIONNUMBER_1_3
_CHANNELS = (0, 1, 2, 15)  # RGBSDA channel ids of R, G, B, A, in memory order
_FLOAT_SIGNED = 0x80 | 0x40  # sample qualifiers KHR_DF_SAMPLE_DATATYPE_FLOAT | _SIGNED (high nibble)
_ORIENTATION = "rd"


def _dfd(fmt: str) -> bytes:
    """``dfdTotalSize`` followed by one basic descriptor block for the unpacked RGBA ``fmt``."""
    type_size = KTX2_FORMATS[fmt][1]
    bits = 8 * type_size
    samples = b""
    for c, channel in enumerate(_CHANNELS):
        if fmt == "rgba8":
            qualifiers, lower, upper = 0, 0, 255
        else:  # float samples carry -1.0f and 1.0f as their bounds (Data Format Spec. §5.18)
            qualifiers = _FLOAT_SIGNED
            lower, upper = (struct.unpack("<I", struct.pack("<f", v))[0] for v in (-1.0, 1.0))
        samples += struct.pack("<HBB4BII", c * bits, bits - 1, channel | qualifiers, 0, 0, 0, 0, lower, upper)
    block_size = 24 + len(samples)
    block = struct.pack("<IHH", 0, _DFD_VERSION, block_size)  # vendor Khronos 0, type basic 0
    block += bytes([_MODEL_RGBSDA, _PRIMARIES_BT709, _TRANSFER_LINEAR, 0])  # flags 0: straight alpha
    block += bytes(4)  # texelBlockDimension0..3 = 0: a 1 x 1 x 1 x 1 texel block
    block += bytes([4 * type_size, 0, 0, 0, 0, 0, 0, 0])  # bytesPlane0..7
    return struct.pack("<I", 4 + len(block + samples)) + block + samples


def _key_values(pairs: dict[str, str]) -> bytes:
    """Key/value data: pairs sorted by the keys' code points, each value a NUL-terminated UTF-8
    string, each pair followed by 0–3 zero bytes of ``valuePadding``."""
    out = b""
    for key in sorted(pairs):
        body = key.encode("utf-8") + b"\0" + pairs[key].encode("utf-8") + b"\0"
        out += struct.pack("<I", len(body)) + body + bytes(-len(body) % 4)
    return out


def write_ktx2_cube(path: str | os.PathLike[str], levels: Sequence[np.ndarray], *, fmt: str = "rgba16f") -> Path:
    """Write a cube map with its mip chain as a KTX 2.0 file (no supercompression), atomically.

    Parameters
    ----------
    path
        Output file.
    levels
        Mip levels, largest first: arrays (6, S_m, S_m, 3) of linear RGB, faces in the order
        +X, −X, +Y, −Y, +Z, −Z, rows top to bottom; S_m = max(1, S_0 >> m) (as for
        :func:`~shrmkit.brdf_io.dds.write_dds_cube`).
    fmt
        A key of :data:`KTX2_FORMATS`.

    Raises
    ------
    BadInputError
        Unknown format, wrong shapes, non-finite values, values beyond float16's range
        (65504) for ``rgba16f``.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> import numpy as np
    >>> folder = tempfile.TemporaryDirectory()
    >>> chain = [np.full((6, 2, 2, 3), 0.5), np.full((6, 1, 1, 3), 0.25)]
    >>> path = write_ktx2_cube(pathlib.Path(folder.name) / "tiny.ktx2", chain)
    >>> path.read_bytes()[:12] == b"\\xabKTX 20\\xbb\\r\\n\\x1a\\n"
    True
    >>> [level[0, 0, 0].tolist() for level in read_ktx2_cube(path)[0]]
    [[0.5, 0.5, 0.5], [0.25, 0.25, 0.25]]
    >>> folder.cleanup()
    """
    arrays = check_cube_chain(path, levels, fmt, "KTX2")
    size, n = arrays[0].shape[1], len(arrays)
    vk_format, type_size = KTX2_FORMATS[fmt]
    texel = 4 * type_size
    dfd = _dfd(fmt)
    kvd = _key_values({"KTXorientation": _ORIENTATION, "KTXwriter": f"shrmkit {__version__}"})
    dfd_offset = _HEADER_BYTES + _LEVEL_BYTES * n
    kvd_offset = dfd_offset + len(dfd)
    align = math.lcm(texel, 4)  # mipPadding: each level on a multiple of lcm(texel block size, 4)
    level_bytes = [6 * max(1, size >> m) ** 2 * texel for m in range(n)]
    offsets = [0] * n
    at = kvd_offset + len(kvd)
    for m in reversed(range(n)):  # the Mip Level Array holds the smallest level first
        at += -at % align
        offsets[m] = at
        at += level_bytes[m]
    header = _IDENTIFIER + struct.pack("<9I", vk_format, type_size, size, size, 0, 0, 6, n, 0)
    header += struct.pack("<4I2Q", dfd_offset, len(dfd), kvd_offset, len(kvd), 0, 0)
    index = b"".join(struct.pack("<3Q", offsets[m], level_bytes[m], level_bytes[m]) for m in range(n))
    with atomic_path(path) as tmp, tmp.open("wb") as f:
        f.write(header + index + dfd + kvd)
        written = kvd_offset + len(kvd)
        for m in reversed(range(n)):
            f.write(bytes(offsets[m] - written))
            for face in range(6):  # inside a level: face by face, rows top to bottom
                f.write(pack_rgba(arrays[m][face], fmt))
            written = offsets[m] + level_bytes[m]
    return Path(path)


def read_ktx2_cube(path: str | os.PathLike[str]) -> tuple[list[np.ndarray], str]:
    """Read a KTX 2.0 cube map with uncompressed RGBA texels of :data:`KTX2_FORMATS` (a file of
    :func:`write_ktx2_cube`, or any such file: the level index is followed, not assumed).

    Returns
    -------
    levels, fmt
        float64 arrays (6, S_m, S_m, 3) largest first (alpha dropped), and the format name.

    Raises
    ------
    BadInputError
        Not a KTX 2.0 file; not a complete cube map (faceCount 6, no layers, no depth); another
        vkFormat or a supercompressed file; a DFD that is not linear RGBA of that format; a level
        index whose lengths or offsets disagree with the header or the file; an orientation
        other than ``rd``.
    """
    path = Path(path)
    size = regular_file(path, "KTX2 file")
    if size < _HEADER_BYTES:
        raise BadInputError(path, f"{size} bytes, shorter than a KTX 2.0 header ({_HEADER_BYTES})")
    data = read_bytes(path, "KTX2 file")
    if data[:12] != _IDENTIFIER:
        raise BadInputError(path, "not a KTX 2.0 file (identifier «KTX 20» expected)")
    vk_format, type_size, width, height, depth, layers, faces, n, scheme = struct.unpack_from("<9I", data, 12)
    dfd_offset, dfd_length, kvd_offset, kvd_length, _, sgd_length = struct.unpack_from("<4I2Q", data, 48)
    if faces != 6 or layers != 0 or depth != 0 or height != width or width < 1:
        raise BadInputError(path, f"not a cube map (faceCount {faces}, layerCount {layers}, {width} x {height} "
                            f"x {depth}; 6, 0 and square faces expected)")
    fmt = next((name for name, (code, _) in KTX2_FORMATS.items() if code == vk_format), None)
    if fmt is None or type_size != KTX2_FORMATS[fmt][1]:
        raise BadInputError(path, f"vkFormat {vk_format} (typeSize {type_size}); readable: "
                            + ", ".join(f"{name} ({code})" for name, (code, _) in KTX2_FORMATS.items()))
    if scheme != 0 or sgd_length != 0:
        raise BadInputError(path, f"supercompression scheme {scheme}: only uncompressed files are read")
    if n < 1 or n > 32 or (width >> (n - 1)) < 1:
        raise BadInputError(path, f"levelCount {n} for {width}-texel faces is not a mip chain")
    texel = 4 * type_size
    if dfd_offset != _HEADER_BYTES + _LEVEL_BYTES * n or dfd_offset + dfd_length > len(data):
        raise BadInputError(path, f"DFD at {dfd_offset} (+{dfd_length}) does not follow the level index")
    dfd = data[dfd_offset : dfd_offset + dfd_length]
    if len(dfd) < 28 + 16 * 4 or struct.unpack_from("<I", dfd)[0] != dfd_length:
        raise BadInputError(path, "the data format descriptor is truncated or its size disagrees")
    model, _, transfer, _ = dfd[12:16]
    if model != _MODEL_RGBSDA or transfer != _TRANSFER_LINEAR or dfd[20] != texel:
        raise BadInputError(path, f"DFD colour model {model}, transfer {transfer}, {dfd[20]} bytes a texel: "
                            f"linear RGBA of {texel} bytes expected")
    if kvd_length and (kvd_offset < dfd_offset + dfd_length or kvd_offset + kvd_length > len(data)):
        raise BadInputError(path, f"key/value data at {kvd_offset} (+{kvd_length}) lies outside the file")
    at, end = kvd_offset, kvd_offset + kvd_length
    while kvd_length and at + 4 <= end:
        length = struct.unpack_from("<I", data, at)[0]
        key, _, value = data[at + 4 : at + 4 + length].partition(b"\0")
        if key == b"KTXorientation" and value.rstrip(b"\0") != _ORIENTATION.encode():
            raise BadInputError(path, f"KTXorientation {value.rstrip(bytes(1)).decode(errors='replace')!r}: "
                                "only 'rd' (top-left origin) is read")
        at += 4 + length + (-length % 4)
    dtype = np.dtype(DDS_FORMATS[fmt][1])
    levels = []
    for m in range(n):
        offset, length, unpacked = struct.unpack_from("<3Q", data, _HEADER_BYTES + _LEVEL_BYTES * m)
        s = max(1, width >> m)
        want = 6 * s * s * texel
        if length != want or unpacked != want or offset + length > len(data) or offset % math.lcm(texel, 4):
            raise BadInputError(path, f"level {m}: {length} bytes at {offset}; {want} bytes at a multiple of "
                                f"{math.lcm(texel, 4)} within the file's {len(data)} expected")
        flat = np.frombuffer(data, dtype=dtype, count=want // dtype.itemsize, offset=offset).astype(np.float64)
        if fmt == "rgba8":
            flat = flat / 255.0
        levels.append(flat.reshape(6, s, s, 4)[..., :3].copy())
    return levels, fmt
