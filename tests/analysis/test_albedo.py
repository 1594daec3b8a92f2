"""Directional albedo (analysis/albedo.py) against closed forms: Lafortune kd + ks cos^n at normal view,
a(0) = kd + ks·2π/(n + 2); Lambert a at every view."""

from __future__ import annotations

import numpy as np

import shrmkit
from shrmkit.analysis.albedo import ALBEDO_CHECK_VIEWS_DEG, directional_albedo


def test_lafortune_at_normal_view_is_closed_form() -> None:
    brdf = shrmkit.load_brdf("lafortune:kd=0.3,n=20,ks=4")
    a = directional_albedo(brdf, views_deg=(0.0,), nodes=48)[0]
    np.testing.assert_allclose(a, 0.3 + 4.0 * 2.0 * np.pi / 22.0, rtol=1e-9)


def test_lambert_is_its_albedo_at_every_view() -> None:
    lam = directional_albedo(shrmkit.load_brdf("lambert:albedo=0.2/0.4/0.8"), nodes=16)
    assert lam.shape == (len(ALBEDO_CHECK_VIEWS_DEG), 3)
    np.testing.assert_allclose(lam, np.tile([0.2, 0.4, 0.8], (lam.shape[0], 1)), rtol=1e-12)
