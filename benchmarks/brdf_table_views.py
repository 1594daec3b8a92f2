"""The lights' BRDF table tabulated only in the θ_d rows a render's views read (issue 22).

``render_frames`` knows its cameras (and the environment's rotation per frame): the θ_d = ½ ∠(L, V)
a lookup can reach lies, for each light sample L and camera, in [½(γ − a), ½(γ + a)] (γ the angle
of L to the axis of the camera's cone of view directions, a its half-angle;
``render._brdf_table.theta_d_ranges``), so ``choose_table(theta_d=)`` tabulates those rows (plus a
margin row each side and the texels the error pairs read) instead of the whole 91 × 91 × 181 grid.

For a measured BRDF (default: the RGL file the quick report was timed on) under ``builtin:sky``'s
sun at the quick report's 32 rows, a lights-only SHRM (the map part is black: the frame is the
lights' reflection, which the table alone makes), per case:

- ``rows``: the θ_d row runs tabulated, ``share`` the fraction of the texels tabulated;
- ``whole`` / ``views``: CPU seconds (process time) of the lights' shading with the whole table
  (as before) and with the views' rows, the minimum of ``--rounds`` interleaved runs;
- ``max|d|``: the largest absolute difference of the float frames (linear radiance, the
  ``env`` background composited) of the two renders: 0 when bit-identical;
- ``err``: whether the table's stated error (``choose_table``'s dict) is the same to the bit.

Cases: the report preview's camera (``preview_camera``, the unit sphere, ``distant``), an ortho
camera, a perspective camera close to the sphere (distance 1.3: a 50° cone), a lighting turntable
(8 ``env_rotation`` frames, one camera), a camera turntable in ``perpixel`` (4 cameras). Then the
preview stage itself (``render_previews``, 128 px, GL) with the whole table and with the views'.

Run: ``.venv/bin/python benchmarks/brdf_table_views.py [--brdf FILE] [--rounds 3]``
(needs an offscreen OpenGL context).
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np

import shrmkit
from shrmkit.analysis.lights import extract_lights
from shrmkit.analysis.shrm import SHRM
from shrmkit.brdf_io.specs import load_brdf
from shrmkit.render.camera import Camera
from shrmkit.render.mesh import load_mesh
from shrmkit.render.pipeline import light_turntable_rotations, render_frames, turntable_cameras, view_cones
from shrmkit.render.preview import PREVIEW_VIEW, preview_camera, render_previews, unit_mesh
from shrmkit.render.shader import cached_light_shading

DEFAULT_BRDF = "/work/shared/data/brdf/rgl/cc_iris_purple_gem_rgb.bsdf"


def lights_only(env, brdf) -> SHRM:
    """A fresh SHRM of ``env``'s lights alone (black maps): its own light-shading cache."""
    lights = extract_lights(env, "auto").lights
    return SHRM(F=0, P=0, coeffs=np.zeros((1, 8, 16, 3), np.float32),
                meta={"max_view_deg": 80.0, "brdf": brdf.name, "environment": env.name, "lights_requested": "auto"},
                lights=lights, brdf=brdf)


def cpu(fn):
    t = time.process_time()
    out = fn()
    return out, time.process_time() - t


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--brdf", default=DEFAULT_BRDF)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--size", type=int, default=128)
    args = parser.parse_args()
    brdf = load_brdf(args.brdf)
    env = shrmkit.load_env("builtin:sky", height=32)
    sphere = unit_mesh(load_mesh("builtin:sphere"))
    base = preview_camera()
    cases = [
        ("preview", "distant", [base], None),
        ("ortho", "distant", [Camera.looking_at(view=np.array(PREVIEW_VIEW), projection="ortho", margin=1.15)], None),
        ("close d=1.3", "distant", [Camera.looking_at(view=np.array(PREVIEW_VIEW), distance=1.3)], None),
        ("light turntable x8", "distant", [base] * 8, light_turntable_rotations(8)),
        ("camera turntable x4", "perpixel", turntable_cameras(base, 4), None),
    ]
    print(f"BRDF {brdf.name}, builtin:sky (32 rows) lights, {args.size} px, CPU s min of {args.rounds}",
          file=sys.stderr)
    print("| case | mode | grid | rows | share | whole s | views s | max abs d | err same |")
    print("|---|---|---|---|---|---|---|---|---|")
    identical = True
    for name, mode, cameras, rotations in cases:
        views = view_cones(sphere, cameras, rotations)
        times: dict[str, list[float]] = {"whole": [], "views": []}
        shadings = {}
        for _ in range(args.rounds):
            for key in ("whole", "views"):
                shrm = lights_only(env, brdf)
                wanted = None if key == "whole" else views
                shadings[key], seconds = cpu(lambda s=shrm, v=wanted: cached_light_shading(s, v))
                times[key].append(seconds)
                shadings[key, "shrm"] = shrm
        frames = {}
        for key in ("whole", "views"):  # each SHRM's cache holds its table: render_frames uses it
            frames[key], _ = render_frames(sphere, shadings[key, "shrm"], cameras, size=args.size, mode=mode,
                                           env_radiance=env.radiance, background="env", fps_frames=0,
                                           env_rotation=rotations)
        assert shadings["views"] is cached_light_shading(shadings["views", "shrm"], views)  # no other made
        diff = max(float(np.max(np.abs(a.linear - b.linear))) for a, b in zip(frames["whole"], frames["views"],
                                                                                 strict=True))
        lit = max(float(np.max(f.linear)) for f in frames["views"])
        table = shadings["views"].table
        same_err = shadings["views"].table_error == shadings["whole"].table_error
        identical &= diff == 0.0 and same_err and lit > 0
        rows = "whole" if table.rows is None else " ".join(f"{a}-{b}" for a, b in table.rows)
        print(f"| {name} | {mode} | {'x'.join(map(str, table.shape))} | {rows} | "
              f"{table.tabulated / np.prod(table.shape):.3f} | {min(times['whole']):.3f} | {min(times['views']):.3f} | "
              f"{diff:.3g} | {same_err} |")
    # the preview stage (render_previews: load the sphere, the lights' shading, one GL frame, PNG)
    stage: dict[str, list[float]] = {"whole": [], "views": []}
    for _ in range(args.rounds):
        for key in ("whole", "views"):
            shrm = lights_only(env, brdf)

            def run(s=shrm, k=key):
                if k == "whole":  # as before: the whole table (what the cache then hands the preview)
                    cached_light_shading(s)
                return render_previews(s, env, mode="gl", size=args.size)

            _, seconds = cpu(run)
            stage[key].append(seconds)
    print(f"\npreview stage (render_previews, {args.size} px) CPU s: whole table "
          f"{' '.join(f'{t:.3f}' for t in stage['whole'])}; views' rows {' '.join(f'{t:.3f}' for t in stage['views'])}")
    print("frames bit-identical and errors the same:", "yes" if identical else "NO")
    return 0 if identical else 1


if __name__ == "__main__":
    sys.exit(main())
