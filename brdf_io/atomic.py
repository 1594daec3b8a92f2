"""Atomic file writing: write to a temporary file beside the target, then ``os.replace``.

A failed or interrupted write leaves no partial output and never clobbers an existing
file with half-written data.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path

from .errors import BadInputError

__all__ = ["atomic_path", "check_writable"]


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str], suffix: str | None = None) -> Iterator[Path]:
    """Yield a temporary path in the target's folder; move it onto ``path`` on success.

    Parameters
    ----------
    path
        Final file path.
    suffix
        Suffix of the temporary file (default: the target's own suffixes, so libraries
        that pick a format by extension still work).
    """
    target = Path(path)
    folder = target.parent if str(target.parent) else Path(".")
    try:
        folder.mkdir(parents=True, exist_ok=True)
        fd, tmp_name = tempfile.mkstemp(
            prefix=f".{target.name}.", suffix=suffix or "".join(target.suffixes), dir=folder
        )
    except OSError as err:
        raise BadInputError(target, f"cannot write here ({err.strerror or err})") from None
    os.close(fd)
    tmp = Path(tmp_name)
    try:
        yield tmp
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)  # mkstemp creates 0600; give the file normal permissions
        try:
            os.replace(tmp, target)
        except OSError as err:
            raise BadInputError(target, f"cannot write here ({err.strerror or err})") from None
    finally:
        if tmp.exists():
            tmp.unlink()


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
