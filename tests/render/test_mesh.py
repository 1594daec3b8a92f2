"""Mesh loading, validation and normalization (no OpenGL needed).

References: closed forms (unit sphere radius/normals, triangle counts of the built-ins),
files written by trimesh's exporters for every supported format.
"""

from __future__ import annotations

import os
import re
import signal
import tracemalloc
from contextlib import contextmanager

import numpy as np
import pytest
import trimesh

from shrmkit.brdf_io.errors import BadInputError
from shrmkit.render.mesh import MeshRepairWarning, load_mesh, make_mesh


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
    degen.write_text("v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\nf 3 2 1\n")
    with pytest.raises(BadInputError, match=r"degen\.obj: all 2 faces are degenerate"):
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


# ----------------------------------------------------------------------------- cleaning

# a tetrahedron with a non-symmetric bounding box: bbox centre (1, 1.5, 0.5)
TET_V = np.array([[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 3.0, 0.0], [0.0, 0.0, 1.0]])
TET_F = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])


def _expected_placement(v: np.ndarray) -> np.ndarray:
    """Centre at the bounding-box centre, scale to radius 1, computed here independently."""
    c = np.array([(v[:, k].min() + v[:, k].max()) / 2 for k in range(3)])
    r = max(float(np.sqrt(np.sum((p - c) ** 2))) for p in v)
    return (v - c) / r


def _write_ply(path, v, f, normals=None) -> None:
    props = "property double x\nproperty double y\nproperty double z\n"
    if normals is not None:
        props += "property double nx\nproperty double ny\nproperty double nz\n"
    lines = [
        "ply", "format ascii 1.0", f"element vertex {len(v)}", props.rstrip("\n"),
        f"element face {len(f)}", "property list uchar int vertex_indices", "end_header",
    ]
    for i, p in enumerate(v):
        row = list(p) + ([] if normals is None else list(normals[i]))
        lines.append(" ".join(repr(float(x)) for x in row))
    lines += ["3 " + " ".join(str(int(i)) for i in face) for face in f]
    path.write_text("\n".join(lines) + "\n")


def test_expected_placement_of_tetrahedron() -> None:
    """The hand numbers behind the stray-vertex test: centre (1, 1.5, 0.5), radius √3.5."""
    e = _expected_placement(TET_V)
    np.testing.assert_allclose(e[0], np.array([-1.0, -1.5, -0.5]) / np.sqrt(3.5))


@pytest.mark.parametrize("fmt", ["ply", "obj", "arrays"])
def test_stray_vertex_does_not_move_or_shrink_the_mesh(tmp_path, fmt: str) -> None:
    """An unreferenced vertex at (1000, 0, 0), placed between the used ones, is dropped: the
    result equals the clean tetrahedron's placement and the faces are renumbered."""
    v = np.insert(TET_V, 2, [1000.0, 0.0, 0.0], axis=0)  # stray becomes vertex 2
    f = np.where(TET_F >= 2, TET_F + 1, TET_F)
    if fmt == "ply":
        _write_ply(tmp_path / "stray.ply", v, f)
        m = load_mesh(tmp_path / "stray.ply")
    elif fmt == "obj":
        text = "".join(f"v {float(a)!r} {float(b)!r} {float(c)!r}\n" for a, b, c in v)
        text += "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in f)
        (tmp_path / "stray.obj").write_text(text)
        m = load_mesh(tmp_path / "stray.obj")
    else:
        m = make_mesh(v, f, name="arr")
    assert len(m.vertices) == 4
    np.testing.assert_allclose(m.vertices, _expected_placement(TET_V), atol=1e-12)
    np.testing.assert_array_equal(m.faces, TET_F)


def test_stray_vertex_keeps_file_normals_aligned(tmp_path) -> None:
    """File normals follow their vertices when a stray vertex before them is dropped."""
    normals = np.array([[1.0, 0, 0], [0, 1.0, 0], [0, 0, 1.0], [0.6, 0.8, 0]])
    v = np.vstack([[[-500.0, 7.0, 7.0]], TET_V])
    n = np.vstack([[[0.0, 0.0, -1.0]], normals])
    _write_ply(tmp_path / "normals.ply", v, TET_F + 1, normals=n)
    m = load_mesh(tmp_path / "normals.ply")
    np.testing.assert_allclose(m.normals, normals, atol=1e-12)
    np.testing.assert_allclose(m.vertices, _expected_placement(TET_V), atol=1e-12)


def test_degenerate_faces_are_dropped_with_their_count(tmp_path) -> None:
    """Two good faces plus three degenerate ones (repeated index, collinear, coincident
    points): the warning counts 3 of 5, the two good faces remain, and the vertices only the
    degenerate faces used are dropped too (placement from the good faces alone)."""
    text = (
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"  # 1-4: the good faces
        "v 50 0 0\nv 60 0 0\n"  # 5, 6: collinear with vertex 1 (degenerate only)
        "v 0 40 0\n"  # 7: coincides with itself (repeated index face)
        "f 1 2 3\nf 1 2 4\nf 1 5 6\nf 7 7 2\nf 2 2 2\n"
    )
    (tmp_path / "degen.obj").write_text(text)
    with pytest.warns(MeshRepairWarning, match=r"degen\.obj: dropped 3 of 5 faces that are degenerate"):
        m = load_mesh(tmp_path / "degen.obj")
    assert m.n_triangles == 2
    good = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    np.testing.assert_allclose(np.sort(m.vertices, axis=0), np.sort(_expected_placement(good), axis=0), atol=1e-12)


def test_make_mesh_zero_area_threshold_ignores_stray_vertices() -> None:
    """A small but real triangle is not called degenerate because of a far stray point."""
    v = np.array([[0.0, 0, 0], [1e-4, 0, 0], [0, 1e-4, 0], [1e6, 0, 0]])
    m = make_mesh(v, np.array([[0, 1, 2]]), name="arr")
    assert m.n_triangles == 1
    np.testing.assert_allclose(m.vertices, _expected_placement(v[:3]), atol=1e-12)


# ----------------------------------------------------------------------------- refusals


@pytest.mark.parametrize(
    ("name", "text"),
    [
        ("nan.obj", "v 0 0 0\nv 1 0 0\nv 0 nan 0\nf 1 2 3\n"),
        ("inf.obj", "v 0 0 0\nv 1 0 0\nv 0 1 inf\nf 1 2 3\n"),
        (
            "inf.ply",
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
            "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n-inf 0 0\n0 1 0\n3 0 1 2\n",
        ),
    ],
)
def test_non_finite_vertices_are_refused(tmp_path, name: str, text: str) -> None:
    (tmp_path / name).write_text(text)
    with pytest.raises(BadInputError, match=re.escape(name) + r": 1 of 3 vertices are not finite"):
        load_mesh(tmp_path / name)


def test_face_index_out_of_range_is_refused(tmp_path) -> None:
    ply = tmp_path / "range.ply"
    ply.write_text(
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
        "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 9\n"
    )
    with pytest.raises(BadInputError, match=r"range\.ply: face indices out of range \[0, 3\): min 0, max 9"):
        load_mesh(ply)
    obj = tmp_path / "range.obj"
    obj.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n")
    with pytest.raises(BadInputError, match=r"range\.obj: .*face index out of range"):
        load_mesh(obj)


@pytest.mark.parametrize(
    ("name", "text"),
    [
        ("cloud.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n"),
        (
            "cloud.ply",
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
            "end_header\n0 0 0\n1 0 0\n0 1 0\n",
        ),
    ],
)
def test_point_clouds_are_refused(tmp_path, name: str, text: str) -> None:
    (tmp_path / name).write_text(text)
    with pytest.raises(BadInputError, match=re.escape(name) + r": file holds a point cloud \(3 vertices, no faces\)"):
        load_mesh(tmp_path / name)


@contextmanager
def _deadline(seconds: int):
    """Fail instead of hanging when a reader blocks (a FIFO open waits for a writer)."""

    def fail(*_):
        raise AssertionError(f"blocked for more than {seconds} s")

    old = signal.signal(signal.SIGALRM, fail)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)


@pytest.mark.skipif(not hasattr(os, "mkfifo") or not os.path.exists("/dev/zero"), reason="POSIX only")
def test_special_files_are_refused_without_reading(tmp_path) -> None:
    fifo = tmp_path / "x.ply"
    os.mkfifo(fifo)
    zero = tmp_path / "x.obj"
    zero.symlink_to("/dev/zero")
    with _deadline(20):
        with pytest.raises(BadInputError, match=r"x\.ply: is a FIFO, not a regular mesh file"):
            load_mesh(fifo)
        with pytest.raises(BadInputError, match=r"x\.obj: is a device or special file"):
            load_mesh(zero)
        with pytest.raises(BadInputError, match=r"x\.stl: is a folder"):
            (tmp_path / "x.stl").mkdir()
            load_mesh(tmp_path / "x.stl")


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="POSIX only")
def test_files_a_mesh_references_are_read_safely(tmp_path) -> None:
    """An OBJ's material library that is a FIFO is skipped (materials are not used); a glTF
    buffer that is a FIFO is refused, naming it; neither blocks."""
    os.mkfifo(tmp_path / "mat.mtl")
    (tmp_path / "m.obj").write_text("mtllib mat.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    gl = tmp_path / "gl"
    gl.mkdir()
    for name, data in trimesh.exchange.gltf.export_gltf(trimesh.creation.box()).items():
        if name.endswith(".bin"):
            os.mkfifo(gl / name)
        else:
            (gl / name).write_bytes(data)
    assert list(gl.glob("*.bin"))
    with _deadline(20):
        assert load_mesh(tmp_path / "m.obj").n_triangles == 1
        with pytest.raises(BadInputError, match=r"\.bin: is a FIFO"):
            load_mesh(gl / "model.gltf")


_PLY_HEAD = (
    "ply\nformat {fmt} 1.0\nelement vertex {nv}\nproperty float x\nproperty float y\nproperty float z\n"
    "element face {nf}\nproperty list uchar int vertex_indices\nend_header\n"
)


@pytest.mark.parametrize(
    ("fmt", "nv", "nf", "message"),
    [
        ("ascii", 10**12, 1, r"PLY element 'vertex' of shape \(1000000000000, 3\) = 3,000,000,000,000 elements"
         r" exceeds the 536,870,912-element limit"),
        ("binary_little_endian", 3, 10**12, r"PLY element 'face' of shape \(1000000000000, 1\)"),
        # within the element limit, but far more than a 200-byte file holds:
        # ASCII needs 2 bytes per value (3 per vertex, >= 1 per face), binary 12 per vertex, 1 per face
        ("ascii", 10**6, 1, r"need at least 6,000,001 bytes, but the file holds 26 after its header"),
        ("binary_little_endian", 3, 10**6, r"need at least 1,000,036 bytes, but the file holds 36 after its header"),
    ],
)
def test_ply_header_counts_are_checked_before_allocation(tmp_path, fmt: str, nv: int, nf: int, message: str) -> None:
    path = tmp_path / "hostile.ply"
    head = _PLY_HEAD.format(fmt=fmt, nv=nv, nf=nf).encode()
    body = b"0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n" if fmt == "ascii" else np.zeros(9, "<f4").tobytes()
    path.write_bytes(head + body)
    assert path.stat().st_size < 300
    tracemalloc.start()
    try:
        with pytest.raises(BadInputError, match=r"hostile\.ply: .*" + message):
            load_mesh(path)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 8 * 2**20


def test_ply_header_check_accepts_exact_binary_files(tmp_path) -> None:
    """A well-formed binary PLY (trimesh's exporter) passes the header check unchanged."""
    src = trimesh.creation.icosphere(subdivisions=1)
    path = tmp_path / "ok.ply"
    path.write_bytes(trimesh.exchange.ply.export_ply(src, encoding="binary"))
    assert load_mesh(path).n_triangles == len(src.faces)
