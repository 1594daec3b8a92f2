"""Fixtures for rendering tests: an offscreen OpenGL context, probed once in a subprocess."""

from __future__ import annotations

import pytest

from shrmkit.render.offscreen import probe_offscreen

_PROBE: list[tuple[bool, str]] = []


@pytest.fixture(scope="session")
def offscreen() -> str:
    """The VTK window class in use; skips the test when no offscreen float context can be made."""
    if not _PROBE:
        _PROBE.append(probe_offscreen())
    ok, message = _PROBE[0]
    if not ok:
        pytest.skip(message)
    return message
