"""The builtin sphere's icosphere (render/mesh.py) against trimesh's, which it replaces at start-up."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from shrmkit.render.mesh import _icosphere


@pytest.mark.parametrize("subdivisions", [0, 1, 2, 5])
def test_icosphere_is_trimesh_icosphere(subdivisions):
    import trimesh.creation

    ico = trimesh.creation.icosphere(subdivisions=subdivisions, radius=1.0)
    expected = np.asarray(ico.vertices, dtype=np.float64)
    expected /= np.linalg.norm(expected, axis=1, keepdims=True)
    v, f = _icosphere(subdivisions)
    # the same vertices in the same order, bit for bit, and the same faces
    assert np.array_equal(v, expected)
    assert np.array_equal(f, np.asarray(ico.faces))


def test_icosphere_closed_form():
    k = 3
    v, f = _icosphere(k)
    assert len(v) == 10 * 4**k + 2 and len(f) == 20 * 4**k  # Euler: V − E + F = 2, E = 3F/2
    assert np.allclose(np.linalg.norm(v, axis=1), 1.0, atol=1e-15)
    # counter-clockwise seen from outside: each face's normal points away from the centre
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    assert np.all(np.einsum("ij,ij->i", np.cross(b - a, c - a), a + b + c) > 0)
    # the triangles tile the sphere: their flat areas add up to just under 4π
    area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1).sum()
    assert 0.98 * 4 * np.pi < area < 4 * np.pi


def test_builtin_sphere_does_not_import_trimesh():
    code = ("import sys; from shrmkit.render.mesh import load_mesh; m = load_mesh('builtin:sphere'); "
            "print(len(m.vertices), 'trimesh' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    assert out == ["40962", "False"]
