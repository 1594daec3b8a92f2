"""Shared fixtures: the real data in ../shared/data (skipped with a clear message if absent)."""

from __future__ import annotations

from pathlib import Path

import pytest

from shrmkit.render.offscreen import probe_offscreen

SHARED_DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"


@pytest.fixture(scope="session")
def shared_data() -> Path:
    """Path of ../shared/data; skips the test when a user's clone has no ../shared."""
    if not SHARED_DATA.is_dir():
        pytest.skip(f"real data folder {SHARED_DATA} not present (only in the project workspace)")
    return SHARED_DATA


_PROBE: list[tuple[bool, str]] = []


@pytest.fixture(scope="session")
def offscreen() -> str:
    """The VTK window class in use; skips the test when no offscreen float context can be made
    (probed once, in a subprocess)."""
    if not _PROBE:
        _PROBE.append(probe_offscreen())
    ok, message = _PROBE[0]
    if not ok:
        pytest.skip(message)
    return message
