"""Deferred per-pixel shading (``vtk_renderer.SHRMRenderer`` docstring) changes no image.

The deferred path (a geometry pass writing R · 2^(k+1), then one screen quad per object shading
each covered pixel once) against
- the forward path of the same renderer (``SHRMRenderer(deferred=False)``): identical coverage,
  radiance equal to float rounding (V is recomputed from the quad's point on the same pixel ray),
  for a closed mesh (back faces culled) under perspective and ortho, a camera inside a sphere,
  an open mesh whose inside shows through a hole, two overlapping objects with their own SHRMs
  (depth between them, tags kept apart), ``kautz-mccool``, and a sequence of cameras in one renderer;
- the numpy ray caster ``render.cpu_reference`` (Möller–Trumbore + ``SHRM.radiance``, RH02 eq. 8;
  RH02 = Ramamoorthi & Hanrahan 2002, doi:10.1145/566654.566611) for the open mesh and the two objects.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from shrmkit.analysis.sh import real_sph_harm
from shrmkit.analysis.shrm import SHRM
from shrmkit.brdf_io.latlong import pixel_directions
from shrmkit.render.camera import Camera, orbit_camera
from shrmkit.render.cpu_reference import mesh_geometry, shade
from shrmkit.render.mesh import Mesh, load_mesh, make_mesh
from shrmkit.render.vtk_renderer import SHRMRenderer, closed_outward

pytestmark = pytest.mark.render


def _smooth_shrm(P: int, seed: int, H: int = 32, W: int = 64) -> SHRM:
    """A smooth random SHRM (low-order SH in R per coefficient map), radiance kept positive."""
    rng = np.random.default_rng(seed)
    basis = real_sph_harm(3, pixel_directions(H, W))
    c = np.einsum("hwk,nkc->nhwc", basis, rng.normal(size=((P + 1) ** 2, 16, 3))).astype(np.float32)
    c[0] += 3.0
    return SHRM(F=3, P=P, coeffs=c)


def _combined(*meshes: Mesh) -> Mesh:
    """One mesh holding all of ``meshes`` (for the CPU ray caster); faces keep their order."""
    v, f, n, base = [], [], [], 0
    for m in meshes:
        v.append(m.vertices)
        f.append(m.faces + base)
        n.append(m.normals)
        base += len(m.vertices)
    return make_mesh(np.vstack(v), np.vstack(f), np.vstack(n), normalize=False)


def _open_sphere() -> Mesh:
    """A sphere without the faces around +x: open, its inside visible through the hole."""
    sphere = load_mesh("builtin:sphere:subdivisions=4")
    centroid = sphere.vertices[sphere.faces].mean(axis=1)
    keep = centroid[:, 0] < 0.6
    return make_mesh(sphere.vertices, sphere.faces[keep], sphere.normals, normalize=False)


def _render_both(objects, cameras, size=(64, 48)):
    """Forward and deferred images of ``objects`` [(mesh, shrm, mode)] for each camera."""
    out = {}
    for deferred in (False, True):
        with SHRMRenderer(*size, deferred=deferred) as r:
            for mesh, shrm, mode in objects:
                r.add_object(mesh, shrm, mode=mode)
            assert r.deferred == deferred
            out[deferred] = [r.render(cam) for cam in cameras]
    return out


def _assert_same(forward, deferred) -> None:
    np.testing.assert_array_equal(deferred.alpha, forward.alpha)
    scale = float(np.abs(forward.radiance).max())
    np.testing.assert_allclose(deferred.radiance, forward.radiance, rtol=0.0, atol=2e-5 * scale)
    assert np.all(deferred.radiance[deferred.alpha == 0.0] == 0.0)


@pytest.mark.parametrize("mode", ["perpixel", "kautz-mccool"])
def test_deferred_equals_forward_for_a_closed_mesh(offscreen, mode) -> None:
    """A torus knot (closed: back faces culled) under perspective and ortho cameras, several in
    one renderer (the quad and culling follow the camera)."""
    mesh = load_mesh("builtin:torus-knot:segments=128,sides=12")
    assert closed_outward(mesh)
    base = Camera.looking_at(view=(1.0, 0.3, 0.5))
    cams = [base, orbit_camera(base, np.zeros(3), 2.0), Camera.looking_at(view=(0.2, -1.0, 0.3), projection="ortho"),
            base]
    images = _render_both([(mesh, _smooth_shrm(2, 1), mode)], cams)
    for fwd, dfr in zip(images[False], images[True], strict=True):
        assert fwd.alpha.sum() > 400
        _assert_same(fwd, dfr)


def test_deferred_equals_forward_from_inside_a_sphere(offscreen) -> None:
    """Camera at the centre of a closed sphere: every pixel sees back faces (normals flipped)."""
    sphere = load_mesh("builtin:sphere:subdivisions=4")
    outside = Camera.looking_at(view=(1.0, 0.2, 0.3))
    inside = Camera(np.zeros(3), outside.forward, outside.right, outside.up, fov_y=np.deg2rad(60.0))
    images = _render_both([(sphere, _smooth_shrm(1, 2), "perpixel")], [inside, outside, inside])
    assert np.all(images[True][0].alpha == 1.0)
    for fwd, dfr in zip(images[False], images[True], strict=True):
        _assert_same(fwd, dfr)


def test_deferred_open_mesh_against_forward_and_cpu(offscreen) -> None:
    """An open sphere seen through its hole: front faces of the far side's inside are back faces."""
    mesh = _open_sphere()
    assert not closed_outward(mesh)
    shrm = _smooth_shrm(2, 3)
    cam = Camera.looking_at(view=(1.0, 0.25, 0.2), projection="perspective")
    images = _render_both([(mesh, shrm, "perpixel")], [cam])
    fwd, dfr = images[False][0], images[True][0]
    _assert_same(fwd, dfr)
    geom = mesh_geometry(cam, 64, 48, mesh)
    assert np.sum(geom.hit & (geom.position @ cam.eye < 0.0)) > 100  # the far side's inside, through the hole
    cover = dfr.alpha > 0.5
    assert np.sum(geom.hit != cover) <= 0.02 * geom.hit.sum()
    m = geom.hit & cover
    ref = shade(geom, shrm.radiance)[m]
    # relative to the image's largest radiance (the clamp at 0 leaves some pixels black)
    err = np.linalg.norm(dfr.radiance[m] - ref, axis=-1) / np.linalg.norm(ref, axis=-1).max()
    assert np.mean(err < 1e-3) > 0.97  # a few pixels see another surface at depth edges


def test_deferred_overlapping_objects_against_forward_and_cpu(offscreen) -> None:
    """Three spheres with their own SHRMs (tags 2, 4, 8), the nearer ones hiding parts of the
    others: each pixel gets the nearest object's shading, as forward and as the ray caster."""
    sphere = load_mesh("builtin:sphere:subdivisions=3")
    meshes = [sphere.transformed(scale=0.6, translate=(0.0, 0.0, 0.0)),
              sphere.transformed(scale=0.45, translate=(0.45, -0.5, 0.1)),
              sphere.transformed(scale=0.3, translate=(-0.3, -0.6, -0.2))]
    shrms = [_smooth_shrm(1, 10), _smooth_shrm(2, 11), _smooth_shrm(1, 12)]
    cam = Camera.looking_at(view=(0.1, -1.0, 0.2), projection="perspective", radius=1.0)
    images = _render_both([(m, s, "perpixel") for m, s in zip(meshes, shrms, strict=True)], [cam], size=(64, 64))
    fwd, dfr = images[False][0], images[True][0]
    _assert_same(fwd, dfr)
    geom = mesh_geometry(cam, 64, 64, _combined(*meshes))
    owner = np.searchsorted(np.cumsum([len(m.faces) for m in meshes]), np.where(geom.hit, geom.face, 0), side="right")
    cover = dfr.alpha > 0.5
    assert np.sum(geom.hit != cover) <= 0.02 * geom.hit.sum()
    m = geom.hit & cover
    assert all(np.sum(m & (owner == k)) > 50 for k in range(3))
    ref = np.zeros_like(dfr.radiance)
    for k, s in enumerate(shrms):
        ref[owner == k] = shade(geom, s.radiance)[owner == k]
    err = np.linalg.norm(dfr.radiance[m] - ref[m], axis=-1) / np.linalg.norm(ref[m], axis=-1).max()
    # pixel centres on a silhouette in front of another object may hit either one
    assert np.mean(err < 1e-3) > 0.95 and np.median(err) < 1e-5


def test_mixed_modes_draw_forward(offscreen) -> None:
    """A scene with a distant-mode object is drawn forward (its shading needs no deferral)."""
    sphere = load_mesh("builtin:sphere:subdivisions=2")
    with SHRMRenderer(16, 16, deferred=True) as r:
        r.add_object(sphere.transformed(scale=0.4, translate=(-0.5, 0, 0)), _smooth_shrm(1, 4), mode="perpixel")
        assert r.deferred
        r.add_object(sphere.transformed(scale=0.4, translate=(0.5, 0, 0)), _smooth_shrm(1, 5), mode="distant")
        assert not r.deferred
        assert r.render(Camera.looking_at(view=(0, -1, 0))).alpha.sum() > 20


def test_default_defers_on_cpu_rasterizers_only(offscreen) -> None:
    """deferred=None (the default) follows the OpenGL renderer: deferred on a CPU rasterizer
    (llvmpipe here, SwiftShader…), forward on a GPU; the renderer string is read from VTK."""
    from shrmkit.render.offscreen import SOFTWARE_RASTERIZERS, gl_renderer, is_software_rasterizer

    sphere = load_mesh("builtin:sphere:subdivisions=2")
    with SHRMRenderer(16, 16) as r:
        name = gl_renderer(r.render_window)
        assert name  # VTK reports a renderer string
        software = any(s in name.lower() for s in SOFTWARE_RASTERIZERS)
        assert is_software_rasterizer(r.render_window) == software
        r.add_object(sphere.transformed(scale=0.4), _smooth_shrm(1, 4), mode="perpixel")
        assert r.deferred == software


def test_the_most_objects_a_deferred_frame_tags_are_all_drawn(offscreen) -> None:
    """MAX_DEFERRED_OBJECTS spheres (tags up to 2^64): every one is drawn deferred, with the
    forward path's coverage (|R·2^64|² would overflow float32 if the tag were measured first)."""
    from shrmkit.render.vtk_renderer import MAX_DEFERRED_OBJECTS

    sphere = load_mesh("builtin:sphere:subdivisions=1")
    side = int(np.ceil(np.sqrt(MAX_DEFERRED_OBJECTS)))
    shrm = _smooth_shrm(1, 7, H=8, W=16)
    objects = []
    for k in range(MAX_DEFERRED_OBJECTS):
        row, col = divmod(k, side)
        centre = (2.2 * (col - (side - 1) / 2) / side, 0.0, 2.2 * (row - (side - 1) / 2) / side)
        objects.append((sphere.transformed(scale=0.9 / side, translate=centre), shrm, "perpixel"))
    camera = Camera.looking_at(view=(0, -1, 0), radius=1.15, projection="ortho")
    images = _render_both(objects, [camera], size=(160, 160))
    _assert_same(images[False][0], images[True][0])
    # every sphere is drawn, the last one (tag 2^64) included: 64 separate blobs
    _, blobs = ndimage.label(images[True][0].alpha > 0)
    assert blobs == MAX_DEFERRED_OBJECTS
