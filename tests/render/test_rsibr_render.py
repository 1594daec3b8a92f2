"""Render mode ``rsibr`` (Cabral et al. 1999) in the VTK shader against the CPU.

References: at an icosahedron vertex the blended map is map i alone, i.e. RH02 eq. 12's
distant-viewer map for v_i (RH02 = Ramamoorthi & Hanrahan 2002, doi:10.1145/566654.566611),
so the GPU image equals the CPU reference (analytic ray–sphere + RSIBRMaps.radiance);
between vertices the CPU RSIBR reconstruction. The renderer takes the twelve maps, or an
SHRM that it turns into them.
"""

from __future__ import annotations

import numpy as np
import pytest

from shrmkit.analysis.baselines.icosahedron import icosahedron
from shrmkit.analysis.baselines.rsibr import rsibr_from_shrm
from shrmkit.analysis.shrm import prefilter
from shrmkit.analysis.tolerance import DEFAULT_EPS
from shrmkit.brdf_io.envmap import load_env
from shrmkit.brdf_io.specs import load_brdf
from shrmkit.render.camera import Camera
from shrmkit.render.cpu_reference import shade, sphere_geometry
from shrmkit.render.mesh import load_mesh
from shrmkit.render.vtk_renderer import SHRMRenderer

pytestmark = pytest.mark.render


@pytest.mark.parametrize(("vertex_view", "give_maps"), [(True, False), (False, False), (False, True)])
def test_rsibr_mode_matches_cpu_reconstruction(offscreen, vertex_view: bool, give_maps: bool) -> None:
    env = load_env("builtin:studio,height=16")
    shrm = prefilter(env, load_brdf("microfacet:sigma=0.3"), eps=DEFAULT_EPS)
    maps = rsibr_from_shrm(shrm)
    view = icosahedron()[0][3] if vertex_view else np.array([0.9, 0.3, 0.4])
    up = np.array([0.0, 0.0, 1.0]) if abs(view[2]) < 0.9 * np.linalg.norm(view) else np.array([1.0, 0.0, 0.0])
    cam = Camera.looking_at(view=view, up=up, projection="ortho")
    with SHRMRenderer(48, 48) as r:
        r.add_object(load_mesh("builtin:sphere:subdivisions=5"), maps if give_maps else shrm, mode="rsibr")
        res = r.render(cam)
    geom = sphere_geometry(cam, 48, 48)
    cos_v = np.sum(geom.N * geom.V, axis=-1)
    m = geom.hit & (res.alpha > 0.5) & (cos_v > np.cos(np.radians(75.0)))
    cpu = shade(geom, maps.radiance)[m]
    rms = np.sqrt(np.mean((res.radiance[m] - cpu) ** 2) / np.mean(cpu**2))
    assert rms < 0.02  # mesh faceting only
    if vertex_view:
        exact = shade(geom, lambda R, V: shrm.radiance(R, np.broadcast_to(view, R.shape)))[m]
        assert np.sqrt(np.mean((res.radiance[m] - exact) ** 2) / np.mean(exact**2)) < 0.02
