"""Reading NumPy ``.npz`` archives without trusting them: every member's declared size is
checked before anything is decompressed or allocated.

A ``.npz`` file is a zip archive of ``.npy`` members (``key.npy``). A few kilobytes of
hostile or broken archive can declare an array of 10⁹ or 2⁴⁰ elements, a string of 10¹⁰
characters, an object (pickle) array, or a member that decompresses a thousand-fold;
``numpy.load`` would try to allocate or decompress all of it. :func:`read_npz` instead

1. accepts only a regular file within the size limit (:func:`~shrmkit.brdf_io.limits.regular_file`),
2. reads the zip directory and refuses encrypted members, compression methods other
   than stored and deflated (the two NumPy writes), a stored member whose sizes differ, a
   deflated member whose declared size exceeds :data:`MAX_DEFLATE_RATIO` times its
   compressed size (deflate cannot expand more than about 1032-fold: the directory lies),
   and a member larger than :func:`max_member_bytes`;
3. reads each wanted member's ``.npy`` header only (format versions 1.0 and 2.0; at most
   :data:`MAX_HEADER_BYTES` bytes) and checks its dtype (the expected kind, never an object,
   structured or sub-array dtype), its shape (:func:`~shrmkit.brdf_io.limits.check_elements`),
   its byte count against the member's declared size (header + data, exactly) and a cap on
   its bytes, and the reader's planned peak memory for it (``peak_bytes_per_element`` ×
   elements, :func:`~shrmkit.brdf_io.limits.check_memory`: a member that inflates a
   thousand-fold within the element limit, 2.35 MB declaring 2²⁸ elements, would need
   8 GB once read and analysed);
4. only then reads the data, in chunks, into an array of the checked size (the zip CRC is
   verified at the end of each member).

Every problem raises :class:`~shrmkit.brdf_io.errors.BadInputError` naming the file. The
rules are documented in ``data_specs/brdf_table.md`` and ``data_specs/shrm_file.md``, whose
readers (:func:`~shrmkit.brdf_io.table.read_table`,
:func:`~shrmkit.analysis.shrm_file.read_shrm_fields`) use this module.
"""

from __future__ import annotations

import io
import os
import struct
import warnings
import zipfile
import zlib
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import IO

import numpy as np

from .errors import BadInputError
from .limits import check_elements, check_memory, max_elements, regular_file

__all__ = ["NpzMember", "read_npz", "max_member_bytes", "MAX_DEFLATE_RATIO", "MAX_HEADER_BYTES"]

#: Largest declared uncompressed/compressed size ratio of a deflated member. Deflate's own
#: maximum is about 1032:1 (a run of identical bytes), so anything above is a lying directory.
MAX_DEFLATE_RATIO = 1100
#: Largest ``.npy`` header read, bytes (NumPy's own default ``max_header_size`` is 10000).
MAX_HEADER_BYTES = 10000
_MAGIC = b"\x93NUMPY"
_CHUNK = 1 << 24  # bytes read per step
# what the zip and deflate layers raise on a corrupt archive (RuntimeError: encrypted;
# NotImplementedError: unknown method; zlib.error: bad deflate stream; BadZipFile: bad CRC)
_CORRUPT = (
    zipfile.BadZipFile, zipfile.LargeZipFile, OSError, EOFError, ValueError, struct.error, zlib.error,
    NotImplementedError, RuntimeError, OverflowError, KeyError, IndexError, MemoryError,
)


def max_member_bytes() -> int:
    """Largest archive member read, bytes: the element limit in float64 plus 64 KiB
    (``8 * SHRM_MAX_ELEMENTS + 65536``; 4 GiB with the default limits)."""
    return 8 * max_elements() + 65536


@dataclass(frozen=True)
class NpzMember:
    """What one member of an archive must be.

    Attributes
    ----------
    kinds
        The accepted ``dtype.kind`` letters (``"f"`` float, ``"fiu"`` any real number,
        ``"U"`` a unicode string).
    expect
        The expectation in words, for the messages (``"float32"``, ``"a JSON string"``).
    ndim
        The required number of dimensions (None: any; the reader checks it).
    itemsize
        The required bytes per element (None: any).
    required
        Whether a missing member is an error.
    max_bytes
        Cap on the member's data bytes (None: :func:`max_member_bytes`).
    peak_bytes_per_element
        The caller's peak memory per element of this member once read and converted
        (bytes; 0: not planned), checked against ``SHRM_MAX_MEMORY_BYTES`` from the
        ``.npy`` header, before the data is inflated.
    """

    kinds: str
    expect: str
    ndim: int | None = None
    itemsize: int | None = None
    required: bool = True
    max_bytes: int | None = None
    peak_bytes_per_element: float = 0.0


def _read_exact(fp: IO[bytes], n: int) -> bytes:
    data = b""
    while len(data) < n:
        chunk = fp.read(n - len(data))
        if not chunk:
            break
        data += chunk
    return data


def _parse_header(path: Path, key: str, fp: IO[bytes]) -> tuple[tuple[int, ...], bool, np.dtype, int]:
    """(shape, fortran_order, dtype, header bytes) of the ``.npy`` member open in ``fp``."""
    magic = _read_exact(fp, 8)
    if len(magic) < 8 or magic[:6] != _MAGIC:
        raise BadInputError(path, f"member {key!r} is not a .npy array (bad magic string)")
    version = (magic[6], magic[7])
    if version not in ((1, 0), (2, 0)):
        raise BadInputError(path, f"member {key!r}: .npy format version {version} is not supported (1.0, 2.0)")
    size_format = "<H" if version == (1, 0) else "<I"
    length_bytes = _read_exact(fp, struct.calcsize(size_format))
    if len(length_bytes) < struct.calcsize(size_format):
        raise BadInputError(path, f"member {key!r}: truncated .npy header")
    (length,) = struct.unpack(size_format, length_bytes)
    if length > MAX_HEADER_BYTES:
        raise BadInputError(path, f"member {key!r}: .npy header of {length:,} bytes (at most {MAX_HEADER_BYTES})")
    header = _read_exact(fp, length)
    if len(header) < length:
        raise BadInputError(path, f"member {key!r}: truncated .npy header")
    reader = np.lib.format.read_array_header_1_0 if version == (1, 0) else np.lib.format.read_array_header_2_0
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # NumPy's Python-2 header fallback warns
            shape, fortran, dtype = reader(io.BytesIO(length_bytes + header), max_header_size=MAX_HEADER_BYTES)
    except Exception as err:  # noqa: BLE001 - any failure to parse hostile header text (ast, tokenize, dtype)
        text = str(err).splitlines()[0][:120] if str(err) else type(err).__name__
        raise BadInputError(path, f"member {key!r}: invalid .npy header ({text})") from None
    return tuple(shape), bool(fortran), dtype, 8 + len(length_bytes) + length


def _check_member(path: Path, key: str, spec: NpzMember, info: zipfile.ZipInfo) -> None:
    """Zip-directory checks of one member, before it is opened."""
    if info.flag_bits & 0x1:
        raise BadInputError(path, f"member {key!r} is encrypted")
    if info.compress_type not in (zipfile.ZIP_STORED, zipfile.ZIP_DEFLATED):
        raise BadInputError(
            path, f"member {key!r} uses zip compression method {info.compress_type} (only stored and deflated)"
        )
    limit = spec.max_bytes if spec.max_bytes is not None else max_member_bytes()
    if info.file_size > limit + MAX_HEADER_BYTES + 64:
        raise BadInputError(
            path, f"member {key!r} declares {info.file_size:,} bytes uncompressed, over the {limit:,}-byte limit "
            "(SHRM_MAX_ELEMENTS)",
        )
    if info.compress_type == zipfile.ZIP_STORED and info.file_size != info.compress_size:
        raise BadInputError(
            path, f"member {key!r} is stored uncompressed but declares {info.file_size:,} bytes in "
            f"{info.compress_size:,}",
        )
    if info.file_size > MAX_DEFLATE_RATIO * info.compress_size + 4096:
        raise BadInputError(
            path, f"member {key!r} declares {info.file_size:,} bytes from {info.compress_size:,} compressed "
            f"(ratio over {MAX_DEFLATE_RATIO}: a zip bomb or a corrupt directory)",
        )


def _read_member(path: Path, key: str, spec: NpzMember, zf: zipfile.ZipFile, info: zipfile.ZipInfo) -> np.ndarray:
    _check_member(path, key, spec, info)
    with zf.open(info) as fp:
        shape, fortran, dtype, header_bytes = _parse_header(path, key, fp)
        described = f"dtype {dtype} and shape {shape}" if dtype.names is None else f"a structured dtype, shape {shape}"
        if (
            dtype.hasobject or dtype.names is not None or dtype.subdtype is not None
            or dtype.kind not in spec.kinds or (spec.itemsize is not None and dtype.itemsize != spec.itemsize)
        ):
            raise BadInputError(path, f"{key} has {described}; expected {spec.expect}")
        if spec.ndim is not None and len(shape) != spec.ndim:
            raise BadInputError(path, f"{key} has {described}; expected {spec.expect} with {spec.ndim} dimension(s)")
        count = check_elements(path, shape, key)
        nbytes = count * dtype.itemsize
        limit = spec.max_bytes if spec.max_bytes is not None else max_member_bytes()
        if nbytes > limit:
            raise BadInputError(path, f"{key} of {described} holds {nbytes:,} bytes, over the {limit:,}-byte limit")
        if spec.peak_bytes_per_element:
            check_memory(path, count * spec.peak_bytes_per_element, f"reading {key} of {described}")
        if header_bytes + nbytes != info.file_size:
            raise BadInputError(
                path, f"{key} declares {described} = {nbytes:,} data bytes, but its archive member holds "
                f"{info.file_size - header_bytes:,} (truncated or padded)",
            )
        array = np.empty(count, dtype=dtype)
        # numpy's stubs give ndarray __buffer__ only for Python >= 3.12 (we check as 3.10)
        buffer = memoryview(array.view(np.uint8) if array.dtype.itemsize else np.empty(0, np.uint8)).cast("B")  # type: ignore[arg-type]
        done = 0
        while done < nbytes:
            chunk = fp.read(min(_CHUNK, nbytes - done))
            if not chunk:
                raise BadInputError(path, f"{key}: archive member ends after {done:,} of {nbytes:,} data bytes")
            buffer[done : done + len(chunk)] = chunk
            done += len(chunk)
        if fp.read(1):  # also makes zipfile verify the member's CRC
            raise BadInputError(path, f"{key}: archive member has bytes after the array data")
    return array.reshape(shape, order="F" if fortran else "C")


def read_npz(
    path: str | os.PathLike[str], members: Mapping[str, NpzMember], what: str = "the archive"
) -> dict[str, np.ndarray]:
    """The checked arrays of a ``.npz`` file (module docstring: what is checked, in order).

    Parameters
    ----------
    path
        The archive.
    members
        The members to read, by key (without ``.npy``), and what each must be. Other
        members are ignored and never decompressed.
    what
        The format in words, for the missing-key message (``"a BRDF table"``).

    Returns
    -------
    dict
        ``{key: array}`` for every present member of ``members`` (native byte order is not
        enforced: callers convert).

    Raises
    ------
    BadInputError
        Not a regular file, not a zip archive, a missing required member, or any check above.
    """
    path = Path(path)
    regular_file(path, ".npz archive")
    arrays: dict[str, np.ndarray] = {}
    try:
        with path.open("rb") as handle, zipfile.ZipFile(handle) as zf:
            infos = {}
            for info in zf.infolist():
                name = info.filename
                if name.endswith(".npy"):
                    infos[name[:-4]] = info  # the last of duplicate names wins, as in numpy.load
            missing = [k for k, spec in members.items() if spec.required and k not in infos]
            if missing:
                raise BadInputError(path, f"missing key(s) {', '.join(missing)}; {what} has {', '.join(members)}")
            for key, spec in members.items():
                if key in infos:
                    arrays[key] = _read_member(path, key, spec, zf, infos[key])
    except BadInputError:
        raise
    except _CORRUPT as err:
        text = str(err).splitlines()[0][:160] if str(err) else ""
        raise BadInputError(path, f"not a readable .npz archive ({type(err).__name__}: {text})") from None
    return arrays
