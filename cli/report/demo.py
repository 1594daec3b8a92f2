"""The ``shrm demo`` pipeline on built-in data only.

1. Two analytic materials (Lafortune lobes: a red plastic and a gold-like metal) are
   tabulated at MERL resolution and written as MERL ``.binary`` files
   (``brdf_io.merl.write_merl``) — from then on they are measured data like any other;
2. orders (F, P) of the plastic at the default ε ([RH02] §5.1);
3. a one-lobe Lafortune fit of the plastic, written as a fit JSON (``data_specs/fit_json.md``);
4. the SHRM of the built-in studio environment and the plastic, saved as ``.shrm.npz``;
5. a preview render of a built-in mesh (torus knot with OpenGL; the CPU reference renders
   a sphere when no offscreen OpenGL context exists);
6. reports on both materials with the summary table (``batch.run_batch``, quick profile);
   each ``report.html`` holds a live WebGL2 preview of the SHRM that works from ``file://``
   (``explorer.live_views``) and BRDF Explorer's views of the table next to its fits.

Reference: [RH02] (``data_specs/bibliography.md``).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ...analysis.fit import fit_brdf, write_fit_json
from ...analysis.orders import choose_orders
from ...analysis.shrm import prefilter
from ...analysis.tolerance import DEFAULT_EPS
from ...brdf_io.envmap import load_env
from ...brdf_io.merl import write_merl
from ...brdf_io.specs import load_brdf
from ...render.camera import Camera
from ...render.mesh import load_mesh
from ...render.output import to_8bit, write_png
from ...render.pipeline import render_frames
from ...render.preview import PREVIEW_VIEW, cpu_sphere_image, preview_exposure, resolve_preview_mode, unit_mesh
from .batch import run_batch
from .options import profile

__all__ = ["DEMO_MATERIALS", "DEMO_ENV", "DEMO_MESH", "DemoStep", "run_demo"]

#: name -> analytic spec tabulated into the demo's MERL files
DEMO_MATERIALS = {
    "red-plastic": "lafortune:kd=0.45/0.07/0.05,cxy=-1,cz=1,n=60,ks=3",
    "gold-metal": "lafortune:kd=0.02/0.015/0.005,cxy=-1,cz=1,n=300,ks=36/26/10",
}
DEMO_ENV = "builtin:studio"
DEMO_MESH = "builtin:torus-knot"
DEMO_EPS = DEFAULT_EPS


@dataclass(frozen=True)
class DemoStep:
    """One finished step: what it did, the files it wrote and the numbers worth printing."""

    step: str
    paths: tuple[Path, ...]
    detail: str
    seconds: float
    info: dict[str, Any] = field(default_factory=dict)


def _render_preview(shrm: Any, env: Any, path: Path, size: int) -> str:
    """Render the demo mesh with OpenGL, or the sphere with the CPU reference; returns a note."""

    mode, note = resolve_preview_mode("auto")
    exposure = preview_exposure(env)
    if mode == "gl":
        mesh = unit_mesh(load_mesh(DEMO_MESH))
        camera = Camera.looking_at(view=np.array(PREVIEW_VIEW), up=(0.0, 0.0, 1.0), margin=1.05)
        frames, timings = render_frames(mesh, shrm, [camera], size=size, mode="distant", env_radiance=env.radiance,
                                        background="env", fps_frames=0)
        write_png(path, to_8bit(frames[0].linear, exposure=exposure))
        return f"{DEMO_MESH}, OpenGL ({timings.backend}), {size}x{size}"
    write_png(path, to_8bit(cpu_sphere_image(shrm, env, size), exposure=exposure))
    return f"sphere, CPU reference renderer, {size}x{size} ({note})"


def run_demo(out_dir: str | Path = "shrm-demo", *, progress: Callable[[str], None] | None = None,
             report_progress: Callable[[str, str, str], None] | None = None,
             size: int = 384) -> list[DemoStep]:
    """Run the demo into ``out_dir`` (see module docstring); returns the steps in order."""

    out = Path(out_dir)
    steps: list[DemoStep] = []

    def begin(name: str) -> float:
        if progress is not None:
            progress(name)
        return time.perf_counter()

    t = begin("tabulate built-in materials as MERL files")
    files = []
    for name, spec in DEMO_MATERIALS.items():
        files.append(write_merl(out / "brdfs" / f"{name}.binary", load_brdf(spec)))
    steps.append(DemoStep("MERL files", tuple(files), "analytic Lafortune materials tabulated at 90x90x180",
                          time.perf_counter() - t))
    plastic = files[0]

    t = begin("orders")
    brdf = load_brdf(plastic)
    orders = choose_orders(brdf, eps=DEMO_EPS)
    steps.append(DemoStep("orders", (plastic,), f"{plastic.stem}: F={orders.F}, P={orders.P} at eps {DEMO_EPS:g} "
                          f"(eps(F,P)={orders.eps:.3g})", time.perf_counter() - t,
                          {"F": orders.F, "P": orders.P}))

    t = begin("fit")
    fit = fit_brdf(brdf, "lafortune", n_samples=4096, starts=1, seed=0)
    fit_path = write_fit_json(out / "fits" / f"{plastic.stem}.fit.json", fit, source=str(plastic))
    steps.append(DemoStep("fit", (fit_path,), f"lafortune: rel_rms={fit.errors['rel_rms']:.3g}, {fit.status}",
                          time.perf_counter() - t, {"rel_rms": fit.errors["rel_rms"]}))

    t = begin("prefilter")
    env = load_env(DEMO_ENV, height=128)
    shrm = prefilter(env, brdf, eps=DEMO_EPS)
    shrm_path = shrm.save(out / "shrm" / f"{plastic.stem}.shrm.npz")
    seconds = shrm.info.timings.total or 0.0  # prefilter always times its total
    steps.append(DemoStep("prefilter", (shrm_path,), f"SHRM F={shrm.F}, P={shrm.P}, {shrm.height}x{shrm.width}, "
                          f"{seconds * 1e3:.0f} ms", time.perf_counter() - t,
                          {"F": shrm.F, "P": shrm.P, "height": shrm.height, "width": shrm.width,
                           "prefilter_seconds": seconds}))

    t = begin("render")
    png = out / "render" / f"{plastic.stem}.png"
    note = _render_preview(shrm, env, png, size)
    steps.append(DemoStep("render", (png,), note, time.perf_counter() - t))

    t = begin("reports")
    options = profile("quick", envs=(DEMO_ENV,), models=("lafortune", "cook-torrance"))
    result = run_batch([str(f) for f in files], out / "report", options, progress=report_progress)
    report_paths = tuple(result.out_dir / r["name"] / "report.html" for r in result.rows if r["status"] == "ok")
    steps.append(DemoStep("reports", (*report_paths, result.out_dir / "index.html", result.out_dir / "summary.csv"),
                          f"{len(result.rows) - result.n_failed} of {len(result.rows)} reports",
                          time.perf_counter() - t, {"n_failed": result.n_failed}))
    return steps
