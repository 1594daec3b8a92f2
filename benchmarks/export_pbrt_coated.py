"""pbrt-v4 ``coateddiffuse`` against the conductor ``mix`` for diffuse + dielectric-like models (issue 26).

    .venv/bin/python benchmarks/export_pbrt_coated.py            # ~30 s CPU
    .venv/bin/python benchmarks/export_pbrt_coated.py --quick    # 4 models

For each Cook–Torrance model with a diffuse term and a dielectric-like lobe (ks·f0 ≤ 0.25), both
pbrt-v4 materials ``shrm export`` can write are built (``brdf_io/export_material.py``:
``_pbrt_mix``, ``_pbrt_coated``) and their measured error against the model is printed (relative
RMS of ρ cos θ_i, all views / worst view band, 16384 Sobol pairs with θ ≤ 80°, as
``analysis/material_export.py`` states it), with the material ``to_target`` chooses, the coat's
η, base reflectance, ``maxdepth``, and the CPU seconds of the export. The coated material is
evaluated by ``brdf_io/pbrt_coated.py``'s closed form of pbrt-v4's random walk (no medium, thin
layer); pbrt itself is not run here.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from shrmkit.analysis.material_export import export_material
from shrmkit.brdf_io import export_material as em
from shrmkit.brdf_io.specs import brdf_from_spec

MODELS = [
    "cook-torrance:kd=0.3/0.2/0.1,ks=1,alpha=0.05,f0=0.04,dist=ggx",
    "cook-torrance:kd=0.3/0.2/0.1,ks=1,alpha=0.2,f0=0.04,dist=ggx",
    "cook-torrance:kd=0.3/0.2/0.1,ks=1,alpha=0.5,f0=0.04,dist=ggx",
    "cook-torrance:kd=0.6/0.5/0.4,ks=1,alpha=0.2,f0=0.04,dist=ggx",
    "cook-torrance:kd=0.8/0.8/0.8,ks=1,alpha=0.2,f0=0.04,dist=ggx",
    "cook-torrance:kd=0.3/0.2/0.1,ks=1,alpha=0.2,f0=0.1,dist=ggx",
    "cook-torrance:kd=0.3/0.2/0.1,ks=1,alpha=0.3,f0=0.04,dist=beckmann",
    "cook-torrance:kd=0.3/0.2/0.1,ks=0.5,alpha=0.3,f0=0.04,dist=beckmann",
    "cook-torrance:kd=0.3/0.2/0.1,ks=0.5,alpha=0.2,f0=0.04,dist=ggx",
    "cook-torrance:kd=0.05,ks=1,alpha=0.2,f0=0.04,dist=ggx",
]


def _forced(builder):
    """``to_target(…, "pbrt")`` with the choice fixed to one builder (for the comparison only)."""
    def convert(brdf):
        kd = np.asarray(brdf.kd, float) * np.ones(3)
        ks, f0 = np.asarray(brdf.ks, float) * np.ones(3), np.asarray(brdf.f0, float) * np.ones(3)
        return builder(brdf.to_spec(), kd, brdf, ks, f0)
    return convert


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="4 models")
    args = parser.parse_args()
    models = MODELS[:3] + MODELS[7:8] if args.quick else MODELS
    print(f"{'model':66s} {'chosen':>13s} {'mix all/worst':>14s} {'coated all/worst':>17s} "
          f"{'eta':>6s} {'reflectance':>20s} {'maxdepth':>8s} {'CPU s':>6s}")
    original = em.MATERIAL_TARGETS["pbrt"]
    for spec in models:
        brdf = brdf_from_spec(spec)
        t = time.process_time()
        chosen = export_material(brdf, "pbrt")
        seconds = time.process_time() - t
        rows = {}
        for name, builder in (("mix", em._pbrt_mix), ("coated", em._pbrt_coated)):
            em.MATERIAL_TARGETS["pbrt"] = em.MaterialTarget("pbrt", ".pbrt", _forced(builder), original.text, "")
            try:
                rows[name] = export_material(brdf, "pbrt")
            finally:
                em.MATERIAL_TARGETS["pbrt"] = original
        coat = rows["coated"].material.coat
        assert coat is not None
        print(f"{spec:66s} {chosen.material.native['type']:>13s} "
              f"{rows['mix'].rel_rms:6.3f}/{rows['mix'].worst.rel_rms:6.3f} "
              f"{rows['coated'].rel_rms:8.3f}/{rows['coated'].worst.rel_rms:6.3f} {coat.eta:6.3f} "
              f"{' '.join(f'{r:.3f}' for r in coat.reflectance):>20s} {coat.maxdepth():8d} {seconds:6.2f}")


if __name__ == "__main__":
    main()
