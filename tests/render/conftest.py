"""Fixtures of the render tests: the "dots" map of the lights tests (test_lights_render.py, the VTK
shaders; test_lights_webgl.py, the WebGL page) and its lights-only SHRM."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest

from shrmkit.analysis.lights import extract_lights
from shrmkit.analysis.shrm import SHRM
from shrmkit.brdf_io.envmap import EnvironmentMap

#: Bright pixels of the 32 × 64 "dots" map: (row, column, RGB radiance); one near the horizon
DOTS = [(8, 5, (50, 40, 30)), (14, 20, (20, 30, 60)), (20, 44, (40, 40, 40)), (5, 33, (10, 60, 10)),
        (15, 58, (30, 20, 10))]


@pytest.fixture(scope="session")
def dots() -> EnvironmentMap:
    """The 32 × 64 map black but for :data:`DOTS`."""
    radiance = np.zeros((32, 64, 3), np.float32)
    for i, j, c in DOTS:
        radiance[i, j] = c
    return EnvironmentMap(radiance, name="dots")


@pytest.fixture(scope="session")
def n_dots() -> int:
    """How many bright pixels the dots map holds (each one light sample)."""
    return len(DOTS)


@pytest.fixture(scope="session")
def lights_only(dots) -> Callable[..., SHRM]:
    """``lights_only(brdf)``: the SHRM of the dots map, a map that is only lights:
    extract_lights(dots, "auto") (what prefilter does first) takes every bright pixel, the residual
    is black, so the maps are zero and the radiance is the lights' alone."""
    extraction = extract_lights(dots, "auto")
    assert float(extraction.residual.radiance.max()) < 1e-30  # black (a float32 "tiny" at most)

    def make(brdf) -> SHRM:
        return SHRM(F=0, P=0, coeffs=np.zeros((1, 8, 16, 3), np.float32),
                    meta={"max_view_deg": 80.0, "brdf": brdf.name, "environment": "dots", "lights_requested": "auto"},
                    lights=extraction.lights, brdf=brdf)

    return make
