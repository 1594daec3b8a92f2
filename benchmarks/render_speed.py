"""Rendering speed of the SHRM shader: frames per second and where a frame's time goes.

Measures, on whatever OpenGL the machine offers (Mesa llvmpipe on a CPU-only machine), for
the ``distant`` and ``perpixel`` modes at 512² (and 1024²), for a ~100k- (and a
1M-) triangle torus knot; ``perpixel`` twice in the same run: as the renderer draws it by
default — deferred on a CPU rasterizer (a geometry pass writing R, then each covered pixel
shaded once, ``SHRMRenderer`` docstring), forward on a GPU — and by the other path:
``pp-fwd`` (``SHRMRenderer(deferred=False)``: every rasterized fragment shaded) or ``pp-def``
(``deferred=True``). The OpenGL renderer string is printed first.

- **fps**: frames per second while orbiting the camera (draw only, no readback, one
  glFinish at the end; every frame moves the camera, so distant-mode maps are recomputed
  and uploaded each frame), the best of ``--rounds`` runs, and ``cpu``, the process's CPU
  time per frame over all its threads in that run (insensitive to other load: on an idle
  2-core machine fps ≤ 2000 / cpu);
- **what each frame spends** (milliseconds, each frame synchronized with glFinish, the
  minimum over rounds): ``py`` the Python/VTK work of ``draw`` before VTK's first Render starts
  (camera, uniforms, culling decision), without the map; ``map`` the distant-mode map
  Σ B̃_pq Y^r_pq(Ṽ) evaluated on the CPU ([RH02] eq. 12, ``data_specs/bibliography.md``); ``upload`` its
  texture upload (GL time of frames with the map
  updated minus frames without); ``gl`` the first Render() through glFinish with nothing
  updated (the GL draw itself; both passes when deferred);
- **floors** measured in the same run: ``empty`` an empty frame (clear, VTK's traversal,
  framebuffer blit); ``geom`` the same mesh drawn with a constant-colour shader, back faces
  culled (vertex work, triangle set-up and rasterization: what no shader change can
  remove); ``shade1`` the mode's forward shader on a full-screen quad minus ``empty``, i.e. shading
  every pixel exactly once, scaled to the mesh's coverage ``cov`` (the shading a frame would
  cost if each covered pixel were shaded once);
- **ratios**: ``over`` = (gl − geom) / shade1, how many times the shader runs per covered
  pixel (llvmpipe shades whole 4×4 blocks of each small triangle, plus overdraw), and
  ``fps/30``.

Also the per-frame cost of the distant-mode map at P = 3 on a lat-long grid of 111 × 222
texels (≈ the 24 576 texels of a 6 × 64² cube): CPU evaluation alone, and evaluation +
upload on a small window.

Targets (issue 15): ≥ 30 fps in ``perpixel`` at 512² for 100k triangles on 2 CPU cores with
Mesa llvmpipe; ≥ 1000 fps on a GPU; map update ≤ 2 ms.

llvmpipe rasterizes with ``LP_NUM_THREADS`` threads (default: the number of online CPUs);
the vertex work and triangle binning run on the calling thread.

Usage: ``.venv/bin/python benchmarks/render_speed.py [--quick] [--frames N] [--rounds N]``
(``--quick``: 512², 100k triangles only, under a minute on 2 cores).
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

from shrmkit.analysis.sh import real_sph_harm
from shrmkit.analysis.shrm import SHRM
from shrmkit.brdf_io.latlong import pixel_directions
from shrmkit.render.camera import Camera, orbit_camera
from shrmkit.render.mesh import Mesh, load_mesh, make_mesh
from shrmkit.render.offscreen import gl_renderer, is_software_rasterizer, make_render_window
from shrmkit.render.vtk_renderer import SHRMRenderer

MESHES = {
    "100k": "builtin:torus-knot:segments=1024,sides=49",
    "1M": "builtin:torus-knot:segments=4000,sides=125",
}
#: (label, mode, deferred): each mode as the renderer draws it by default (deferred on a CPU
#: rasterizer, forward on a GPU), then the other per-pixel path (``pp-fwd`` or ``pp-def``)
MODES = (("distant", "distant", None), ("perpixel", "perpixel", None))
TARGET_FPS = 30.0


def synthetic_shrm(P: int, H: int, W: int) -> SHRM:
    """Smooth synthetic SHRM (speed does not depend on the values)."""
    rng = np.random.default_rng(0)
    basis = real_sph_harm(4, pixel_directions(H, W))
    c = np.einsum("hwk,nkc->nhwc", basis, rng.normal(size=((P + 1) ** 2, 25, 3))).astype(np.float32)
    return SHRM(F=4, P=P, coeffs=c)


def full_screen_quad() -> tuple[Mesh, Camera]:
    """Two triangles covering the whole image of an ortho camera, normals varying across them."""
    v = np.array([[0.0, -2.0, -2.0], [0.0, 2.0, -2.0], [0.0, 2.0, 2.0], [0.0, -2.0, 2.0]])
    n = np.array([[1.0, -0.5, -0.5], [1.0, 0.5, -0.5], [1.0, 0.5, 0.5], [1.0, -0.5, 0.5]])
    quad = make_mesh(v, np.array([[0, 1, 2], [0, 2, 3]]), n, normalize=False)
    return quad, Camera.looking_at(view=(-1.0, 0.0, 0.0), projection="ortho")


def gl_info() -> str:
    """The OpenGL renderer string and the llvmpipe thread setting."""
    window = make_render_window(8, 8)
    caps = window.ReportCapabilities()
    window.Finalize()
    renderer = next((line.split(":", 1)[1].strip() for line in caps.splitlines()
                     if line.startswith("OpenGL renderer string")), "unknown")
    cpus = len(os.sched_getaffinity(0))
    threads = os.environ.get("LP_NUM_THREADS", f"unset (llvmpipe default: {os.cpu_count()} online CPUs)")
    return f"OpenGL renderer: {renderer}; CPUs available: {cpus}; LP_NUM_THREADS: {threads}"


class _RenderClock:
    """Time of the first VTK Render start (StartEvent) of a frame (a deferred frame renders twice)."""

    def __init__(self, window) -> None:
        self.start: float | None = None
        window.AddObserver("StartEvent", self._on_start)

    def reset(self) -> None:
        """Forget the last frame's start."""
        self.start = None

    def _on_start(self, *_: object) -> None:
        if self.start is None:
            self.start = time.perf_counter()


def frame_costs(r: SHRMRenderer, cameras: list[Camera], rounds: int) -> dict[str, float]:
    """Per-frame ms, each frame synchronized with glFinish, minimum over ``rounds``:
    py (draw before Render, map excluded), map (CPU map), upload, gl (Render → glFinish)."""
    clock = _RenderClock(r.render_window)
    best = {"py": np.inf, "map": np.inf, "gl_update": np.inf, "gl": np.inf}
    for _ in range(rounds):
        for update in (True, False):  # interleaved so that load changes hit both alike
            py = gl = 0.0
            for cam in cameras:
                r.finish()
                clock.reset()
                t0 = time.perf_counter()
                r.draw(cam, update_maps=update)
                r.finish()
                t1 = time.perf_counter()
                py += clock.start - t0
                gl += t1 - clock.start
            key = "gl_update" if update else "gl"
            best[key] = min(best[key], gl / len(cameras))
            if not update:
                best["py"] = min(best["py"], py / len(cameras))
        t0 = time.perf_counter()
        for cam in cameras:
            r.update_view_maps(cam)
        best["map"] = min(best["map"], (time.perf_counter() - t0) / len(cameras))
    ms = {key: 1e3 * value for key, value in best.items()}
    ms["upload"] = max(ms.pop("gl_update") - ms["gl"], 0.0)
    return ms


def _window_frame_ms(window, n: int, rounds: int) -> float:
    """Milliseconds of one Render + glFinish of ``window`` (best of ``rounds`` runs of ``n``, after
    one warm-up frame); the window is finalized."""
    window.Render()
    window.WaitForCompletion()
    best = np.inf
    for _ in range(rounds):
        t0 = time.perf_counter()
        for _ in range(n):
            window.Render()
            window.WaitForCompletion()
        best = min(best, (time.perf_counter() - t0) / n)
    window.Finalize()
    return 1e3 * best


def empty_frame_ms(size: int, n: int, rounds: int) -> float:
    """An empty frame: clear, VTK's traversal and the framebuffer blit, with glFinish."""
    return _window_frame_ms(make_render_window(size, size), n, rounds)


def geometry_floor_ms(mesh: Mesh, camera: Camera, size: int, n: int, rounds: int) -> float:
    """``mesh`` drawn with a constant-colour fragment shader, back faces culled, with glFinish."""
    from vtkmodules.util.numpy_support import numpy_to_vtk, numpy_to_vtkIdTypeArray  # lazy: VTK
    from vtkmodules.vtkCommonCore import vtkPoints  # lazy: VTK
    from vtkmodules.vtkCommonDataModel import vtkCellArray, vtkPolyData  # lazy: VTK
    from vtkmodules.vtkRenderingCore import vtkActor  # lazy: VTK
    from vtkmodules.vtkRenderingOpenGL2 import vtkOpenGLPolyDataMapper  # lazy: VTK

    window = make_render_window(size, size)
    pts = vtkPoints()
    pts.SetData(numpy_to_vtk(np.ascontiguousarray(mesh.vertices, dtype=np.float32), deep=1))
    cells = vtkCellArray()
    cells.SetData(numpy_to_vtkIdTypeArray(np.arange(0, 3 * mesh.n_triangles + 1, 3, dtype=np.int64), deep=1),
                  numpy_to_vtkIdTypeArray(np.ascontiguousarray(mesh.faces.reshape(-1), dtype=np.int64), deep=1))
    poly = vtkPolyData()
    poly.SetPoints(pts)
    poly.SetPolys(cells)
    mapper = vtkOpenGLPolyDataMapper()
    mapper.SetInputData(poly)
    actor = vtkActor()
    actor.SetMapper(mapper)
    actor.GetProperty().BackfaceCullingOn()
    actor.GetShaderProperty().AddFragmentShaderReplacement(
        "//VTK::Light::Impl", True, "  gl_FragData[0] = vec4(1.0);\n", False)
    renderer = window.GetRenderers().GetFirstRenderer()
    renderer.AddActor(actor)
    camera.apply_to(renderer.GetActiveCamera(), (0.5, 10.0))
    return _window_frame_ms(window, n, rounds)


def quad_ms(shrm: SHRM, mode: str, size: int, n: int, rounds: int) -> float:
    """The mode's forward shader on every pixel once (full-screen quad), with glFinish."""
    quad, cam = full_screen_quad()
    with SHRMRenderer(size, size, deferred=False) as r:
        r.add_object(quad, shrm, mode=mode)
        best = np.inf
        for _ in range(rounds):
            r.draw(cam)
            r.finish()
            t0 = time.perf_counter()
            for _ in range(n):
                r.render_window.Render()
                r.finish()
            best = min(best, (time.perf_counter() - t0) / n)
    return 1e3 * best


def map_update_line(shrm: SHRM, base: Camera) -> str:
    """CPU evaluation and evaluation + upload of the distant map on a 64² window (RH02 eq. 12)."""
    mesh = load_mesh("builtin:sphere:subdivisions=4")
    with SHRMRenderer(64, 64) as r:
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
    return (f"dynamic map P=3, 111x222 texels: CPU evaluation {1e3 * t_cpu:.2f} ms, "
            f"evaluation + upload {1e3 * (times[True] - times[False]):.2f} ms per frame (target <= 2 ms)")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="only 512², 100k triangles")
    ap.add_argument("--frames", type=int, default=20, help="frames per fps measurement")
    ap.add_argument("--rounds", type=int, default=3, help="rounds of the per-frame costs (minimum kept)")
    args = ap.parse_args(argv)
    shrm = synthetic_shrm(P=3, H=111, W=222)
    base = Camera.looking_at(view=(1.0, 0.3, 0.4))
    print(gl_info())
    print(f"load average at start: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    print(map_update_line(shrm, base))

    sizes = (512,) if args.quick else (512, 1024)
    meshes = {"100k": MESHES["100k"]} if args.quick else MESHES
    n_cost = max(4, args.frames // 2)
    cameras = [orbit_camera(base, np.zeros(3), 2.0 * np.pi * k / n_cost) for k in range(n_cost)]
    head = (f"{'mesh':>4} {'size':>4} {'mode':>8} {'fps':>6} {'fps/30':>6} {'cpu':>5} | {'py':>5} {'map':>5} "
            f"{'upload':>6} {'gl':>6} | {'empty':>5} {'geom':>5} {'shade1':>6} {'cov':>5} {'over':>5}")
    print("per-frame ms (each frame glFinish-synchronized, min over rounds); floors measured in this run")
    print(head)
    rows = []
    with SHRMRenderer(8, 8) as probe:
        software = is_software_rasterizer(probe.render_window)
        print(f"OpenGL renderer: {gl_renderer(probe.render_window)} (per-pixel modes drawn "
              f"{'deferred' if software else 'forward'} by default)")
    modes = (*MODES, ("pp-fwd", "perpixel", False) if software else ("pp-def", "perpixel", True))
    for label, spec in meshes.items():
        mesh = load_mesh(spec)
        for size in sizes:
            empty = empty_frame_ms(size, args.frames, args.rounds)
            geom = geometry_floor_ms(mesh, base, size, args.frames // 2, args.rounds)
            for name, mode, deferred in modes:
                with SHRMRenderer(size, size, deferred=deferred) as r:
                    r.add_object(mesh, shrm, mode=mode)
                    cov = float(r.render(base).alpha.mean())
                    fps, cpu = 0.0, np.inf
                    for _ in range(args.rounds):
                        c0 = sum(os.times()[:2])
                        f = r.frames_per_second(base, args.frames)
                        if f > fps:
                            fps, cpu = f, 1e3 * (sum(os.times()[:2]) - c0) / (args.frames + 1)
                    cost = frame_costs(r, cameras, args.rounds)
                if mode != "distant":
                    cost["map"] = cost["upload"] = 0.0  # no per-frame map in this mode
                shade1 = max(quad_ms(shrm, mode, size, args.frames // 2, args.rounds) - empty, 0.0) * cov
                over = (cost["gl"] - geom) / shade1 if shade1 > 0 else float("nan")
                rows.append((label, size, name, fps, cpu, cost, geom, shade1, over))
                print(f"{label:>4} {size:>4} {name:>8} {fps:>6.1f} {fps / TARGET_FPS:>6.2f} {cpu:>5.1f} | "
                      f"{cost['py']:>5.2f} {cost['map']:>5.2f} {cost['upload']:>6.2f} {cost['gl']:>6.1f} | "
                      f"{empty:>5.1f} {geom:>5.1f} {shade1:>6.1f} {cov:>5.2f} {over:>5.1f}", flush=True)
    print("ratios (this run):")
    for label, size, mode, fps, cpu, cost, geom, shade1, over in rows:
        frame = cost["py"] + cost["map"] + cost["upload"] + cost["gl"]
        once = geom + shade1  # each covered pixel shaded once on top of the geometry floor
        print(f"  {label} {size} {mode}: frame {frame:.1f} ms = non-drawing {cost['py'] + cost['map']:.2f} ms "
              f"({100 * (cost['py'] + cost['map']) / frame:.1f} %) + upload {cost['upload']:.2f} ms + GL "
              f"{cost['gl']:.1f} ms [geometry floor {geom:.1f} ms ({100 * geom / cost['gl']:.0f} %), shading "
              f"{cost['gl'] - geom:.1f} ms = {over:.1f} x once-per-pixel {shade1:.1f} ms]; fps {fps:.1f} = "
              f"{fps / TARGET_FPS:.2f} x {TARGET_FPS:.0f}; idle 2-core bound 2000/cpu = {2000 / cpu:.0f} fps; "
              f"once-per-pixel shading would give {1e3 / once:.0f} fps")
    print(f"load average at end: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
