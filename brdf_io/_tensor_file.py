"""Mitsuba 3's ``tensor_file`` container (RGL ``.bsdf``): reader and atomic writer.

The container is a header (magic, version, field count, one entry per field: name, dtype code,
data offset, shape) followed by each field's little-endian C-order data; the reading rules and
the checks of a hostile file are in ``data_specs/rgl_bsdf.md``, "Container". :mod:`.rgl` reads
the RGL material on top of it and re-exports the public names.

Reference: [Mitsuba3] ``src/core/tensor.cpp`` and ``mitsuba/python/tensor_io.py``. Citation keys:
``data_specs/bibliography.md``.
"""

from __future__ import annotations

import os
import struct
from pathlib import Path

import numpy as np

from .atomic import atomic_path
from .errors import BadInputError
from .limits import check_elements, read_bytes

#: Peak bytes per byte of an RGL tensor file while it is read and set up (21 measured on the shared
#: files): the memory plan of data_specs/limits.md.
RGL_PEAK_PER_BYTE = 32

TENSOR_MAGIC = b"tensor_file\x00"
TENSOR_VERSION = (1, 0)
_PREAMBLE = 12 + 2 + 4  # magic, version (2 x u8), field count (u32)
_MIN_ENTRY = 2 + 2 + 1 + 8  # name length, ndim, dtype, offset (an empty name, no shape)

#: dtype code -> numpy dtype (little-endian): Mitsuba's ``Struct::Type`` enumeration
#: (0 = invalid), as written by ``mitsuba/python/tensor_io.py``.
TENSOR_DTYPES: dict[int, np.dtype] = {
    1: np.dtype("u1"),
    2: np.dtype("i1"),
    3: np.dtype("<u2"),
    4: np.dtype("<i2"),
    5: np.dtype("<u4"),
    6: np.dtype("<i4"),
    7: np.dtype("<u8"),
    8: np.dtype("<i8"),
    9: np.dtype("<f2"),
    10: np.dtype("<f4"),
    11: np.dtype("<f8"),
}
_DTYPE_CODES = {dt: code for code, dt in TENSOR_DTYPES.items()}

#: One header entry: field name, dtype, data offset, shape.
_Entry = tuple[str, np.dtype, int, tuple[int, ...]]


def _parse_tensor_file(data: bytes, source: object) -> dict[str, np.ndarray]:
    """Every field of the container bytes ``data`` (``source`` names the file in errors)."""
    n_fields = _check_preamble(data, source)
    entries, header_end = _read_entries(data, source, n_fields)
    return _field_arrays(data, source, entries, header_end)


def _check_preamble(data: bytes, source: object) -> int:
    """The field count of the 18-byte preamble (magic, version, count), checked."""
    size = len(data)
    if size < _PREAMBLE:
        raise BadInputError(
            source, f"{size} bytes, shorter than the 18-byte tensor_file header (magic, version, field count)"
        )
    if data[:12] != TENSOR_MAGIC:
        raise BadInputError(
            source, f"starts with {data[:12]!r}, not the tensor_file magic {TENSOR_MAGIC!r}: not a Mitsuba "
            "tensor file (RGL .bsdf)"
        )
    version = (data[12], data[13])
    if version != TENSOR_VERSION:
        raise BadInputError(source, f"tensor_file version {version[0]}.{version[1]}; only version 1.0 is known")
    (n_fields,) = struct.unpack_from("<I", data, 14)
    if n_fields == 0:
        raise BadInputError(source, "tensor_file declares no fields")
    if n_fields > (size - _PREAMBLE) // _MIN_ENTRY:
        raise BadInputError(
            source, f"tensor_file declares {n_fields:,} fields, more than its {size:,} bytes can hold "
            f"({_MIN_ENTRY} header bytes each at least): truncated or corrupt"
        )
    return int(n_fields)


def _read_entries(data: bytes, source: object, n_fields: int) -> tuple[list[_Entry], int]:
    """The ``n_fields`` header entries after the preamble and the offset where the header ends."""
    size = len(data)

    def need(pos: int, count: int, what: str) -> None:
        if pos + count > size:
            raise BadInputError(
                source, f"truncated header: {what} needs bytes {pos}..{pos + count - 1}, the file has {size}"
            )

    entries: list[_Entry] = []
    seen: set[str] = set()
    pos = _PREAMBLE
    for index in range(n_fields):
        where = f"field {index + 1} of {n_fields}"
        need(pos, 2, f"{where} (name length)")
        (name_length,) = struct.unpack_from("<H", data, pos)
        pos += 2
        need(pos, name_length + 2 + 1 + 8, f"{where} (name, ndim, dtype, offset)")
        try:
            name = data[pos : pos + name_length].decode("utf-8")
        except UnicodeDecodeError:
            raise BadInputError(source, f"{where}: name {data[pos : pos + name_length]!r} is not UTF-8") from None
        pos += name_length
        if not name:
            raise BadInputError(source, f"{where} has an empty name")
        if name in seen:
            raise BadInputError(source, f"field {name!r} appears twice")
        seen.add(name)
        ndim, code, offset = struct.unpack_from("<HBQ", data, pos)
        pos += 11
        if code not in TENSOR_DTYPES:
            known = ", ".join(f"{c} {dt.name}" for c, dt in TENSOR_DTYPES.items())
            raise BadInputError(source, f"field {name!r} has unknown dtype code {code} (known: {known})")
        need(pos, 8 * ndim, f"field {name!r} (shape of {ndim} axes)")
        shape = struct.unpack_from(f"<{ndim}Q", data, pos)
        pos += 8 * ndim
        entries.append((name, TENSOR_DTYPES[code], int(offset), tuple(int(n) for n in shape)))
    return entries, pos


def _field_arrays(data: bytes, source: object, entries: list[_Entry], header_end: int) -> dict[str, np.ndarray]:
    """Read-only views of each entry's data, checked to lie after the header and inside the file."""
    size = len(data)
    fields: dict[str, np.ndarray] = {}
    for name, dtype, offset, shape in entries:
        count = check_elements(source, shape, f"field {name!r}")
        nbytes = count * dtype.itemsize
        if count and offset < header_end:
            raise BadInputError(
                source, f"field {name!r}: data offset {offset} lies inside the header (which ends at byte "
                f"{header_end})"
            )
        if offset + nbytes > size:
            raise BadInputError(
                source, f"field {name!r} ({dtype.name}, shape {shape}, {nbytes:,} bytes at offset {offset:,}) "
                f"extends past the end of the file ({size:,} bytes): truncated?"
            )
        fields[name] = np.frombuffer(data, dtype=dtype, count=count, offset=offset if count else 0).reshape(shape)
    return fields


def read_tensor_file(path: str | os.PathLike[str]) -> dict[str, np.ndarray]:
    """Read every field of a Mitsuba ``tensor_file`` (data_specs/rgl_bsdf.md, "Container").

    Returns
    -------
    dict
        Field name -> read-only array of the stored dtype and shape, in file order.

    Raises
    ------
    BadInputError
        Unreadable or oversized file, wrong magic or version, a header that runs past
        the end of the file, an unknown dtype code, a non-UTF-8, empty or repeated name,
        a shape over the element limit, data that overlaps the header or runs past the
        end of the file.
    """
    path = Path(path)
    # memory plan: the file, its fields and the interpolation tables (21 B per file byte measured)
    return _parse_tensor_file(read_bytes(path, "tensor file", peak_per_byte=RGL_PEAK_PER_BYTE), path)


def write_tensor_file(path: str | os.PathLike[str], fields: dict[str, object], *, align: int = 8) -> Path:
    """Write a Mitsuba ``tensor_file`` atomically: the header, then each field's C-order
    little-endian data at an offset aligned to ``align`` bytes (as Mitsuba's
    ``tensor_io.write`` does). A ``str`` value is stored as a uint8 array of its UTF-8.

    Raises
    ------
    BadInputError
        A dtype with no tensor_file code (e.g. bool, complex, object).
    """
    path = Path(path)
    arrays: dict[str, np.ndarray] = {}
    for name, value in fields.items():
        if isinstance(value, str):
            value = np.frombuffer(value.encode("utf-8"), dtype=np.uint8)
        a = np.asarray(value)
        a = np.ascontiguousarray(a) if a.ndim else a  # ascontiguousarray would make a scalar 1-D
        dtype = a.dtype.newbyteorder("<") if a.dtype.byteorder == ">" else a.dtype
        if dtype not in _DTYPE_CODES:
            raise BadInputError(path, f"field {name!r}: dtype {a.dtype} has no tensor_file code")
        arrays[name] = a.astype(dtype, copy=False)
    header = bytearray(TENSOR_MAGIC + bytes(TENSOR_VERSION) + struct.pack("<I", len(arrays)))
    header_size = len(header) + sum(2 + len(n.encode()) + 2 + 1 + 8 + 8 * a.ndim for n, a in arrays.items())
    offset = header_size
    blobs = []
    for name, a in arrays.items():
        offset = -(-offset // align) * align
        label = name.encode("utf-8")
        header += struct.pack("<H", len(label)) + label
        header += struct.pack("<HBQ", a.ndim, _DTYPE_CODES[a.dtype], offset)
        header += struct.pack(f"<{a.ndim}Q", *a.shape)
        blobs.append((offset, a.tobytes()))
        offset += a.nbytes
    out = bytearray(offset)
    out[: len(header)] = header
    for start, blob in blobs:
        out[start : start + len(blob)] = blob
    with atomic_path(path) as tmp:
        tmp.write_bytes(bytes(out))
    return path
