"""Per-pixel relative error of a lit sphere against brute force, with and without light extraction
(issue 23's target: Grace + Phong s = 200, median <= 0.05, 90th percentile <= 0.15).

For each configuration (lights, window, and optionally more or larger lights than the defaults) the
script prefilters the map, takes ``--pixels`` covered pixels of a ``--size``² orthographic sphere
(``render.cpu_reference.sphere_geometry``, the camera of ``shrm render``'s default view) at random
(seeded), and compares ``SHRM.radiance`` at each pixel's (R, V) with the brute-force angular reference
(``analysis.reference.reference_radiance``, every pixel of the same map): relative error of the Rec. 709
luminance per pixel, median / 90th percentile / max. It also splits the error into the SHRM part (the
residual map's reflection) and the lights part (exact up to their merge).

Run from the repository root (about a minute per configuration on one core of this machine):

    .venv/bin/python benchmarks/lights_per_pixel.py [--height 256] [--pixels 3000] [--brdf phong:s=200]

Reads ``../shared/data/env/grace_latlong.exr`` (Debevec's Grace Cathedral, y-up, flipped as the README's
commands load it).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

import shrmkit
import shrmkit.analysis.lights as lights_module
from shrmkit.analysis.lights import extract_lights
from shrmkit.analysis.reference import reference_radiance
from shrmkit.brdf_io.exr import luminance_weights
from shrmkit.render.camera import Camera
from shrmkit.render.cpu_reference import sphere_geometry

GRACE = Path(__file__).resolve().parents[2] / "shared" / "data" / "env" / "grace_latlong.exr"
#: (label, lights, window, MAX_LIGHTS, MAX_LIGHT_RADIUS_DEG, LIGHT_CONTRAST); None: the library default
CONFIGS = [
    ("default", "auto", "auto", None, None, None),
    ("no lights", "none", "auto", None, None, None),
    ("no window", "auto", "none", None, None, None),
    ("32 lights <= 15 deg", "auto", "auto", 32, 15.0, None),
    ("64 lights <= 30 deg, 30x", "auto", "auto", 64, 30.0, 30.0),
]


def stats(x: np.ndarray) -> str:
    return f"{np.median(x):8.3f} {np.percentile(x, 90):8.3f} {x.max():8.2f}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--height", type=int, default=256, help="rows of the lat-long map (default 256)")
    ap.add_argument("--pixels", type=int, default=3000, help="covered pixels compared (default 3000)")
    ap.add_argument("--size", type=int, default=256, help="image size (default 256)")
    ap.add_argument("--brdf", default="phong:s=200")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()

    env = shrmkit.load_env(GRACE, up="y", flip=True, height=args.height)
    brdf = shrmkit.load_brdf(args.brdf)
    geometry = sphere_geometry(Camera.looking_at(projection="ortho"), args.size, args.size)
    covered = np.flatnonzero(geometry.hit.ravel())
    pick = np.random.default_rng(args.seed).choice(covered, min(args.pixels, covered.size), replace=False)
    R, V = geometry.R.reshape(-1, 3)[pick], geometry.V.reshape(-1, 3)[pick]
    luma = luminance_weights()
    reference = reference_radiance(env, brdf, R, V) @ luma
    defaults = (lights_module.MAX_LIGHTS, lights_module.MAX_LIGHT_RADIUS_DEG, lights_module.LIGHT_CONTRAST)
    print(f"{args.brdf} under Grace ({args.height} rows), {pick.size} pixels of a {args.size}² sphere; "
          "relative error of the luminance per pixel: median, 90th percentile, max")
    print(f"{'configuration':26s} {'F':>3s} {'P':>2s} {'lights':>6s} {'flux':>5s} {'median':>8s} {'p90':>8s} "
          f"{'max':>8s}   SHRM part median/p90   lights part p90   {'s':>5s}")
    for label, lights, window, n_max, radius, contrast in CONFIGS:
        try:
            lights_module.MAX_LIGHTS = n_max or defaults[0]
            lights_module.MAX_LIGHT_RADIUS_DEG = radius or defaults[1]
            lights_module.LIGHT_CONTRAST = contrast or defaults[2]
            t0 = time.process_time()
            shrm = shrmkit.prefilter(env, brdf, lights=lights, window=window)
            seconds = time.process_time() - t0
            extraction = extract_lights(env, lights)
        finally:
            lights_module.MAX_LIGHTS, lights_module.MAX_LIGHT_RADIUS_DEG, lights_module.LIGHT_CONTRAST = defaults
        total = shrm.radiance(R, V) @ luma
        shrm_part = shrm.radiance(R, V, lights=False) @ luma
        residual_reference = reference_radiance(extraction.residual, brdf, R, V) @ luma
        light_error = np.abs(total - shrm_part - (reference - residual_reference)) / reference
        shrm_error = np.abs(shrm_part - residual_reference) / reference
        print(f"{label:26s} {shrm.F:3d} {shrm.P:2d} {len(extraction.lights.lights):6d} "
              f"{extraction.flux_share:5.2f} {stats(np.abs(total - reference) / reference)}   "
              f"{np.median(shrm_error):8.3f} {np.percentile(shrm_error, 90):8.3f}   "
              f"{np.percentile(light_error, 90):15.3g}   {seconds:5.1f}")


if __name__ == "__main__":
    main()
