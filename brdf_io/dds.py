"""DirectDraw Surface (``.dds``) cube maps with mip chains: writer and reader.

Layout (Microsoft, "Programming Guide for DDS": ``DDS_HEADER``, ``DDS_PIXELFORMAT``,
``DDS_HEADER_DXT10``; ``data_specs/export.md`` has the byte table): the magic ``"DDS "``, a
124-byte ``DDS_HEADER`` (flags CAPS | HEIGHT | WIDTH | PITCH | PIXELFORMAT | MIPMAPCOUNT,
caps COMPLEX | TEXTURE | MIPMAP, caps2 CUBEMAP and all six face bits) whose pixel format is
the FourCC ``"DX10"``, then the 20-byte ``DDS_HEADER_DXT10`` (a DXGI format,
``D3D10_RESOURCE_DIMENSION_TEXTURE2D``, ``DDS_RESOURCE_MISC_TEXTURECUBE``, array size 1), then
the surfaces: **face by face** (+X, −X, +Y, −Y, +Z, −Z), each face's mip levels from the
largest down, each level's rows top to bottom, texels RGBA. All little-endian.

Pixel formats (:data:`DDS_FORMATS`): ``rgba16f`` (``DXGI_FORMAT_R16G16B16A16_FLOAT``, 10: the
engines' HDR format), ``rgba32f`` (``R32G32B32A32_FLOAT``, 2) and ``rgba8`` (``R8G8B8A8_UNORM``,
28: values clipped to [0, 1] and rounded; for LDR data). Alpha is written as 1.

Public objects: :data:`DDS_FORMATS`, :func:`write_dds_cube`, :func:`read_dds_cube`, and the helpers
shared with ``brdf_io/ktx2.py``: :func:`check_cube_chain`, :func:`pack_rgba`.

References
----------
Microsoft Docs, "DDS_HEADER structure", "DDS_PIXELFORMAT structure", "DDS_HEADER_DXT10
structure", "Programming Guide for DDS" (cube maps: "each face ... followed by its mipmaps").
"""

from __future__ import annotations

import os
import struct
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from .atomic import atomic_path
from .errors import BadInputError
from .limits import read_bytes, regular_file

__all__ = ["DDS_FORMATS", "check_cube_chain", "pack_rgba", "write_dds_cube", "read_dds_cube"]

#: format name -> (DXGI_FORMAT value, numpy dtype of one channel)
DDS_FORMATS: dict[str, tuple[int, str]] = {"rgba16f": (10, "<f2"), "rgba32f": (2, "<f4"), "rgba8": (28, "u1")}

_MAGIC = b"DDS "
# DDS_HEADER.dwFlags: DDSD_CAPS | DDSD_HEIGHT | DDSD_WIDTH | DDSD_PITCH | DDSD_PIXELFORMAT | DDSD_MIPMAPCOUNT
_FLAGS = 0x1 | 0x2 | 0x4 | 0x8 | 0x1000 | 0x20000
_DDPF_FOURCC = 0x4
# dwCaps: DDSCAPS_COMPLEX | DDSCAPS_TEXTURE | DDSCAPS_MIPMAP
_CAPS = 0x8 | 0x1000 | 0x400000
# dwCaps2: DDSCAPS2_CUBEMAP | POSITIVEX | NEGATIVEX | POSITIVEY | NEGATIVEY | POSITIVEZ | NEGATIVEZ
_CAPS2 = 0x200 | 0x400 | 0x800 | 0x1000 | 0x2000 | 0x4000 | 0x8000
_TEXTURE2D = 3  # D3D10_RESOURCE_DIMENSION_TEXTURE2D
_MISC_TEXTURECUBE = 0x4  # DDS_RESOURCE_MISC_TEXTURECUBE
_HEADER_BYTES = 4 + 124 + 20


def pack_rgba(values: np.ndarray, fmt: str) -> bytes:
    """RGB (…, 3) float → little-endian RGBA bytes of ``fmt`` (a key of :data:`DDS_FORMATS`;
    alpha 1), texels in C order. Shared by the DDS and KTX2 writers (``brdf_io/ktx2.py``)."""
    rgba = np.concatenate([values, np.ones(values.shape[:-1] + (1,))], axis=-1)
    dtype = DDS_FORMATS[fmt][1]
    if fmt == "rgba8":
        return np.rint(np.clip(rgba, 0.0, 1.0) * 255.0).astype(dtype).tobytes()
    return rgba.astype(dtype).tobytes()


def check_cube_chain(path: str | os.PathLike[str] | None, levels: Sequence[np.ndarray], fmt: str,
                     container: str) -> list[np.ndarray]:
    """The mip levels of a cube chain as float64 arrays, checked before a byte is written
    (shared by the DDS and KTX2 writers).

    Raises
    ------
    BadInputError
        ``fmt`` not a key of :data:`DDS_FORMATS`; no level; a level m not (6, S >> m, S >> m, 3)
        (at least 1 texel); NaN or infinite values; for ``rgba16f`` values beyond 65504.
    """
    if fmt not in DDS_FORMATS:
        raise BadInputError(path, f"unknown {container} format {fmt!r}; choose from {', '.join(DDS_FORMATS)}")
    arrays = [np.asarray(level, dtype=np.float64) for level in levels]
    if not arrays:
        raise BadInputError(path, "no mip levels to write")
    size = arrays[0].shape[1] if arrays[0].ndim == 4 else 0
    for m, a in enumerate(arrays):
        want = (6, max(1, size >> m), max(1, size >> m), 3)
        if a.shape != want or size < 1:
            raise BadInputError(path, f"mip level {m} has shape {a.shape}, expected {want}")
        if not np.all(np.isfinite(a)):
            raise BadInputError(path, f"mip level {m} holds NaN or infinite values")
        if fmt == "rgba16f" and np.max(np.abs(a)) > 65504.0:
            raise BadInputError(path, f"mip level {m} exceeds float16's largest value 65504 (use rgba32f)")
    return arrays


def write_dds_cube(path: str | os.PathLike[str], levels: Sequence[np.ndarray], *, fmt: str = "rgba16f") -> Path:
    """Write a cube map with its mip chain as a DX10 ``.dds`` file, atomically.

    Parameters
    ----------
    path
        Output file.
    levels
        Mip levels, largest first: arrays (6, S_m, S_m, 3) of linear RGB, faces in the order
        +X, −X, +Y, −Y, +Z, −Z, rows top to bottom; S_m = max(1, S_0 >> m).
    fmt
        A key of :data:`DDS_FORMATS`.

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
    >>> path = write_dds_cube(pathlib.Path(folder.name) / "tiny.dds", chain)
    >>> path.stat().st_size  # 148 header bytes + 6 faces x (4 + 1 texels) x 8 bytes
    388
    >>> [level[0, 0, 0].tolist() for level in read_dds_cube(path)[0]]
    [[0.5, 0.5, 0.5], [0.25, 0.25, 0.25]]
    >>> folder.cleanup()
    """
    arrays = check_cube_chain(path, levels, fmt, "DDS")
    size = arrays[0].shape[1]
    dxgi, dtype = DDS_FORMATS[fmt]
    texel = 4 * np.dtype(dtype).itemsize
    pixel_format = struct.pack("<II4sIIIII", 32, _DDPF_FOURCC, b"DX10", 0, 0, 0, 0, 0)
    header = struct.pack("<7I", 124, _FLAGS, size, size, size * texel, 0, len(arrays)) + b"\0" * 44
    header += pixel_format + struct.pack("<5I", _CAPS, _CAPS2, 0, 0, 0)
    dx10 = struct.pack("<5I", dxgi, _TEXTURE2D, _MISC_TEXTURECUBE, 1, 0)
    with atomic_path(path) as tmp, tmp.open("wb") as f:
        f.write(_MAGIC + header + dx10)
        for face in range(6):  # face-major: each face followed by its whole mip chain
            for a in arrays:
                f.write(pack_rgba(a[face], fmt))
    return Path(path)


def read_dds_cube(path: str | os.PathLike[str]) -> tuple[list[np.ndarray], str]:
    """Read a cube map written by :func:`write_dds_cube` (uncompressed DX10 RGBA formats of
    :data:`DDS_FORMATS`).

    Returns
    -------
    levels, fmt
        float64 arrays (6, S_m, S_m, 3) largest first (alpha dropped), and the format name.

    Raises
    ------
    BadInputError
        Not a DDS file, not a DX10 cube map, another pixel format, a length other than the
        header implies.
    """
    path = Path(path)
    size = regular_file(path, "DDS file")
    if size < _HEADER_BYTES:
        raise BadInputError(path, f"{size} bytes, shorter than a DX10 DDS header ({_HEADER_BYTES})")
    data = read_bytes(path, "DDS file")
    if data[:4] != _MAGIC or struct.unpack_from("<I", data, 4)[0] != 124:
        raise BadInputError(path, "not a DDS file (magic 'DDS ' and a 124-byte header expected)")
    height, width = struct.unpack_from("<II", data, 12)
    mips = max(1, struct.unpack_from("<I", data, 28)[0])
    fourcc = data[84:88]
    caps2 = struct.unpack_from("<I", data, 112)[0]
    dxgi, _, misc, array_size = struct.unpack_from("<4I", data, 128)
    if fourcc != b"DX10" or not caps2 & 0x200 or not misc & _MISC_TEXTURECUBE or array_size != 1:
        raise BadInputError(path, "not a DX10 cube map (FourCC DX10, CUBEMAP caps, one cube expected)")
    fmt = next((name for name, (code, _) in DDS_FORMATS.items() if code == dxgi), None)
    if fmt is None:
        raise BadInputError(path, f"DXGI format {dxgi}; readable: {', '.join(DDS_FORMATS)}")
    if height != width or height < 1 or mips > 32 or (width >> (mips - 1)) < 1:
        raise BadInputError(path, f"face {width} x {height} with {mips} mip levels is not a square mip chain")
    dtype = np.dtype(DDS_FORMATS[fmt][1])
    counts = [max(1, width >> m) ** 2 * 4 for m in range(mips)]
    expected = _HEADER_BYTES + 6 * sum(counts) * dtype.itemsize
    if len(data) != expected:
        raise BadInputError(path, f"{len(data)} bytes; the header implies {expected}")
    flat = np.frombuffer(data, dtype=dtype, offset=_HEADER_BYTES).astype(np.float64)
    if fmt == "rgba8":
        flat = flat / 255.0
    levels = [np.empty((6, max(1, width >> m), max(1, width >> m), 3)) for m in range(mips)]
    at = 0
    for face in range(6):
        for m, n in enumerate(counts):
            s = max(1, width >> m)
            levels[m][face] = flat[at : at + n].reshape(s, s, 4)[..., :3]
            at += n
    return levels, fmt
