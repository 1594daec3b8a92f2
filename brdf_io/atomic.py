"""Atomic file writing: write to a temporary file beside the target, then ``os.replace``.

A failed or interrupted write leaves no partial output and never clobbers an existing
file with half-written data.
"""

from __future__ import annotations

import contextlib
import os
import secrets
import tempfile
from collections.abc import Iterator, Sequence
from pathlib import Path

from .errors import BadInputError

__all__ = ["atomic_path", "atomic_paths", "check_writable"]


#: Tries at a fresh temporary name before giving up (each name has 64 random bits).
_NAME_TRIES = 16


def _temporary(target: Path, suffix: str | None) -> Path:
    """Create an empty temporary file beside ``target``: ``.NAME.<random>SUFFIX``, mode 0o666 less the
    process umask (applied by the kernel: no process-wide state is read or changed, so threads may
    write at once)."""
    folder = target.parent if str(target.parent) else Path(".")
    try:
        folder.mkdir(parents=True, exist_ok=True)
        for _ in range(_NAME_TRIES):
            tmp = folder / f".{target.name}.{secrets.token_hex(8)}{suffix or ''.join(target.suffixes)}"
            try:
                fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_CLOEXEC", 0), 0o666)
            except FileExistsError:
                continue
            os.close(fd)
            return tmp
        raise FileExistsError(f"no free temporary name after {_NAME_TRIES} tries")
    except OSError as err:
        raise BadInputError(target, f"cannot write here ({err.strerror or err})") from None


def _write_error(target: Path, err: BaseException, temps: dict[Path, Path] | None = None) -> BadInputError:
    """One line naming the target for a failed write (``OSError``, or a library's ``RuntimeError``
    such as OpenEXR's "Failed to write pixel data … No space left on device"); ``temps`` maps
    temporary paths to their targets, so that a library's message names the file the user asked for."""
    reason: str | None
    if isinstance(err, OSError):
        reason = err.strerror or str(err)
    else:
        text = str(err)
        reason = next((known for known in ("No space left on device", "Disk quota exceeded", "File too large",
                                           "Input/output error", "Read-only file system") if known in text), None)
        if reason is None:
            for tmp, real in (temps or {}).items():
                text = text.replace(str(tmp), str(real))
            reason = text.strip()[:200]
    return BadInputError(target, f"cannot write ({reason}); nothing was written")


@contextlib.contextmanager
def atomic_paths(paths: Sequence[str | os.PathLike[str]], suffix: str | None = None) -> Iterator[list[Path]]:
    """Yield temporary paths beside each of ``paths``; move them all onto their targets when the
    block succeeds, remove them all when it fails: outputs that belong together (a PNG and its EXR,
    a turntable's frames and GIF) appear together or not at all.

    Raises
    ------
    BadInputError
        A folder that cannot be written, or a write inside the block that fails with ``OSError``
        (full disk, quota, I/O error) or with a writer library's ``RuntimeError`` naming such a
        cause: one line naming the target; no target is changed.
    """
    targets = [Path(p) for p in paths]
    temps: list[Path] = []
    try:
        for target in targets:
            temps.append(_temporary(target, suffix))
        try:
            yield list(temps)
        except (OSError, RuntimeError) as err:
            # the file the error names (an OSError's filename, or a library's message), else the first
            mentioned = f"{err} {getattr(err, 'filename', None) or ''}"
            which = next((t for t, tmp in zip(targets, temps, strict=True) if tmp.name in mentioned), targets[0])
            raise _write_error(which, err, dict(zip(temps, targets, strict=True))) from None
        for target, tmp in zip(targets, temps, strict=True):
            try:
                os.replace(tmp, target)
            except OSError as err:
                raise _write_error(target, err) from None
    finally:
        for tmp in temps:
            with contextlib.suppress(OSError):
                tmp.unlink()


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str], suffix: str | None = None) -> Iterator[Path]:
    """Yield a temporary path in the target's folder; move it onto ``path`` on success
    (:func:`atomic_paths` of one path).

    Parameters
    ----------
    path
        Final file path.
    suffix
        Suffix of the temporary file (default: the target's own suffixes, so libraries
        that pick a format by extension still work).
    """
    with atomic_paths([path], suffix) as (tmp,):
        yield tmp


def check_writable(path: str | os.PathLike[str]) -> Path:
    """Fail early, before any long computation, if ``path`` cannot be written.

    Creates the parent folder if needed (as :func:`atomic_path` would), checks that a file can
    be created there and that ``path`` is not an existing folder.
    """
    target = Path(path)
    if target.is_dir():
        raise BadInputError(target, "is a folder, not a file name")
    folder = target.parent if str(target.parent) else Path(".")
    try:
        folder.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=folder):
            pass
    except OSError as err:
        raise BadInputError(target, f"cannot write here ({err.strerror or err})") from None
    return target
