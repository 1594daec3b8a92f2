"""Rendering speed of the SHRM shader: frames per second and the dynamic-map update cost.

Measures, on whatever OpenGL the machine offers (Mesa llvmpipe on a CPU-only machine):

- frames per second in ``distant`` and ``perpixel`` modes at 512² and 1024², for a
  ~100k- and a 1M-triangle torus knot (draw only, no readback; every frame moves the
  camera, so distant-mode maps are recomputed and uploaded each frame);
- the per-frame cost of the distant-mode map Σ B̃_pq Y^r_pq(Ṽ) (RH02 eq. 12; RH02 =
  Ramamoorthi & Hanrahan 2002, doi:10.1145/566654.566611) at P = 3 on a lat-long grid of
  111 × 222 texels (≈ the 24 576 texels of a 6 × 64² cube): CPU evaluation alone, and
  evaluation + texture upload (difference of frame times with and without the update).

Targets: ≥ 10 fps at 512² for 100k triangles; map update ≤ 2 ms.

Usage: ``.venv/bin/python benchmarks/render_speed.py [--quick] [--frames N]``
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from shrmkit.analysis.sh import real_sph_harm
from shrmkit.analysis.shrm import SHRM
from shrmkit.brdf_io.latlong import pixel_directions
from shrmkit.render.camera import Camera, orbit_camera
from shrmkit.render.mesh import load_mesh
from shrmkit.render.vtk_renderer import SHRMRenderer

MESHES = {
    "100k": "builtin:torus-knot:segments=1024,sides=49",
    "1M": "builtin:torus-knot:segments=4000,sides=125",
}


def synthetic_shrm(P: int, H: int, W: int) -> SHRM:
    """Smooth synthetic SHRM (speed does not depend on the values)."""
    rng = np.random.default_rng(0)
    basis = real_sph_harm(4, pixel_directions(H, W))
    c = np.einsum("hwk,nkc->nhwc", basis, rng.normal(size=((P + 1) ** 2, 25, 3))).astype(np.float32)
    return SHRM(F=4, P=P, coeffs=c)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="only 512², 100k triangles")
    ap.add_argument("--frames", type=int, default=20)
    args = ap.parse_args(argv)
    shrm = synthetic_shrm(P=3, H=111, W=222)
    base = Camera.looking_at(view=(1.0, 0.3, 0.4))

    # dynamic-map update cost (RH02 eq. 12)
    mesh = load_mesh("builtin:sphere:subdivisions=4")
    with SHRMRenderer(64, 64) as r:
        print(f"OpenGL back end: {r.backend}")
        r.add_object(mesh, shrm, mode="distant")
        r.draw(base)
        n = 200
        cameras = [orbit_camera(base, np.zeros(3), 0.01 * k) for k in range(n)]  # not part of the cost
        t0 = time.perf_counter()
        for cam in cameras:
            r.update_view_maps(cam)
        t_cpu = (time.perf_counter() - t0) / n
        times = {}
        for update in (True, False):
            r.finish()
            t0 = time.perf_counter()
            for cam in cameras:
                r.draw(cam, update_maps=update)
            r.finish()
            times[update] = (time.perf_counter() - t0) / n
    print(f"dynamic map P=3, 111x222 texels: CPU evaluation {1e3 * t_cpu:.2f} ms, "
          f"evaluation + upload {1e3 * (times[True] - times[False]):.2f} ms per frame (target <= 2 ms)")

    sizes = (512,) if args.quick else (512, 1024)
    meshes = {"100k": MESHES["100k"]} if args.quick else MESHES
    print(f"{'mesh':>5} {'triangles':>9} {'size':>5} {'mode':>9} {'first frame s':>13} {'fps':>6}")
    for label, spec in meshes.items():
        mesh = load_mesh(spec)
        for size in sizes:
            for mode in ("distant", "perpixel"):
                t0 = time.perf_counter()
                with SHRMRenderer(size, size) as r:
                    r.add_object(mesh, shrm, mode=mode)
                    r.draw(base)
                    r.finish()
                    first = time.perf_counter() - t0
                    fps = r.frames_per_second(base, args.frames)
                print(f"{label:>5} {mesh.n_triangles:>9} {size:>5} {mode:>9} {first:>13.3f} {fps:>6.1f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
