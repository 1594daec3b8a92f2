"""Limits every reader checks *before* it allocates or reads, and the one safe way to
open an input file (``data_specs/limits.md``).

A hostile or broken file must cost a reader no more than a look at its header: a FIFO
named ``x.binary`` would block forever, a symlink to ``/dev/zero`` would read until
memory runs out, and a few kilobytes of header can declare 10⁹ pixels or array
elements. Readers therefore

1. open inputs through :func:`regular_file` / :func:`read_bytes`, which accept only a
   regular file (after following links) no larger than :func:`max_file_bytes`,
2. check every declared size with :func:`check_elements` (or :func:`check_pixels`)
   against :func:`max_elements` before allocating, and against the bytes the file
   actually holds where the format lets them, and
3. estimate their peak memory from the header and the options before allocating
   (:func:`check_memory`, against :func:`max_memory_bytes`).

The limits are generous for real data (a 16384 × 8192 lat-long map, a MERL table, a 1 GB table)
and overridable through the environment: ``SHRM_MAX_FILE_BYTES``, ``SHRM_MAX_PIXELS``,
``SHRM_MAX_ELEMENTS``, ``SHRM_MAX_MEMORY_BYTES`` (defaults and meaning: each ``max_*`` function).
Every violation raises :class:`~shrmkit.brdf_io.errors.BadInputError` naming the file, so the CLI
prints one line and exits with status 2.
"""

from __future__ import annotations

import math
import os
import stat
from pathlib import Path

from .errors import BadInputError

__all__ = [
    "max_file_bytes",
    "max_pixels",
    "max_elements",
    "regular_file",
    "read_bytes",
    "check_pixels",
    "check_elements",
    "max_memory_bytes",
    "check_memory",
    "format_bytes",
    "TEXT_PEAK_PER_BYTE",
]

DEFAULT_MAX_FILE_BYTES = 8 * 2**30
DEFAULT_MAX_PIXELS = 2**28
DEFAULT_MAX_ELEMENTS = 2**29
DEFAULT_MAX_MEMORY_BYTES = 8 * 2**30
#: Peak bytes per file byte a text reader (Cornell, CURET, gonioreflectometer CSV) plans while it
#: parses: the text, its lines and tokens, the arrays (measured 4.0 for Cornell, 6.2 for a CSV).
TEXT_PEAK_PER_BYTE = 8


def _env_limit(name: str, default: int) -> int:
    text = os.environ.get(name)
    if text is None or not text.strip():
        return default
    try:
        value = int(text.strip())
    except ValueError:
        raise BadInputError(name, f"environment variable {name}={text!r} is not a whole number") from None
    if value <= 0:
        raise BadInputError(name, f"environment variable {name}={text!r} must be positive")
    return value


def max_file_bytes() -> int:
    """Largest input file a reader opens, in bytes (``SHRM_MAX_FILE_BYTES``, default 8 GiB)."""
    return _env_limit("SHRM_MAX_FILE_BYTES", DEFAULT_MAX_FILE_BYTES)


def max_pixels() -> int:
    """Largest image a reader decodes, in pixels: width × height (``SHRM_MAX_PIXELS``, default
    2²⁸ = 268,435,456, twice a 16384 × 8192 map)."""
    return _env_limit("SHRM_MAX_PIXELS", DEFAULT_MAX_PIXELS)


def max_elements() -> int:
    """Largest array a reader allocates from a file's declared shape, in elements
    (``SHRM_MAX_ELEMENTS``, default 2²⁹ ≈ 5.4 · 10⁸, 4 GiB of float64)."""
    return _env_limit("SHRM_MAX_ELEMENTS", DEFAULT_MAX_ELEMENTS)


def max_memory_bytes() -> int:
    """Largest peak memory a reader or verb plans to spend, in bytes (``SHRM_MAX_MEMORY_BYTES``,
    default 8 GiB, a third of a 24 GiB machine)."""
    return _env_limit("SHRM_MAX_MEMORY_BYTES", DEFAULT_MAX_MEMORY_BYTES)


def format_bytes(nbytes: float) -> str:
    """``nbytes`` in words for a message: ``"8.3 GiB"``, ``"512 MiB"``, ``"40 KiB"``, ``"12 bytes"``."""
    for unit, size in (("GiB", 2**30), ("MiB", 2**20), ("KiB", 2**10)):
        if nbytes >= size:
            value = nbytes / size
            return f"{value:,.1f} {unit}" if value < 100 else f"{value:,.0f} {unit}"
    return f"{int(nbytes)} bytes"


def check_memory(source: object, nbytes: float, what: str) -> int:
    """Refuse a planned peak of ``nbytes`` bytes over :func:`max_memory_bytes`, before it is spent.

    Each reader or verb estimates its peak from the header and the options before it allocates,
    so that a few kilobytes declaring 2²⁸ pixels or a table that inflates a thousand-fold cost a
    look at the header, not 8 GB.

    Parameters
    ----------
    source
        The file, or the option (``"--size 100000"``), the estimate comes from: named first
        in the message.
    nbytes
        The estimated peak, bytes: the arrays the reader or verb will hold at once, from the
        declared sizes (header) and the options (data_specs/limits.md lists each estimate).
    what
        What needs it, in words (``"reading 23170 x 11585 pixels"``).

    Returns
    -------
    int
        ``nbytes`` rounded up (for callers that add estimates).

    Raises
    ------
    BadInputError
        ``nbytes`` over the limit: one line naming ``source``, ``what``, the estimate and the
        limit (``SHRM_MAX_MEMORY_BYTES``).
    """
    need = int(math.ceil(float(nbytes))) if math.isfinite(float(nbytes)) else 2**63
    limit = max_memory_bytes()
    if need > limit:
        raise BadInputError(
            source, f"{what} needs an estimated {format_bytes(need)} of memory, over the {format_bytes(limit)} "
            "limit (SHRM_MAX_MEMORY_BYTES)",
        )
    return need


def regular_file(path: str | Path, what: str = "file") -> int:
    """Check that ``path`` is a readable regular file of allowed size; return its size.

    Links are followed. FIFOs, sockets, devices (``/dev/zero``) and folders are refused
    without opening them, so a reader never blocks or reads without end.

    Raises
    ------
    BadInputError
        Missing, not a regular file, or larger than :func:`max_file_bytes`.
    """
    path = Path(path)
    try:
        info = path.stat()
    except FileNotFoundError:
        raise BadInputError(path, "no such file") from None
    except OSError as err:
        raise BadInputError(path, f"cannot read ({err.strerror or err})") from None
    except ValueError:  # a NUL character in the path
        raise BadInputError(repr(str(path)), "not a valid file name (contains a NUL character)") from None
    if stat.S_ISDIR(info.st_mode):
        raise BadInputError(path, f"is a folder, expected a {what}")
    if not stat.S_ISREG(info.st_mode):
        kind = "a FIFO" if stat.S_ISFIFO(info.st_mode) else "a device or special file"
        raise BadInputError(path, f"is {kind}, not a regular {what}")
    limit = max_file_bytes()
    if info.st_size > limit:
        raise BadInputError(
            path, f"file of {info.st_size:,} bytes exceeds the {limit:,}-byte limit (SHRM_MAX_FILE_BYTES)"
        )
    return int(info.st_size)


def read_bytes(path: str | Path, what: str = "file", peak_per_byte: float = 0.0) -> bytes:
    """The whole content of a regular file checked by :func:`regular_file`.

    ``peak_per_byte``: the caller's peak memory per byte of the file while it parses it (a text
    reader's lines, tokens and arrays); with it, :func:`check_memory` plans ``size × peak_per_byte``
    before a byte is read (0: not planned).

    Raises
    ------
    BadInputError
        As :func:`regular_file`, a planned peak over :func:`max_memory_bytes`, or when reading
        fails (the OS reason is given).
    """
    path = Path(path)
    size = regular_file(path, what)
    if peak_per_byte:
        check_memory(path, size * peak_per_byte, f"reading a {size:,}-byte {what}")
    try:
        with path.open("rb") as handle:
            data = handle.read(size + 1)
    except OSError as err:
        raise BadInputError(path, f"cannot read ({err.strerror or err})") from None
    if len(data) > size:  # grew while we read it: not a file we can trust
        raise BadInputError(path, "file changed size while being read")
    return data


def check_pixels(source: object, height: int, width: int) -> None:
    """Refuse an image whose declared ``height × width`` exceeds :func:`max_pixels`
    (or is not positive), before anything is allocated."""
    if height <= 0 or width <= 0:
        raise BadInputError(source, f"zero-size image ({width} x {height})")
    limit = max_pixels()
    if height * width > limit:
        raise BadInputError(
            source,
            f"image of {width} x {height} = {height * width:,} pixels exceeds the {limit:,}-pixel limit "
            "(SHRM_MAX_PIXELS)",
        )


def check_elements(source: object, shape: tuple[int, ...], what: str = "array") -> int:
    """Refuse a declared array shape with a negative axis, more than :func:`max_elements`
    elements, or an axis longer than that (even beside a zero-length one: numpy refuses
    such shapes); return the element count."""
    if any(int(n) < 0 for n in shape):
        raise BadInputError(source, f"{what} declares a negative size {tuple(shape)}")
    count = math.prod(int(n) for n in shape)
    limit = max_elements()
    if count > limit or any(int(n) > limit for n in shape):  # an empty array may still name a huge axis
        raise BadInputError(
            source, f"{what} of shape {tuple(shape)} = {count:,} elements exceeds the {limit:,}-element limit "
            "(SHRM_MAX_ELEMENTS)",
        )
    return count
