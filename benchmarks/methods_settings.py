"""The measurements behind the table of published methods' settings (``data_specs/methods.md``).

Where ``render/modes.py`` and ``analysis/compare`` used to build the same method with different
settings, this prints the error and cost of each:

- ``km``: Kautz–McCool [KM00] with its own order choice (window, pixel rule and map rows decided
  for the q = 0 field; render before the table) against the SHRM's (F, P) and map rows (compare
  before, both now);
- ``elevations``: the Gaussian-lobe fit [Green07], K = 3, at 1 … 90 view elevations (render took
  1–90, compare 2–64; both now 2–64).

Error: relative RMS radiance error against the angular reference ([RH02] eq. 2) on compare's 2000
(R, V) pairs (views to 88°) / on those inside the order rule's 80°. Cost: CPU (process) seconds of
the build. ε = 0.03; ``builtin:sky`` and Grace (``../shared/data``, y-up) at 64 rows.

Run: ``.venv/bin/python benchmarks/methods_settings.py km|elevations [--quick]`` (``km``: ~15 s
CPU; ``elevations``: ~5 min CPU per row, ``--quick`` one row to 32 elevations).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

from shrmkit.analysis.baselines.gaussian_lobes import GaussianLobeModel, fit_gaussian_lobes, sg_mip_stack
from shrmkit.analysis.compare import relative_rms, sample_pairs
from shrmkit.analysis.reference import reference_radiance
from shrmkit.analysis.shrm import prefilter
from shrmkit.brdf_io.envmap import load_env
from shrmkit.brdf_io.specs import load_brdf

GRACE = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "env" / "grace_latlong.exr"
GGX = "cook-torrance:kd=0.05,ks=1,alpha=0.2,f0=0.9,dist=ggx"
BRDFS = ["microfacet:sigma=0.1", "microfacet:sigma=0.3", GGX, "phong:s=64"]
ELEVATIONS = (1, 2, 4, 8, 15, 32, 64, 90)


def _envs() -> dict:
    envs = {"sky": load_env("builtin:sky").resized(64, 128)}
    if GRACE.exists():
        envs["grace"] = load_env(GRACE, flip=True, up="y", height=64)
    return envs


def _cpu(fn, *args, **kwargs):
    t0 = time.process_time()
    out = fn(*args, **kwargs)
    return out, time.process_time() - t0


def main() -> None:
    what = sys.argv[1] if len(sys.argv) > 1 else "km"
    quick = "--quick" in sys.argv
    R, V, tv = sample_pairs(2000, seed=0, max_view_deg=88.0)
    inside = tv <= np.radians(80.0)
    envs = _envs()

    def err(model, ref) -> str:
        p = model.radiance(R, V)
        return f"{relative_rms(p, ref):.4f} / {relative_rms(p[inside], ref[inside]):.4f}"

    if what == "km":
        print("| map | BRDF | SHRM (F, P, rows): error, CPU | own orders: error, CPU | "
              "SHRM's grid: error, CPU (+ the SHRM) |\n|---|---|---|---|---|")
        for env_name, env in envs.items():
            for spec in BRDFS[:2] if quick else BRDFS:
                brdf = load_brdf(spec)
                ref = reference_radiance(env, brdf, R, V)
                base, t_base = _cpu(prefilter, env, brdf, eps=0.03)
                own, t_own = _cpu(prefilter, env, brdf, eps=0.03, azimuth_free=True)
                grid, t_grid = _cpu(prefilter, env, brdf, eps=0.03, F=base.F, P=base.P, size=base.height,
                                      azimuth_free=True)
                print(f"| {env_name} | {spec} | {base.F}, {base.P}, {base.height}: {err(base, ref)}, {t_base:.2f} s "
                      f"| {own.F}, {own.P}, {own.height}: {err(own, ref)}, {t_own:.2f} s "
                      f"| {err(grid, ref)}, {t_grid:.2f} s (+{t_base:.2f}) |", flush=True)
    elif what == "elevations":
        cases = [("sky", "microfacet:sigma=0.1"), ("grace", GGX), ("sky", GGX), ("grace", "microfacet:sigma=0.1")]
        counts = ELEVATIONS[:6] if quick else ELEVATIONS
        print("| map | BRDF | " + " | ".join(f"{n} elevations" for n in counts) + " |")
        print("|---|---|" + "---|" * len(counts))
        for env_name, spec in cases[:1] if quick else cases:
            if env_name not in envs:
                continue
            env, brdf = envs[env_name], load_brdf(spec)
            ref = reference_radiance(env, brdf, R, V)
            stack = sg_mip_stack(env)
            cells = []
            for n in counts:
                fit, t = _cpu(fit_gaussian_lobes, brdf, K=3, n_elevations=n)
                cells.append(f"{err(GaussianLobeModel(fit, stack), ref)}, {t:.1f} s")
            print(f"| {env_name} | {spec} | " + " | ".join(cells) + " |", flush=True)
    else:
        raise SystemExit("usage: methods_settings.py km|elevations [--quick]")


if __name__ == "__main__":
    main()
