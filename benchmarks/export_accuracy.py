"""``shrm export`` measured (issue 26): the error of every material export, checked against Mitsuba 3;
the MERL round trip; the DDS cube chain against direct prefilter sums.

    .venv/bin/python benchmarks/export_accuracy.py            # ~1-2 min CPU
    .venv/bin/python benchmarks/export_accuracy.py --quick    # fewer models, smaller chain

(a) For each model x target (Mitsuba 3, pbrt-v4, MaterialX standard_surface): exact or not, the
measured relative RMS of ρ cos θ_i (all views and the worst view band, 32768 Sobol pairs, θ ≤ 80°),
and, where Mitsuba 3 is installed, the largest relative difference between Mitsuba's own BSDF
evaluation of the exported XML and shrmkit's evaluation of the exported material at 2000 random
direction pairs (so the stated error is the error of what Mitsuba renders).
(b) RGL measurements (../shared/data/brdf/rgl) to MERL: tabulated, written, read back; read-back
error and time.
(c) The DDS cube chain of a real map (Poly Haven venice_sunset, y-up) against Karis's prefilter
summed directly over every pixel at 200 random texels per level; build time.
All times are CPU seconds of this process (time.process_time).
"""

from __future__ import annotations

import argparse
import tempfile
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from shrmkit.analysis.material_export import export_material
from shrmkit.analysis.prefiltered_cube import ggx_cube_chain
from shrmkit.brdf_io.cubemap import CUBE_TO_PROJECT, cube_map_directions
from shrmkit.brdf_io.envmap import load_env
from shrmkit.brdf_io.export_material import material_text
from shrmkit.brdf_io.latlong import pixel_directions, row_solid_angles
from shrmkit.brdf_io.merl import read_merl, tabulate_merl, write_merl
from shrmkit.brdf_io.specs import load_brdf

DATA = Path("/work/shared/data")
MODELS = [
    "lambert:albedo=0.2/0.4/0.8",
    "cook-torrance:kd=0.1/0.2/0.05,ks=0.6,alpha=0.2,f0=1,dist=ggx",
    "cook-torrance:kd=0,ks=1,alpha=0.15,f0=0.95/0.64/0.54,dist=ggx",
    "cook-torrance:kd=0.3/0.2/0.1,ks=0.5,alpha=0.3,f0=0.04,dist=beckmann",
    "lafortune:kd=0.1,cxy=-1,cz=1,n=40,ks=3",
    "phong:s=32",
    "microfacet:sigma=0.2",
]
TARGETS = ("mitsuba", "pbrt", "materialx")


def _directions(n: int, rng: np.random.Generator) -> np.ndarray:
    v = rng.normal(size=(n, 3))
    v[:, 2] = np.abs(v[:, 2]) + 0.05
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def _mitsuba_check(material) -> float | None:
    try:
        import mitsuba as mi  # optional: not a dependency of shrmkit
    except ImportError:
        return None
    mi.set_variant("scalar_rgb")
    element = ET.fromstring(material_text(material, "m")).find("bsdf")
    element.set("version", "3.0.0")
    bsdf = mi.load_string(ET.tostring(element, encoding="unicode"))
    rng = np.random.default_rng(0)
    L, V = _directions(2000, rng), _directions(2000, rng)
    ctx = mi.BSDFContext()
    theirs = []
    for light, view in zip(L, V, strict=True):
        si = mi.SurfaceInteraction3f()
        si.wi = mi.Vector3f(*view)
        si.n = mi.Normal3f(0, 0, 1)
        si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
        theirs.append(np.array(bsdf.eval(ctx, si, mi.Vector3f(*light))) / light[2])
    ours = material.eval(L, V)
    return float(np.max(np.abs(np.array(theirs) - ours) / np.maximum(ours, 1e-3 * ours.max())))


def materials(models: list[str]) -> None:
    print("(a) material exports: relative RMS of rho cos theta_i against the source (32768 Sobol pairs, "
          "theta <= 80 deg)")
    print(f"{'model':66s} {'target':9s} {'exact':5s} {'all':>8s} {'worst band':>16s} {'mitsuba vs ours':>15s} "
          f"{'CPU s':>6s}")
    for spec in models:
        brdf = load_brdf(spec)
        for target in TARGETS:
            t0 = time.process_time()
            result = export_material(brdf, target, n_samples=32768)
            dt = time.process_time() - t0
            check = _mitsuba_check(result.material) if target == "mitsuba" else None
            worst = result.worst
            band = "-" if worst is None else f"{worst.rel_rms:.3g} ({worst.lo_deg:g}-{worst.hi_deg:g})"
            checked = "-" if check is None else f"{check:.1e}"
            print(f"{spec[:66]:66s} {target:9s} {'yes' if result.exact else 'no':5s} {result.rel_rms:8.3g} "
                  f"{band:>16s} {checked:>15s} {dt:6.2f}")


def merl(quick: bool) -> None:
    print("\n(b) MERL export (tabulate, write, read back with read_merl)")
    files = sorted((DATA / "brdf" / "rgl").glob("*.bsdf"))[: 1 if quick else 3]
    sources = [str(f) for f in files] or ["cook-torrance:kd=0.1,ks=0.5,alpha=0.2,dist=ggx"]
    with tempfile.TemporaryDirectory() as folder:
        for source in sources:
            t0 = time.process_time()
            brdf = load_brdf(source)
            values = tabulate_merl(brdf)
            t1 = time.process_time()
            path = write_merl(Path(folder) / "x.binary", values)
            back = read_merl(path).values
            t2 = time.process_time()
            ok = ~np.isnan(values)
            rel = np.max(np.abs(back[ok] - values[ok]) / np.maximum(values[ok], 1e-300))
            print(f"{Path(source).name:40s} missing {np.count_nonzero(np.any(~ok, axis=0)):>9,}  read-back max rel "
                  f"{rel:.1e}  tabulate {t1 - t0:.2f} s, write+read {t2 - t1:.2f} s")


def cube_chain(quick: bool) -> None:
    print("\n(c) DDS cube chain against direct prefilter sums (200 random texels per level)")
    path = DATA / "env" / "polyhaven_cc0" / "venice_sunset_1k.hdr"
    env = load_env(str(path), up="y") if path.exists() else load_env("builtin:sky")
    radiance = env.radiance
    if radiance.shape[0] > 128:  # average 4 x 4 blocks down to a map the direct sum handles
        f = radiance.shape[0] // 128
        radiance = radiance.reshape(128, f, 256, f, 3).mean(axis=(1, 3))
    size = 32 if quick else 64
    t0 = time.process_time()
    chain = ggx_cube_chain(radiance, face_size=size)
    dt = time.process_time() - t0
    print(f"environment {env.name} at {radiance.shape[0]} x {radiance.shape[1]}, face {size}: "
          f"{len(chain.levels)} levels in {dt:.2f} s CPU")
    d = pixel_directions(*radiance.shape[:2])
    omega = row_solid_angles(*radiance.shape[:2])[:, None]
    rng = np.random.default_rng(1)
    print(f"{'level':>5s} {'size':>5s} {'roughness':>9s} {'alpha':>7s} {'median rel':>10s} {'max rel':>8s}")
    for m, (level, r, a) in enumerate(zip(chain.levels, chain.roughness, chain.alpha, strict=True)):
        if a == 0:
            continue
        s = level.shape[1]
        dirs = cube_map_directions(s) @ CUBE_TO_PROJECT.T
        picks = rng.integers(0, 6 * s * s, 200)
        R = dirs.reshape(-1, 3)[picks]
        cos_g = np.einsum("nx,hwx->nhw", R, d)
        c2 = (1 + cos_g) / 2
        k = a**2 / (np.pi * (c2 * (a**2 - 1) + 1) ** 2) * np.maximum(cos_g, 0) * omega
        direct = np.einsum("nhw,hwc->nc", k, radiance) / k.sum(axis=(1, 2))[:, None]
        rel = np.abs(level.reshape(-1, 3)[picks] - direct) / np.maximum(direct, 1e-12)
        print(f"{m:5d} {s:5d} {r:9.4g} {a:7.4g} {np.median(rel):10.2e} {rel.max():8.2e}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args()
    materials(MODELS[:4] if args.quick else MODELS)
    merl(args.quick)
    cube_chain(args.quick)


if __name__ == "__main__":
    main()
