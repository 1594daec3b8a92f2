"""The frame-rate changes of issue 15 change no image.

- Back-face culling of closed, outward-oriented meshes (``vtk_renderer.closed_outward``):
  reference = the same surface drawn without culling (a hidden triangle inside the solid makes
  the mesh open, so the renderer keeps its back faces) and the numpy ray caster
  ``render.cpu_reference`` (Möller–Trumbore, normals flipped on back faces) from inside the solid.
- The per-frame culling decision follows the camera: a sequence of cameras in one renderer gives
  the images of a fresh renderer per camera.
- The packed RGBA coefficient atlas of ``perpixel``: the images equal the closed form
  Σ_c Y^r_c(V) c_k (coefficients constant in R) from ``analysis.sh.real_sph_harm``.
"""

from __future__ import annotations

import numpy as np
import pytest

from shrmkit.analysis.sh import real_sph_harm
from shrmkit.analysis.shrm import SHRM
from shrmkit.brdf_io.latlong import pixel_directions
from shrmkit.render.camera import Camera, orbit_camera
from shrmkit.render.cpu_reference import mesh_geometry, shade
from shrmkit.render.mesh import Mesh, load_mesh, make_mesh
from shrmkit.render.vtk_renderer import SHRMRenderer, closed_outward

Y00 = 1.0 / np.sqrt(4.0 * np.pi)


@pytest.fixture(scope="module")
def torus() -> Mesh:
    return load_mesh("builtin:torus:segments=96,sides=32")


def _shrm_of_R(H: int = 32, W: int = 64) -> SHRM:
    """Radiance (1 + R_x, 1 + R_y, 1 + R_z) / 2 for every V (only the p = 0 maps are non-zero)."""
    c = np.zeros((4, H, W, 3), np.float32)
    c[0] = 0.5 * (1.0 + pixel_directions(H, W)) / Y00
    return SHRM(F=H - 1, P=1, coeffs=c)


def _with_hidden_triangle(mesh: Mesh, point: np.ndarray) -> Mesh:
    """``mesh`` plus a 10⁻³-sized triangle at ``point`` (inside the solid): the same image, not closed."""
    tri = point + 1e-3 * np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    v = np.vstack([mesh.vertices, tri])
    f = np.vstack([mesh.faces, len(mesh.vertices) + np.array([[0, 1, 2]])])
    n = np.vstack([mesh.normals, np.tile([0.0, 0.0, 1.0], (3, 1))])
    return make_mesh(v, f, n, normalize=False)


def test_closed_outward_recognises_closed_outward_surfaces(torus) -> None:
    sphere = load_mesh("builtin:sphere:subdivisions=2")
    assert closed_outward(sphere) and closed_outward(torus)
    assert closed_outward(load_mesh("builtin:torus-knot:segments=64,sides=8"))
    assert not closed_outward(make_mesh(sphere.vertices, sphere.faces[:, ::-1], normalize=False))  # inward
    assert not closed_outward(make_mesh(sphere.vertices, sphere.faces[1:], normalize=False))  # a hole
    assert not closed_outward(_with_hidden_triangle(sphere, np.zeros(3)))  # an open piece
    # two pieces: the second inward (a cavity) -> not culled, though the total volume is positive
    inner = make_mesh(0.5 * sphere.vertices, sphere.faces[:, ::-1], normalize=False)
    hollow = make_mesh(np.vstack([sphere.vertices, inner.vertices]),
                       np.vstack([sphere.faces, len(sphere.vertices) + inner.faces]), normalize=False)
    assert not closed_outward(hollow)
    # a seam: one face uses a copy of vertex 0 at the same place -> its edges no longer pair up
    face = int(np.flatnonzero(np.any(sphere.faces == 0, axis=1))[0])
    f = sphere.faces.copy()
    f[face][f[face] == 0] = len(sphere.vertices)
    assert not closed_outward(make_mesh(np.vstack([sphere.vertices, sphere.vertices[:1]]), f, normalize=False))


@pytest.mark.render
@pytest.mark.parametrize("mode", ["distant", "perpixel"])
def test_culling_back_faces_of_a_closed_mesh_changes_no_pixel(offscreen, torus, mode) -> None:
    """A torus seen obliquely (its far side hidden by its near side) is drawn with back faces
    culled; the same torus made open by a hidden triangle inside the tube is drawn without:
    the images are identical, bit for bit."""
    tube_center = torus.vertices[np.argmax(torus.vertices[:, 0])] * np.array([0.85, 1.0, 1.0])
    opened = _with_hidden_triangle(torus, tube_center)
    assert closed_outward(torus) and not closed_outward(opened)
    shrm = _shrm_of_R()
    base = Camera.looking_at(view=(1.0, 0.3, 0.6))
    for cam in (base, orbit_camera(base, np.zeros(3), 2.0), Camera.looking_at(view=(0.3, 1.0, 0.2),
                                                                               projection="ortho")):
        images = []
        for mesh in (torus, opened):
            with SHRMRenderer(96, 96) as r:
                r.add_object(mesh, shrm, mode=mode)
                images.append(r.render(cam))
        assert images[0].alpha.sum() > 500
        np.testing.assert_array_equal(images[0].alpha, images[1].alpha)
        np.testing.assert_array_equal(images[0].radiance, images[1].radiance)


@pytest.mark.render
def test_back_faces_are_drawn_when_the_camera_is_inside_and_culling_follows_the_camera(offscreen) -> None:
    """From the centre of a closed sphere every pixel sees its inside (back faces, normals
    flipped toward the viewer, as the CPU ray caster does); moving the same renderer's camera
    outside and back gives the images of fresh renderers."""
    sphere = load_mesh("builtin:sphere:subdivisions=4")
    shrm = _shrm_of_R()
    outside = Camera.looking_at(view=(1.0, 0.2, 0.3))
    inside = Camera(np.zeros(3), outside.forward, outside.right, outside.up, fov_y=np.deg2rad(60.0))
    fresh = {}
    for name, cam in (("inside", inside), ("outside", outside)):
        with SHRMRenderer(48, 48) as r:
            r.add_object(sphere, shrm, mode="perpixel")
            fresh[name] = r.render(cam)
    assert np.all(fresh["inside"].alpha == 1.0)
    geom = mesh_geometry(inside, 48, 48, sphere)
    cpu = shade(geom, shrm.radiance)
    assert np.all(geom.hit)
    assert np.abs(fresh["inside"].radiance - cpu).max() < 0.02  # faceting of the sphere only
    with SHRMRenderer(48, 48) as r:
        r.add_object(sphere, shrm, mode="perpixel")
        for name in ("outside", "inside", "outside", "inside"):
            res = r.render(outside if name == "outside" else inside)
            np.testing.assert_array_equal(res.radiance, fresh[name].radiance)
            np.testing.assert_array_equal(res.alpha, fresh[name].alpha)


#: the view of test_packed_atlas_sums_every_coefficient_and_channel
ATLAS_CAMERA = Camera.looking_at(view=(1.0, -0.4, 0.5))


@pytest.fixture(scope="module")
def atlas_sphere():
    """(sphere, the ray caster's hits at 40² from ATLAS_CAMERA): cast once (0.4 s CPU) for the
    three orders of the test below, read-only."""
    sphere = load_mesh("builtin:sphere:subdivisions=3")
    geom = mesh_geometry(ATLAS_CAMERA, 40, 40, sphere)
    for value in vars(geom).values():
        if isinstance(value, np.ndarray):
            value.setflags(write=False)
    return sphere, geom


@pytest.mark.render
@pytest.mark.parametrize("P", [0, 1, 3])
def test_packed_atlas_sums_every_coefficient_and_channel(offscreen, atlas_sphere, P) -> None:
    """Coefficients constant in R, distinct per (coefficient, channel): the per-pixel image is
    Σ_c Y^r_c(V) coef[c, k] (closed form, analysis.sh.real_sph_harm) for P = 0, 1, 3
    (3, 12, 48 scalar maps: 1, 3, 12 RGBA tiles, the first with padding)."""
    n = (P + 1) ** 2
    coef = 0.1 * (1.0 + np.arange(3 * n, dtype=np.float64).reshape(n, 3) / (3 * n))
    coef[0] = 10.0 * (1.0 + np.arange(3) / 3.0)  # keeps the radiance positive (the shader clamps at 0)
    c = np.broadcast_to(coef[:, None, None, :], (n, 8, 16, 3)).astype(np.float32)
    shrm = SHRM(F=4, P=P, coeffs=np.ascontiguousarray(c))
    sphere, geom = atlas_sphere
    with SHRMRenderer(40, 40) as r:
        r.add_object(sphere, shrm, mode="perpixel")
        res = r.render(ATLAS_CAMERA)
    m = geom.hit & (res.alpha > 0.5)
    assert m.sum() > 300
    want = real_sph_harm(P, geom.V[m]) @ coef
    np.testing.assert_allclose(res.radiance[m], want, rtol=2e-4, atol=1e-4)



def test_stray_vertices_do_not_change_closed_outward() -> None:
    sphere = load_mesh("builtin:sphere")
    stray = make_mesh(np.vstack([sphere.vertices[:1] * 0.0, sphere.vertices]), sphere.faces + 1, normalize=False)
    assert closed_outward(stray) and closed_outward(sphere)
