"""BRDF Explorer's views (analysis/brdf_views.py) against independent references: the below-surface
condition tan θ_h tan θ_d > 1 at φ_d = 0 and Lambert's ρ = a/π; each lit-sphere pixel recomputed in
another tangent frame (the Rodrigues rotation taking N to +z). The slice of a table with missing
samples, the plane of incidence and the closed-form Lambert sphere are tested through the report's
``explore`` (tests/cli/report/test_explorer.py)."""

from __future__ import annotations

import math

import numpy as np

import shrmkit
from shrmkit.analysis.brdf_views import SPHERE_LIGHT, halfdiff_slice, lit_sphere

LAMBERT = "lambert:albedo=0.2/0.4/0.8"


def test_cells_below_the_surface_are_marked_apart() -> None:
    """At φ_d = 0 one of L, V is below the surface where tan θ_h tan θ_d > 1 (ρ = 0 there, not a
    missing measurement); Lambert ρ = a/π above."""
    s = halfdiff_slice(shrmkit.load_brdf(LAMBERT), phi_d_deg=0.0)
    t = np.tan(np.radians(s["theta_h_deg"]))[:, None] * np.tan(np.radians(s["theta_d_deg"]))[None, :]
    clear = np.abs(t - 1.0) > 1e-9  # θ_h + θ_d = 90° exactly: L grazes the surface
    assert np.array_equal(s["below_surface"][clear], (t > 1.0)[clear]) and s["below_surface"].sum() > 100
    assert not np.any(s["missing"])
    above = s["rgb"][~s["below_surface"]]
    np.testing.assert_allclose(above, np.broadcast_to([0.2 / np.pi, 0.4 / np.pi, 0.8 / np.pi], above.shape),
                               rtol=1e-12)


def test_lit_sphere_uses_each_pixels_tangent_frame() -> None:
    """A glossy isotropic BRDF: every lit pixel is ρ(L', V')·(N·L)·π with L', V' rotated so that
    N is +z (Rodrigues rotation, another tangent frame than the code's)."""
    brdf = shrmkit.load_brdf("cook-torrance:kd=0.1,alpha=0.2,f0=0.8")
    radiance, hit = lit_sphere(brdf, size=24)
    n = 24
    c = (2.0 * np.arange(n) + 1.0) / n - 1.0
    light = np.asarray(SPHERE_LIGHT) / np.linalg.norm(SPHERE_LIGHT)
    view = np.array([0.0, 0.0, 1.0])
    checked = 0
    for i in range(n):
        for j in range(n):
            x, y = c[j], -c[i]
            if x * x + y * y >= 1.0:
                continue
            N = np.array([x, y, math.sqrt(1.0 - x * x - y * y)])
            axis = np.cross(N, [0.0, 0.0, 1.0])
            s, cth = np.linalg.norm(axis), N[2]
            K = np.zeros((3, 3)) if s < 1e-12 else np.array(
                [[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]]) / s
            R = np.eye(3) + s * K + (1.0 - cth) * K @ K
            assert np.allclose(R @ N, [0.0, 0.0, 1.0])
            cos_i = float(N @ light)
            expected = brdf.eval(R @ light, R @ view) * np.pi * cos_i if cos_i > 0 else np.zeros(3)
            np.testing.assert_allclose(radiance[i, j], expected, rtol=1e-9, atol=1e-12)
            checked += 1
    assert checked > 300 and hit.sum() == checked
