"""A batch's output folder: the run's lock file, the stale temporaries of killed runs removed,
and ``summary.csv`` / ``index.html`` of every report there, written under the folder's lock.
"""

from __future__ import annotations

import contextlib
import fcntl
import json
import os
import re
import shutil
import tempfile
from pathlib import Path
from typing import Any

from .writer import summary_row, write_summary

#: A run's lock file in its output folder (its own, held for the run, removed at the end).
_RUN_LOCK_PREFIX, _RUN_LOCK_SUFFIX = ".shrm-report-run.", ".lock"
#: The random part of a temporary name: ``tempfile``'s 8 characters of ``[a-z0-9_]``, or
#: hexadecimal digits (``secrets.token_hex``) of up to 128 bits.
_RANDOM = r"[a-z0-9_]{8,32}"
#: Temporary folders of :func:`~.writer.write_folder` (``.NAME.XXXXXXXX.tmp``, and ``.old``
#: holding the report it replaces), temporary files of the summary (``atomic_path``), and
#: the lock files of runs: report names never start with ``.`` (:func:`~.batch.report_names`).
_TEMP_FOLDER = re.compile(rf"\..+\.{_RANDOM}\.(tmp|old)")
_TEMP_FILE = re.compile(rf"\.(summary\.csv\.{_RANDOM}\.csv|index\.html\.{_RANDOM}\.html)")
_RUN_LOCK = re.compile(rf"{re.escape(_RUN_LOCK_PREFIX)}{_RANDOM}{re.escape(_RUN_LOCK_SUFFIX)}")


def _lock_run(out: Path) -> tuple[int, Path] | None:
    """This run's lock file in ``out``, created and locked (``flock``, exclusive) for the whole
    run: another run that finds it locked leaves the temporaries there alone. None if the
    folder cannot be written (the report folders then fail and say why)."""
    for _ in range(3):
        try:
            fd, name = tempfile.mkstemp(prefix=_RUN_LOCK_PREFIX, suffix=_RUN_LOCK_SUFFIX, dir=out)
        except OSError:
            return None
        fcntl.flock(fd, fcntl.LOCK_EX)
        try:  # still ours? (another run's cleanup may have taken it for a dead run's before the flock)
            if os.stat(name).st_ino == os.fstat(fd).st_ino:
                return fd, Path(name)
        except OSError:
            pass
        os.close(fd)
    return None  # pragma: no cover - lost three times to other runs' cleanups


def _unlock_run(lock: tuple[int, Path] | None) -> None:
    if lock is not None:
        with contextlib.suppress(OSError):
            lock[1].unlink()
        os.close(lock[0])


def _dead_run(path: str) -> bool:
    """Whether the run of lock file ``path`` is over (then the file is removed): nobody holds its lock."""
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:
        return True  # removed meanwhile
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:  # locked: that run is alive
        os.close(fd)
        return False
    with contextlib.suppress(OSError):
        os.unlink(path)
    os.close(fd)
    return True


def _remove_stale_temporaries(out: Path, own_lock: Path | None) -> list[str]:
    """Remove what runs killed while writing left in ``out``: the temporary report folders and
    summary files of :data:`_TEMP_FOLDER` and :data:`_TEMP_FILE`, and their lock files; nothing
    while another run into ``out`` is alive (its lock file is locked). A report that a killed
    run had moved aside (``.old``) and not yet replaced is put back first. Returns the names
    removed."""
    try:
        entries = list(os.scandir(out))
    except OSError:
        return []
    stale: list[os.DirEntry[str]] = []
    removed: list[str] = []
    for entry in entries:
        if _RUN_LOCK.fullmatch(entry.name):
            if own_lock is not None and entry.name == own_lock.name:
                continue
            if not _dead_run(entry.path):
                return removed  # another run into this folder is alive: its temporaries are its own
            removed.append(entry.name)
        elif (_TEMP_FOLDER.fullmatch(entry.name) and entry.is_dir(follow_symlinks=False)) or (
                _TEMP_FILE.fullmatch(entry.name) and entry.is_file(follow_symlinks=False)):
            stale.append(entry)
    for entry in stale:
        try:
            if entry.name.endswith(".old"):
                for kept in os.scandir(entry.path):  # the report a killed run had moved aside
                    if not (out / kept.name).exists():
                        os.replace(kept.path, out / kept.name)
            if entry.is_dir(follow_symlinks=False):
                shutil.rmtree(entry.path)
            else:
                os.unlink(entry.path)
            removed.append(entry.name)
        except OSError:
            continue  # not ours to remove after all (permissions): left as it is
    return removed


def _write_index(out: Path, rows: list[dict[str, Any]], notes: list[str], wait: bool = True) -> None:
    """``summary.csv`` and ``index.html`` of every report in ``out``: this run's rows (input order),
    then those of the other report folders already there (earlier or concurrent runs into the
    same ``--out``), rebuilt from their ``report.json``, under an exclusive lock on the folder, so
    two runs at once never lose a row (issue 28: the last writer's index listed 2 of 3). Not
    ``wait``: nothing written when another run holds the lock (``BlockingIOError``)."""
    fd = os.open(out, os.O_RDONLY)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX if wait else fcntl.LOCK_EX | fcntl.LOCK_NB)
        names = {row["name"] for row in rows}
        others = []
        for folder in sorted(p for p in out.iterdir() if p.is_dir() and not p.name.startswith(".")):
            if folder.name in names:
                continue
            try:
                doc = json.loads((folder / "report.json").read_text(encoding="utf-8"))
                others.append(summary_row(doc))
            except (OSError, ValueError, KeyError, TypeError):
                continue  # not a report folder (or one being replaced): left out
        if others:
            notes = [*notes, f"{len(others)} more report(s) already in this folder are listed after this run's."]
        write_summary(out, rows + others, notes)
    finally:
        os.close(fd)


def _failed_row(name: str, source: str, seconds: float | None, error: str) -> dict[str, Any]:
    """A summary row for a BRDF whose report could not be written or was never made (the
    keys of :func:`~.writer.summary_row` for a failed report)."""
    return {"name": name, "status": "failed", "source": source, "error": error, "total_seconds": seconds}
