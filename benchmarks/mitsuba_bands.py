"""RGL materials rendered by Mitsuba 3 and by shrmkit, compared per view band (issue 29).

The scene: the unit sphere at the origin made of an RGL ``.bsdf`` material, lit by an
environment map (default the ICT Grace probe of ``shared/data/env/ict_small``, y-up, read
with ``load_env(up="y")``, area-averaged to ``--env-rows``), seen by an orthographic camera
from ``VIEW`` (``Camera.looking_at(view=VIEW, projection="ortho")``, z up), one ray through
each pixel centre (``Camera.rays``). Per pixel, θ_v is the angle between the sphere's normal
and the direction toward the camera (data_specs/view_bands.md), and the pixels are grouped by
the bands of ``DEFAULT_BAND_EDGES_DEG``.

Renderers, all on the same rays:

- **Mitsuba** 3.9.1, ``scalar_rgb``: integrator ``direct`` (one emitter and one BSDF sample
  per sample, MIS), a ``sphere`` shape with the ``measured`` plugin of the file, an ``envmap``
  emitter, and one ``radiancemeter`` per pixel-centre ray inside one ``batch`` sensor (so
  Mitsuba samples exactly our rays, not the pixel footprint); ``--seeds`` independent renders of
  ``--spp`` samples give the mean and its noise.
- **reference**: ``render.cpu_reference.shade`` on the analytic sphere with the brute-force
  angular reference (``analysis.reference``: every map pixel a point light at its centre with its
  solid angle) and the file read with ``clip_negative=False`` (Mitsuba passes the table's small
  negative values on).
- **SHRM (CPU)**: the SHRM that ``shrm render`` builds (``render.api.render_scene``, default
  mode, ε = ``--eps``, lights ``auto``, the file loaded as ``shrm render`` loads it) evaluated
  by ``SHRM.radiance`` on the analytic sphere.
- **shrm render (GL)**: that render's frame (the built-in triangulated sphere, OpenGL); only
  with an offscreen context, pixels fully covered.

**Conventions** (checked, not assumed): Mitsuba's envmap frame is y-up with
u = atan2(x, −z)/2π + ½ texel, v = acos(y)/π (rows are vertices, the first at the pole: its
``src/emitters/envmap.cpp``); the emitter's ``to_world`` :data:`MI_TO_WORLD` takes it to the
project z-up frame, and the bitmap holds the project map sampled at its vertex directions,
upsampled ``--upsample`` × so that Mitsuba's bilinear interpolation blurs only a fraction of
each project pixel's edge (:func:`check_envmap` compares Mitsuba's ``eval`` with the project
map at random directions: median difference ~1e-7, the rest the blurred edges). The camera
direction is the file's incident direction (ω_i = V, data_specs/rgl_bsdf.md). Radiance: the
map's values, unscaled, in both.

Per band the table gives the band means (RGB pooled: |m|² summed over channels) of Mitsuba and
of each of ours, ``diff`` = |m_ours − m_Mitsuba| / |m_Mitsuba|, ``noise`` = 2 standard errors of
Mitsuba's mean from the seed-to-seed spread, the per-pixel relative RMS ``rms`` of ours against
Mitsuba with ``pix.noise`` = Mitsuba's own per-pixel relative RMS noise (from the seeds), and
for the SHRM two statements of its error: the band's (``SHRM.meta["view_bands"]``: predicted /
bound, a relative RMS over *all* reflection directions) and the same carried to the band's
pixels (``analysis.compare.band_error.pixels_statement``: max(r, e_b / RMS_pix), larger where
the pixels reflect less than the band's average; data_specs/rgl_bsdf.md says why).
First ``pass``: diff ≤ noise + the band's bound (the criterion before); last ``pass``: diff ≤
noise + the pixels' bound and rms ≤ pix.noise + the pixels' bound (the reference's stated error is 0).
``--json FILE`` writes every table's rows (these keys, ``stated``, ``pixels_statement``,
``pass_stated``, ``pass``) per material, with the SHRM's orders, rows and CPU seconds.

``--record FILE`` writes the small JSON of ``tests/resources/mitsuba_bands_grace16.json``
(data_specs/rgl_bsdf.md, "Rendered against Mitsuba"): Mitsuba's band means and noise for one
material and scene, with the command and Mitsuba's version, which the always-run test checks
against our renders.

Shared data are read from ``../shared/data`` (never copied into the repository). Needs
``pip install mitsuba==3.9.1`` (not a project dependency).

Run:  .venv/bin/python benchmarks/mitsuba_bands.py [--size 64] [--env-rows 64] [--spp 256] [--seeds 4] [--json FILE]
      .venv/bin/python benchmarks/mitsuba_bands.py --size 48 --env-rows 512 --upsample 2 --no-reference \\
          --spp 512 --seeds 8
      .venv/bin/python benchmarks/mitsuba_bands.py --size 16 --env-rows 32 --ref-upsample 2 --spp 2048 --seeds 8 \\
          --material cc_ibiza_sunset_rgb --no-shrm --record tests/resources/mitsuba_bands_grace16.json
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from shrmkit.analysis.compare.band_error import pixels_statement
from shrmkit.analysis.reference import reference_radiance
from shrmkit.analysis.view_bands import DEFAULT_BAND_EDGES_DEG
from shrmkit.brdf_io.envmap import EnvironmentMap, load_env
from shrmkit.brdf_io.latlong import pixel_index
from shrmkit.brdf_io.rgl import read_rgl
from shrmkit.render.camera import Camera
from shrmkit.render.cpu_reference import HitGeometry, shade, sphere_geometry

__all__ = ["MI_TO_WORLD", "VIEW", "SphereScene", "sphere_scene", "scene_env", "mitsuba_bitmap", "check_envmap",
           "mitsuba_render", "band_means", "compare_bands", "reference_render", "main"]

DATA = Path(__file__).resolve().parents[2] / "shared" / "data"
ENV = DATA / "env" / "ict_small" / "grace.hdr"
RGL = DATA / "brdf" / "rgl"
EDGES = DEFAULT_BAND_EDGES_DEG
#: Direction from the sphere toward the camera (z-up frame): slightly above the equator, so the
#: bright lower windows of Grace and the dome both reflect in the sphere.
VIEW = (1.0, 0.3, 0.25)
#: Mitsuba envmap frame (y up, x = sin φ sin θ, z = −cos φ sin θ) → project z-up frame (a rotation):
#: project = MI_TO_WORLD @ mitsuba, so project θ = Mitsuba's θ and project φ = −Mitsuba's φ.
MI_TO_WORLD = np.array([[0.0, 0.0, -1.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
MATERIALS = ("cc_ibiza_sunset_rgb", "paper_white_rgb", "colodur_napoli_4f_rgb")


@dataclass(frozen=True)
class SphereScene:
    """The camera rays that hit the unit sphere: ``origins``, ``dirs`` (n, 3), their ``theta_v_deg``
    (n,), the full ``geometry`` (H, W) and the ``camera``."""

    camera: Camera
    geometry: HitGeometry
    origins: np.ndarray
    dirs: np.ndarray
    theta_v_deg: np.ndarray


def sphere_scene(size: int, view: tuple[float, float, float] = VIEW) -> SphereScene:
    """Orthographic ``size`` × ``size`` view of the unit sphere from ``view`` (module docstring)."""
    camera = Camera.looking_at(view=np.asarray(view, float), projection="ortho")
    geometry = sphere_geometry(camera, size, size)
    origins, dirs = camera.rays(size, size)
    m = geometry.hit
    cos_v = np.clip(np.sum(geometry.N[m] * geometry.V[m], axis=-1), -1.0, 1.0)
    return SphereScene(camera, geometry, origins[m], dirs[m], np.degrees(np.arccos(cos_v)))


def scene_env(rows: int, path: Path = ENV) -> EnvironmentMap:
    """The scene's map: ``path`` read y-up, area-averaged to ``rows`` rows (``load_env``)."""
    return load_env(path, up="y", height=rows)


def mitsuba_bitmap(radiance: np.ndarray, upsample: int = 8) -> np.ndarray:
    """The (k H + 1, k W, 3) float32 bitmap of Mitsuba's ``envmap`` (with ``to_world`` =
    :data:`MI_TO_WORLD`) whose bilinear interpolant integrates like the project map ``radiance``
    (H, W, 3), piecewise constant on its pixels.

    Mitsuba's vertex row i lies at θ = iπ/(kH): k rows per project row, every k-th on a row edge,
    which takes the mean of the two rows it separates (so the trapezoid of each project row is
    exact); vertex column j at Mitsuba's φ = 2π(j + ½)/(kW), k inside each project column, looked up
    through :data:`MI_TO_WORLD` (project φ = −Mitsuba's φ)."""
    radiance = np.asarray(radiance, dtype=np.float64)
    h, w = radiance.shape[:2]
    k = int(upsample)
    phi = (np.arange(k * w) + 0.5) / (k * w) * 2.0 * np.pi
    equator = np.stack([np.sin(phi), np.zeros_like(phi), -np.cos(phi)], -1) @ MI_TO_WORLD.T
    col = pixel_index(equator, h, w)[1]
    i = np.arange(k * h + 1)
    above, below = np.clip((i - 1) // k, 0, h - 1), np.minimum(i // k, h - 1)
    rows = np.where((i % k == 0)[:, None, None], 0.5 * (radiance[above] + radiance[below]), radiance[below])
    return np.ascontiguousarray(rows[:, col], dtype=np.float32)


def _mitsuba():
    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    mi.set_log_level(mi.LogLevel.Error)  # not a warning per sample of the vinyls' small negative values
    return mi


def _to_world(mi):
    matrix = np.eye(4)
    matrix[:3, :3] = MI_TO_WORLD
    return mi.ScalarTransform4f(matrix.tolist())


def check_envmap(radiance: np.ndarray, upsample: int = 8, n: int = 4000, seed: int = 0) -> dict:
    """Mitsuba's ``envmap`` ``eval`` against the project map at ``n`` random directions: the
    fraction equal to 1e-5 and the median relative difference (0 up to float32 where the
    orientation is right; the rest are the blurred pixel edges)."""
    mi = _mitsuba()
    emitter = mi.load_dict({"type": "envmap", "bitmap": mi.Bitmap(mitsuba_bitmap(radiance, upsample)),
                            "to_world": _to_world(mi)})
    rng = np.random.default_rng(seed)
    d = rng.normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    si = mi.SurfaceInteraction3f()
    theirs = np.empty((n, 3))
    for k in range(n):
        si.wi = mi.Vector3f(*map(float, -d[k]))  # eval looks up −wi: the direction toward the map
        value = emitter.eval(si)
        theirs[k] = (value[0], value[1], value[2])
    h, w = radiance.shape[:2]
    ours = np.asarray(radiance, float)[pixel_index(d, h, w)]
    rel = np.abs(theirs - ours).max(axis=1) / np.maximum(np.abs(ours).max(axis=1), 1e-30)
    return {"equal_fraction": float(np.mean(rel < 1e-5)), "median_rel": float(np.median(rel))}


def mitsuba_render(bsdf_path: Path, radiance: np.ndarray, scene: SphereScene, *, spp: int, seed: int,
                   upsample: int = 8) -> np.ndarray:
    """Mitsuba's radiance (n, 3) along the scene's rays (module docstring), ``spp`` samples each."""
    mi = _mitsuba()
    film = {"type": "hdrfilm", "width": 1, "height": 1, "rfilter": {"type": "box"}, "pixel_format": "rgb"}
    sensors = {f"ray{k}": {"type": "radiancemeter", "origin": [float(c) for c in o], "direction": [float(c) for c in d],
                           "film": film}
               for k, (o, d) in enumerate(zip(scene.origins, scene.dirs, strict=True))}
    batch = mi.load_dict({"type": "batch", **sensors,
                          "film": {**film, "width": len(scene.origins)},
                          "sampler": {"type": "independent", "sample_count": int(spp)}})
    world = mi.load_dict({
        "type": "scene", "integrator": {"type": "direct"},
        "sphere": {"type": "sphere", "center": [0.0, 0.0, 0.0], "radius": 1.0,
                   "bsdf": {"type": "measured", "filename": str(bsdf_path)}},
        "env": {"type": "envmap", "bitmap": mi.Bitmap(mitsuba_bitmap(radiance, upsample)), "to_world": _to_world(mi)},
    })
    image = mi.render(world, sensor=batch, seed=int(seed), spp=int(spp))
    return np.asarray(image, dtype=np.float64).reshape(-1, 3)


def reference_render(bsdf_path: Path, env: EnvironmentMap, scene: SphereScene, *, table_direction: str = "view",
                     upsample: int = 1) -> np.ndarray:
    """Brute-force angular reference (n, 3) at the scene's hit pixels (``clip_negative=False``).

    ``upsample`` s > 1 sums over the map's pixels each split into s × s (the same piecewise-constant
    map, which Mitsuba integrates, by a finer midpoint rule than one point light per pixel)."""
    brdf = read_rgl(bsdf_path, clip_negative=False, table_direction=table_direction)
    radiance = np.repeat(np.repeat(np.asarray(env.radiance), upsample, axis=0), upsample, axis=1)
    return shade(scene.geometry, lambda R, V: reference_radiance(radiance, brdf, R, V))[scene.geometry.hit]


def band_means(values: np.ndarray, theta_v_deg: np.ndarray, edges=EDGES) -> list[np.ndarray | None]:
    """Per band the mean RGB (3,) of ``values`` (n, 3) over the pixels whose θ_v lies in it (None: none)."""
    out: list[np.ndarray | None] = []
    for lo, hi in zip(edges[:-1], edges[1:], strict=True):
        sel = (theta_v_deg >= lo) & (theta_v_deg < hi)
        out.append(values[sel].mean(axis=0) if sel.any() else None)
    return out


def compare_bands(runs: np.ndarray, ours: np.ndarray, theta_v_deg: np.ndarray, edges=EDGES) -> list[dict]:
    """Per band: Mitsuba's mean over ``runs`` (K, n, 3) independent renders against ``ours`` (n, 3).

    Keys: ``theta_v_deg``, ``pixels``, ``mitsuba`` (RGB band mean), ``ours``, ``diff`` (|Δm|/|m|,
    RGB pooled), ``noise`` (2 s.e. of Mitsuba's band mean over the K seeds, relative), ``rms``
    (per-pixel relative RMS of ours against Mitsuba's K-seed mean), ``pix_noise`` (the relative RMS
    noise of that mean, per pixel, from the seeds).
    """
    k = runs.shape[0]
    mean = runs.mean(axis=0)
    out = []
    for lo, hi in zip(edges[:-1], edges[1:], strict=True):
        sel = (theta_v_deg >= lo) & (theta_v_deg < hi)
        record = {"theta_v_deg": [float(lo), float(hi)], "pixels": int(sel.sum())}
        if not sel.any():
            out.append(record)
            continue
        m = mean[sel].mean(axis=0)
        per_seed = runs[:, sel].mean(axis=1)  # (K, 3)
        scale = float(np.linalg.norm(m))
        se_mean = float(np.sqrt(np.sum(per_seed.var(axis=0, ddof=1)) / k))
        pix_var = runs[:, sel].var(axis=0, ddof=1) / k  # variance of the K-seed mean per pixel, channel
        energy = float(np.sum(mean[sel] ** 2))
        o = ours[sel]
        record.update(
            mitsuba=m.tolist(), ours=o.mean(axis=0).tolist(),
            diff=float(np.linalg.norm(o.mean(axis=0) - m)) / scale, noise=2.0 * se_mean / scale,
            rms=float(np.sqrt(np.sum((o - mean[sel]) ** 2) / energy)),
            pix_noise=float(np.sqrt(np.sum(pix_var) / energy)),
        )
        out.append(record)
    return out


def _stated(shrm, edges=EDGES) -> list[tuple[float, float] | None]:
    """(predicted, bound) relative RMS of each band from ``SHRM.meta["view_bands"]``."""
    bands = {tuple(b["theta_v_deg"]): b for b in shrm.meta.get("view_bands", [])}
    out = []
    for lo, hi in zip(edges[:-1], edges[1:], strict=True):
        b = bands.get((float(lo), float(hi)))
        out.append(None if b is None else (float(b["predicted_rel_rms"]), float(b["bound_rel_rms"])))
    return out


def _print_table(title: str, rows: list[dict], stated: list | None, pixels: list[dict] | None = None) -> list[dict]:
    """Print one table; returns its rows with ``pass_stated`` (diff ≤ noise + the band's stated bound)
    and, with ``pixels`` (:func:`~shrmkit.analysis.compare.band_error.pixels_statement`), ``pass``
    (diff ≤ noise + the bound carried to the band's pixels, and rms ≤ pix.noise + that bound)."""
    print(f"\n{title}")
    extra = f" {'pixels pred/bound':>17} {'factor':>6} {'pass':>4}" if pixels else ""
    print(f"{'band':>7} {'pix':>4} {'Mitsuba':>8} {'ours':>8} {'diff':>7} {'noise':>7} {'stated pred/bound':>17} "
          f"{'pass':>4} {'rms':>7} {'pix.noise':>9} {'excess':>7}{extra}")
    out = []
    for k, r in enumerate(rows):
        lo, hi = r["theta_v_deg"]
        if "mitsuba" not in r:
            print(f"{lo:>3g}-{hi:<3g} {0:>4} (no pixel)")
            out.append(r)
            continue
        pred, bound = (0.0, 0.0) if stated is None or stated[k] is None else stated[k]
        ok = r["diff"] <= r["noise"] + bound
        s = "0 (exact)" if stated is None else f"{pred:.4f}/{bound:.4f}"
        excess = np.sqrt(max(r["rms"] ** 2 - r["pix_noise"] ** 2, 0.0))
        line = (f"{lo:>3g}-{hi:<3g} {r['pixels']:>4} {np.mean(r['mitsuba']):8.5f} {np.mean(r['ours']):8.5f} "
                f"{r['diff']:7.4f} {r['noise']:7.4f} {s:>17} {'yes' if ok else 'NO':>4} {r['rms']:7.4f} "
                f"{r['pix_noise']:9.4f} {excess:7.4f}")
        record = {**r, "stated": [pred, bound], "pass_stated": bool(ok)}
        if pixels:
            p = pixels[k]
            ok_pix = r["diff"] <= r["noise"] + p["bound_rel_rms"] and r["rms"] <= r["pix_noise"] + p["bound_rel_rms"]
            line += (f" {p['predicted_rel_rms']:.4f}/{p['bound_rel_rms']:.4f} {p['factor']:6.2f} "
                     f"{'yes' if ok_pix else 'NO':>4}")
            record.update(pixels_statement=[p["predicted_rel_rms"], p["bound_rel_rms"]],
                          factor=p["factor"], **{"pass": bool(ok_pix)})
        print(line)
        out.append(record)
    return out


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--material", action="append", help=f"RGL file stem in {RGL} (repeatable; default "
                        f"{', '.join(MATERIALS)})")
    parser.add_argument("--size", type=int, default=64, help="image width and height in pixels")
    parser.add_argument("--env-rows", type=int, default=64, help="rows of the scene's map (area-averaged)")
    parser.add_argument("--upsample", type=int, default=8, help="Mitsuba bitmap vertices per project pixel, per axis")
    parser.add_argument("--ref-upsample", type=int, default=2, help="reference: each map pixel split into s x s")
    parser.add_argument("--spp", type=int, default=256, help="Mitsuba samples per ray and seed")
    parser.add_argument("--seeds", type=int, default=4, help="independent Mitsuba renders (their spread is the noise)")
    parser.add_argument("--eps", type=float, default=0.03, help="SHRM tolerance")
    parser.add_argument("--no-shrm", action="store_true", help="Mitsuba and the brute-force reference only")
    parser.add_argument("--no-reference", action="store_true", help="Mitsuba and the SHRM only (the brute-force "
                        "reference costs ~1 us per map pixel and ray: ~1000 s a material at 512 rows)")
    parser.add_argument("--record", help="write the JSON of Mitsuba's band values (one material)")
    parser.add_argument("--json", help="write every table's rows to this JSON file")
    args = parser.parse_args(argv)
    args.argv = list(sys.argv[1:] if argv is None else argv)
    import mitsuba as mi

    t0 = time.process_time()
    env = scene_env(args.env_rows)
    scene = sphere_scene(args.size)
    check = check_envmap(env.radiance, args.upsample)
    print(f"Mitsuba {mi.__version__} scalar_rgb; {ENV.name} {env.height}x{env.width} (bitmap x{args.upsample}): "
          f"envmap eval equal on {check['equal_fraction']:.0%} of directions, median rel {check['median_rel']:.1e}; "
          f"{args.size}^2 orthographic sphere from {VIEW}, {len(scene.origins)} rays, {args.spp} spp x {args.seeds}; "
          f"set-up CPU {time.process_time() - t0:.0f} s")
    tables: dict = {"argv": args.argv, "mitsuba_version": mi.__version__, "env_rows": env.height, "materials": {}}
    for name in args.material or MATERIALS:
        path = RGL / f"{name}.bsdf"
        own = tables["materials"][name] = {}
        t0 = time.process_time()
        runs = np.stack([mitsuba_render(path, env.radiance, scene, spp=args.spp, seed=1000 * s + 1,
                                        upsample=args.upsample) for s in range(args.seeds)])
        own["mitsuba_cpu_s"] = t_mi = time.process_time() - t0
        if args.no_reference:
            ref_rows = compare_bands(runs, runs.mean(axis=0), scene.theta_v_deg)  # Mitsuba's own band values
            print(f"\n{name}: Mitsuba CPU {t_mi:.0f} s (no brute-force reference)")
        else:
            t0 = time.process_time()
            ref = reference_render(path, env, scene, upsample=args.ref_upsample)
            light = reference_render(path, env, scene, table_direction="light", upsample=args.ref_upsample)
            own["reference_cpu_s"] = t_ref = (time.process_time() - t0) / 2
            ref_rows = compare_bands(runs, ref, scene.theta_v_deg)
            own["reference"] = _print_table(f"{name}: brute-force reference (camera convention; CPU {t_ref:.0f} s; "
                                            f"Mitsuba CPU {t_mi:.0f} s)", ref_rows, None)
            own["reference_light"] = _print_table(f"{name}: brute-force reference, light convention (#light)",
                                                  compare_bands(runs, light, scene.theta_v_deg), None)
        if not args.no_shrm:
            own.update(_shrm_tables(args, name, path, env, scene, runs))
        if args.record:
            _record(args, name, env, scene, runs, ref_rows, check)
    if args.json:
        Path(args.json).write_text(json.dumps(tables, indent=1) + "\n")
        print(f"wrote {args.json}")


def _shrm_tables(args, name: str, path: Path, env: EnvironmentMap, scene: SphereScene, runs: np.ndarray) -> dict:
    from shrmkit.render.api import render_scene

    t0 = time.process_time()
    try:
        result = render_scene("builtin:sphere", env, str(path), camera=scene.camera, size=args.size, eps=args.eps,
                              background="black", fps_frames=0)
    except Exception as error:  # no offscreen OpenGL: build the same SHRM without the GL frame
        print(f"(shrm render unavailable: {error}; SHRM built by prefilter)")
        from shrmkit.analysis.shrm import prefilter
        from shrmkit.brdf_io.specs import load_brdf

        shrm, frame = prefilter(env, load_brdf(str(path)), eps=args.eps), None
    else:
        shrm, frame = result.model, result.frames[0]
    seconds = time.process_time() - t0
    stated = _stated(shrm)
    worst = max((s for s, b in zip(stated, EDGES[:-1], strict=True) if s is not None and b < 80.0),
                key=lambda s: s[1], default=(float("nan"), float("nan")))
    cpu = shade(scene.geometry, shrm.radiance)[scene.geometry.hit]
    t0 = time.process_time()
    pixels = pixels_statement(shrm, cpu, scene.theta_v_deg)
    t_pix = time.process_time() - t0
    out = {"F": shrm.F, "P": shrm.P, "rows": shrm.height, "build_cpu_s": seconds, "statement_cpu_s": t_pix,
           "view_bands": shrm.meta["view_bands"]}
    out["shrm"] = _print_table(
        f"{name}: SHRM (F {shrm.F}, P {shrm.P}, {shrm.height} rows, eps {args.eps:g}; worst band inside 80 deg: "
        f"predicted {worst[0]:.4f}, bound {worst[1]:.4f}; build CPU {seconds:.0f} s, statement for the pixels "
        f"{t_pix:.1f} s), SHRM.radiance on the analytic sphere", compare_bands(runs, cpu, scene.theta_v_deg), stated,
        pixels)
    if frame is not None:
        full = (np.asarray(frame.alpha) >= 0.999) & scene.geometry.hit
        keep = full[scene.geometry.hit]
        gl = np.asarray(frame.linear, dtype=np.float64)[scene.geometry.hit]
        out["gl"] = _print_table(
            f"{name}: shrm render (OpenGL frame, triangulated sphere, {keep.sum()} fully covered pixels)",
            compare_bands(runs[:, keep], gl[keep], scene.theta_v_deg[keep]), stated,
            pixels_statement(shrm, cpu[keep], scene.theta_v_deg[keep]))
    return out


def _record(args, name: str, env: EnvironmentMap, scene: SphereScene, runs: np.ndarray, rows: list[dict],
            check: dict) -> None:
    import mitsuba as mi

    record = {
        "what": "Mitsuba 3 band means of an RGL sphere under an environment map (benchmarks/mitsuba_bands.py); "
                "data_specs/rgl_bsdf.md, 'Rendered against Mitsuba'",
        "command": ".venv/bin/python benchmarks/mitsuba_bands.py " + " ".join(args.argv),
        "mitsuba_version": mi.__version__, "variant": "scalar_rgb", "integrator": "direct",
        "material": f"brdf/rgl/{name}.bsdf", "env": f"env/ict_small/{ENV.name}", "env_up": "y",
        "env_rows": env.height, "upsample": args.upsample, "reference_upsample": args.ref_upsample,
        "size": args.size, "view": list(VIEW),
        "projection": "ortho", "spp": args.spp, "seeds": args.seeds, "envmap_check": check,
        "bands": [{k: r[k] for k in ("theta_v_deg", "pixels", "mitsuba", "noise", "pix_noise") if k in r}
                  | ({"mitsuba_pixels": [[float(f"{v:.6g}") for v in pixel] for pixel in runs.mean(axis=0)[
                      (scene.theta_v_deg >= r["theta_v_deg"][0]) & (scene.theta_v_deg < r["theta_v_deg"][1])]]}
                     if "mitsuba" in r else {}) for r in rows],
    }
    head = ",\n".join(f" {json.dumps(key)}: {json.dumps(value)}" for key, value in record.items() if key != "bands")
    bands = ",\n".join(f"  {json.dumps(band)}" for band in record["bands"])
    Path(args.record).write_text(f"{{\n{head},\n \"bands\": [\n{bands}\n ]\n}}\n")
    print(f"wrote {args.record}")


if __name__ == "__main__":
    main()
