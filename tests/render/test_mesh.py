"""Mesh loading, validation and normalization (no OpenGL needed).

References: closed forms (unit sphere radius/normals, triangle counts of the built-ins),
files written by trimesh's exporters for every supported format.
"""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from shrmkit.brdf_io.errors import BadInputError
from shrmkit.render.mesh import load_mesh, make_mesh


def test_builtin_sphere_is_unit_with_exact_normals() -> None:
    m = load_mesh("builtin:sphere:subdivisions=3")
    assert m.n_triangles == 20 * 4**3
    np.testing.assert_allclose(np.linalg.norm(m.vertices, axis=1), 1.0, atol=1e-12)
    np.testing.assert_allclose(m.normals, m.vertices, atol=1e-12)


@pytest.mark.parametrize(
    ("spec", "n_tri"),
    [("builtin:torus:segments=32,sides=8", 2 * 32 * 8), ("builtin:torus-knot:segments=64,sides=6", 2 * 64 * 6)],
)
def test_builtin_tubes_are_normalized_and_outward(spec: str, n_tri: int) -> None:
    m = load_mesh(spec)
    assert m.n_triangles == n_tri
    center = 0.5 * (m.vertices.min(0) + m.vertices.max(0))
    np.testing.assert_allclose(center, 0.0, atol=1e-12)
    assert np.max(np.linalg.norm(m.vertices, axis=1)) == pytest.approx(1.0)
    a, b, c = (m.vertices[m.faces[:, k]] for k in range(3))
    face_n = np.cross(b - a, c - a)
    # winding agrees with the analytic tube normals on every face
    assert np.all(np.sum(face_n * m.normals[m.faces].mean(1), axis=1) > 0)


@pytest.mark.parametrize("suffix", [".obj", ".ply", ".stl", ".off", ".glb"])
def test_load_formats_normalizes_and_computes_normals(tmp_path, suffix: str) -> None:
    """An icosphere of radius 3 at (5, -2, 1) exported by trimesh comes back as the unit sphere;
    normals (from the file or computed from faces) are the radial directions to O(edge)."""
    src = trimesh.creation.icosphere(subdivisions=3, radius=3.0)
    src.apply_translation([5.0, -2.0, 1.0])
    path = tmp_path / f"ball{suffix}"
    src.export(path)
    m = load_mesh(path)
    assert m.n_triangles == len(src.faces)
    np.testing.assert_allclose(np.linalg.norm(m.vertices, axis=1), 1.0, atol=1e-3)  # float32 formats
    cos = np.sum(m.normals * m.vertices, axis=1) / np.linalg.norm(m.vertices, axis=1)
    assert cos.min() > 0.99


def test_scene_is_flattened_with_transforms(tmp_path) -> None:
    """Two boxes placed by node transforms at x = ±3: the flattened mesh spans both."""
    scene = trimesh.Scene()
    box = trimesh.creation.box(extents=(1.0, 1.0, 1.0))
    scene.add_geometry(box, transform=trimesh.transformations.translation_matrix([3.0, 0, 0]))
    scene.add_geometry(box, transform=trimesh.transformations.translation_matrix([-3.0, 0, 0]))
    path = tmp_path / "two.glb"
    scene.export(path)
    m = load_mesh(path)
    assert m.n_triangles == 24
    # extent along x is 7 before scaling; radius sqrt(3.5² + 0.5² + 0.5²)
    r = np.sqrt(3.5**2 + 0.25 + 0.25)
    np.testing.assert_allclose(m.vertices[:, 0].max() - m.vertices[:, 0].min(), 7.0 / r, rtol=1e-6)


def test_bad_meshes(tmp_path) -> None:
    nan = tmp_path / "nan.obj"
    nan.write_text("v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n")
    with pytest.raises(BadInputError, match="not finite"):
        load_mesh(nan)
    degen = tmp_path / "degen.obj"
    degen.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nf 1 2 3\nf 1 2 4\n")
    with pytest.raises(BadInputError, match="degenerate"):
        load_mesh(degen)
    empty = tmp_path / "empty.obj"
    empty.write_text("# nothing\n")
    with pytest.raises(BadInputError, match=r"empty\.obj"):
        load_mesh(empty)
    garbage = tmp_path / "garbage.ply"
    garbage.write_bytes(b"\x00\x01not a ply file at all")
    with pytest.raises(BadInputError, match=r"garbage\.ply"):
        load_mesh(garbage)
    with pytest.raises(BadInputError, match="no such file"):
        load_mesh(tmp_path / "missing.obj")
    with pytest.raises(BadInputError, match="unsupported mesh extension"):
        load_mesh(tmp_path / "x.txt")
    with pytest.raises(BadInputError, match="unknown built-in"):
        load_mesh("builtin:teapot")
    with pytest.raises(BadInputError, match="unknown parameter"):
        load_mesh("builtin:sphere:radius=2")


def test_make_mesh_rejects_out_of_range_faces() -> None:
    v = np.eye(3)
    with pytest.raises(BadInputError, match="out of range"):
        make_mesh(v, np.array([[0, 1, 3]]), name="arr")
