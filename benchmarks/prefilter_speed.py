"""Frequency-space prefiltering against the best angular methods, each with its error (issue 22).

Every number printed is measured in this run on this machine, one core each (ducc0
``nthreads=1``, BLAS limited to one thread), times as CPU seconds of this process
(``time.process_time``) with the wall time beside them; the two differ when other work shares
the machine. Nothing is read back from saved output, nothing is hard-coded.

(a) **Speed against error.** For each task (environment, material) at ε = 0.03 and the same
    output — ``--views`` (default 100 = RH02 Table 5's 10 × 10) distant-viewer maps, B(R, V)
    at every pixel centre R of an S × 2S lat-long grid for one view direction V each — the
    competitors are:

    - ``bands``: shrmkit's default ``prefilter`` (bands rule, auto window, and light
      extraction where the library has it): the order choice, lights, lighting SHT, window,
      map synthesis and error statement are all in T_setup (``SHRM.meta["timings"]``); a map
      is ``SHRM.view_map(V)`` (plus the lights shaded at each pixel centre);
    - ``rh02``: RH02's rule unchanged (``criterion="rh02", window="none"``, no lights),
      the same way;
    - ``split-sum`` (GGX materials only): the engines' split sum (Karis 2013;
      ``analysis.baselines.split_sum``): T_setup is the GGX-prefiltered level (and irradiance
      map) of this environment; the environment-BRDF table is made once for every material
      and map and is not counted per task (its time is printed); a map is its lookup at the
      level's pixel centres;
    - ``truncated``: RH02 Table 4's baseline, the angular sum over only the pixels where the
      lobe exceeds 1e-3 of its peak (``analysis.baselines.lobe_truncated``) on the ``bands``
      map's S × 2S grid: T_setup is its cone table; its T_map is measured on
      ``--truncated-samples`` random (view, pixel) outputs and EXTRAPOLATED (marked ``*``).

    T_N = T_setup + N × T_map; ``× bands`` is T_N over the default's T_N (> 1: slower).
    Error: relative RMS against the brute-force sum over every pixel (``analysis.reference``,
    used only as the error reference: its time is printed as context, never as a ratio) on
    ``--per-band`` (R, V) pairs per view band inside the 80° limit (``analysis.compare.band_sample``:
    R importance-sampled from the map's bright pixels, R and θ_v stratified), per band with its
    standard error (``band_error``, which matches the spread over seeds); the worst band is shown
    beside the statement of that band (``SHRM.meta["view_bands"]``: predicted / bound relative RMS; for ``truncated``
    its rigorous bound, threshold × peak × flux outside the cone). **FLAG**: some band's
    measured error exceeds its prediction by more than ``--flag-se`` standard errors
    (``pred``), or exceeds its bound (``BOUND``); each flag is listed under the table.
(b) **ε sweep** (full run): ``bands`` against ``rh02`` at ε = 0.1, 0.03, 0.01 on two tasks.
(c) **Targets** (issue 22): order choice <= 0.3 s for an analytic model and <= 3 s for an RGL
    measured table (its reparameterization included), both on one core; the default prefilter
    within 3× of ``criterion="rh02", window="none"`` for builtin:sky + microfacet σ = 0.1 at
    ε = 0.03 and for venice_sunset at 1024 rows at ε = 0.01 (interleaved repeats, fastest of
    each); ``shrm report --quick`` <= 3 s CPU for an analytic spec and <= 5 s for the sharpest RGL
    file, <= 512 MiB peak (fresh processes, fastest of the repeats, beside the CPU of the imports
    alone). Each row: measured, target, met / NO, and for a NO what the run measured that
    explains it.

Run:  .venv/bin/python benchmarks/prefilter_speed.py [--quick] [--only speed sweep targets]
"""

from __future__ import annotations

import argparse
import cProfile
import inspect
import json
import os
import pstats
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from rich.console import Console
from rich.table import Table
from threadpoolctl import threadpool_limits

from shrmkit.analysis.baselines.lobe_truncated import lobe_truncated_sum
from shrmkit.analysis.baselines.split_sum import env_brdf_lut, split_sum
from shrmkit.analysis.compare import BandSample, band_error, band_sample
from shrmkit.analysis.orders import choose_orders
from shrmkit.analysis.reference import reference_radiance
from shrmkit.analysis.shrm import SHRM, prefilter
from shrmkit.analysis.view_bands import DEFAULT_BAND_EDGES_DEG
from shrmkit.brdf_io.envmap import EnvironmentMap, load_env
from shrmkit.brdf_io.latlong import pixel_angles, pixel_directions
from shrmkit.brdf_io.merl import write_merl
from shrmkit.brdf_io.specs import load_brdf

__all__ = ["main"]

ROOT = Path(__file__).resolve().parents[1]
DATA = next((p for p in (ROOT.parent / "shared" / "data", Path("/work/shared/data")) if p.is_dir()),
            ROOT.parent / "shared" / "data")
VENICE = DATA / "env" / "polyhaven_cc0" / "venice_sunset_1k.hdr"
GRACE = DATA / "env" / "grace_latlong.exr"
RGL = DATA / "brdf" / "rgl"
SHARPEST_RGL = "cc_iris_purple_gem_rgb.bsdf"
EPS = 0.03
MAX_VIEW_DEG = 80.0
EDGES = tuple(e for e in DEFAULT_BAND_EDGES_DEG if e <= MAX_VIEW_DEG)  # the bands inside the view limit
BRDFS = ["microfacet:sigma=0.1", "microfacet:sigma=0.3", "phong:s=32", "phong:s=512",
         "cook-torrance:alpha=0.1,dist=ggx", "cook-torrance:alpha=0.3,dist=ggx"]
QUICK_TASKS = [("sky", "microfacet:sigma=0.1"), ("sky", "phong:s=512"), ("venice", "cook-torrance:alpha=0.1,dist=ggx")]
ANALYTIC_TARGET_S, RGL_TARGET_S, RATIO_TARGET = 0.3, 3.0, 3.0
#: `shrm report --quick`: CPU seconds (analytic spec, measured table) and peak memory (issue 22)
QUICK_ANALYTIC_S, QUICK_TABLE_S, QUICK_PEAK_MB = 3.0, 5.0, 512
#: the analytic model tabulated at MERL's size for the MERL row of the quick-report targets
MERL_TABLE_SPEC = "cook-torrance:alpha=0.1,dist=ggx"
#: what every report loads before it computes anything (the floor under its CPU time)
REPORT_IMPORTS = ("import shrmkit.cli.cmd_report, shrmkit.cli.report.collect, shrmkit.cli.report.writer, "
                  "shrmkit.render.vtk_renderer, matplotlib.figure, matplotlib.backends.backend_agg, "
                  "vtkmodules.vtkRenderingOpenGL2")

console = Console(width=200, highlight=False)
HAS_LIGHTS = "lights" in inspect.signature(prefilter).parameters  # light extraction (issue 23) is in the library


# ----------------------------------------------------------------------------------------
# clocks and formatting
# ----------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Clock:
    """CPU seconds of this process and wall seconds."""

    cpu: float
    wall: float

    def __add__(self, other: Clock) -> Clock:
        return Clock(self.cpu + other.cpu, self.wall + other.wall)

    def __mul__(self, k: float) -> Clock:
        return Clock(self.cpu * k, self.wall * k)


def clocked(fn: Callable[[], Any]) -> tuple[Clock, Any]:
    c0, w0 = time.process_time(), time.perf_counter()
    value = fn()
    return Clock(time.process_time() - c0, time.perf_counter() - w0), value


def fmt_time(seconds: float) -> str:
    if not np.isfinite(seconds):
        return "—"
    if seconds < 0.9995e-3:
        return f"{seconds * 1e6:.3g} µs"
    if seconds < 0.9995:
        return f"{seconds * 1e3:.3g} ms"
    if seconds < 600:
        return f"{seconds:.3g} s"
    if seconds < 7200:
        return f"{seconds / 60:.3g} min"
    return f"{seconds / 3600:.3g} h"


def fmt_clock(c: Clock) -> str:
    return f"{fmt_time(c.cpu)} ({fmt_time(c.wall)})"


def fmt_bytes(n: float) -> str:
    for unit, size in (("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if n >= size:
            return f"{n / size:.3g} {unit}"
    return f"{n:.0f} B"


def fmt_err(x: float) -> str:
    return "—" if x is None or not np.isfinite(x) else f"{x:.3g}"


def fmt_ratio(x: float) -> str:
    return f"{x:,.0f}×" if x >= 100 else f"{x:.3g}×"


def short_name(spec: str) -> str:
    """``microfacet:sigma=0.1`` → ``mf σ=0.1``, ``cook-torrance:alpha=0.1,dist=ggx`` → ``ggx α=0.1``."""
    return (spec.replace("microfacet:sigma=", "mf σ=").replace("phong:s=", "phong s=")
            .replace("cook-torrance:alpha=", "ggx α=").replace(",dist=ggx", ""))


def band_name(band: list[float]) -> str:
    return f"{band[0]:g}-{band[1]:g}°"


# ----------------------------------------------------------------------------------------
# tasks
# ----------------------------------------------------------------------------------------
def make_env(name: str, height: int) -> EnvironmentMap | None:
    """builtin:sky, venice_sunset (y-up) or Grace (y-up, stored bottom row first) at ``height`` rows."""
    if name == "sky":
        return load_env(f"builtin:sky,height={height}")
    if name == "venice":
        return load_env(VENICE, up="y", height=height) if VENICE.is_file() else None
    if name == "grace":
        return load_env(GRACE, up="y", flip=True, height=height) if GRACE.is_file() else None
    raise ValueError(name)


def view_grid(T: int) -> np.ndarray:
    """T × T view directions at lat-long pixel centres over the sphere, (T², 3)."""
    theta, phi = pixel_angles(T, T)
    th, ph = np.meshgrid(theta, phi, indexing="ij")
    return np.stack([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)], axis=-1).reshape(-1, 3)


@dataclass
class Measured:
    """One competitor on one task."""

    method: str
    setup: Clock
    per_map: Clock
    nbytes: int
    bands: list[dict]  # per band inside the limit: theta_v_deg, measured_rel_rms, stderr, predicted, bound
    orders: str = ""
    grid: str = ""
    extrapolated: bool = False
    exact_bound: bool = False
    notes: list[str] = field(default_factory=list)

    def total(self, n_maps: int) -> Clock:
        return self.setup + self.per_map * n_maps

    def worst(self) -> dict:
        finite = [b for b in self.bands if np.isfinite(b["measured_rel_rms"])]
        return max(finite, key=lambda b: b["measured_rel_rms"]) if finite else {}

    def flags(self, k_se: float) -> list[Flag]:
        """Bands measured above their prediction by more than ``k_se`` standard errors, or above
        their bound (with the margin in standard errors; ``exact_bound``: a per-pair bound on the
        same pairs, which no sampling noise excuses)."""
        out = []
        for b in self.bands:
            m, se = b["measured_rel_rms"], b["stderr"]
            if not np.isfinite(m):
                continue
            name = band_name(b["theta_v_deg"])
            pred, bound = b.get("predicted"), b.get("bound")
            if pred is not None and m > pred + k_se * se:
                margin = (m - pred) / se if se > 0 else np.inf
                out.append(Flag("pred", f"{name}: measured {m:.3g} ± {se:.2g} > predicted {pred:.3g} "
                                        f"({margin:+.1f} s.e.)", margin))
            if bound is not None and m > bound:
                margin = np.inf if self.exact_bound or se == 0 else (m - bound) / se
                why = "(a per-pair bound: exact)" if self.exact_bound else f"({margin:+.1f} s.e.)"
                out.append(Flag("BOUND", f"{name}: measured {m:.3g} ± {se:.2g} > bound {bound:.3g} {why}", margin))
        return out


@dataclass(frozen=True)
class Flag:
    kind: str  # "pred" or "BOUND"
    text: str
    margin: float  # standard errors beyond the statement (inf: beyond any sampling noise)

    def cell(self) -> str:
        return f"{self.kind}{'(exact)' if np.isinf(self.margin) else f'+{self.margin:.1f}'}"


def measure_bands(value: np.ndarray, ref: np.ndarray, pairs: BandSample, stated: list[dict] | None = None
                  ) -> list[dict]:
    """Per band inside the limit: measured relative RMS ± s.e., beside the stated prediction/bound."""
    measured = band_error(value, ref, pairs)
    out = []
    for m in measured:
        row = {"theta_v_deg": m["theta_v_deg"], "measured_rel_rms": m["measured_rel_rms"], "stderr": m["stderr"]}
        for s in stated or ():
            if [float(x) for x in s["theta_v_deg"]] == m["theta_v_deg"] and s.get("inside", True):
                row["predicted"] = s.get("predicted_rel_rms")
                row["bound"] = s.get("bound_rel_rms")
        out.append(row)
    return out


def light_bytes(shrm: SHRM) -> int:
    lights = getattr(shrm, "lights", None)
    if lights is None:
        return 0
    return int(sum(getattr(lights, k).nbytes for k in ("directions", "power", "light") if hasattr(lights, k)))


def shrm_kwargs(method: str) -> dict:
    if method == "bands":
        return {}
    kw = {"criterion": "rh02", "window": "none"}
    if HAS_LIGHTS:
        kw["lights"] = "none"  # RH02 as published: the whole map in the SHRM
    return kw


def shrmkit_row(env: EnvironmentMap, brdf: Any, method: str, eps: float, views: np.ndarray, pairs: BandSample,
                ref: np.ndarray, n_time_views: int) -> tuple[Measured, SHRM]:
    """Prefilter (timed whole), view maps (timed on a few views), error per band."""
    setup, shrm = clocked(lambda: prefilter(env, brdf, eps=eps, nthreads=1, **shrm_kwargs(method)))
    S = shrm.height
    has_lights = bool(getattr(shrm, "has_lights", False))
    grid = pixel_directions(S, 2 * S).reshape(-1, 3)
    sample = views[:: max(1, len(views) // n_time_views)][:n_time_views]

    def maps(lights: bool) -> None:
        for v in sample:
            m = shrm.view_map(v)
            if lights:  # the lights are shaded per pixel beside the map (DESIGN §5a)
                m = m + shrm.light_radiance(grid, np.broadcast_to(v, grid.shape)).reshape(m.shape)

    t_maps, _ = clocked(lambda: maps(has_lights))
    bands = measure_bands(shrm.radiance(pairs.R, pairs.V), ref, pairs, shrm.meta.get("view_bands"))
    timings = shrm.meta["timings"]
    stages = ", ".join(f"{k} {fmt_time(v)}" for k, v in timings.items() if k != "total" and v >= 5e-4)
    notes = [f"T_setup stages (wall): {stages}", f"window: {shrm.meta.get('window_reason', '')}"]
    if has_lights:
        t_bare, _ = clocked(lambda: maps(False))
        notes.append(f"lights: {len(shrm.lights)} samples of {len(shrm.meta.get('lights', []))} light(s), "
                     f"{100 * float(shrm.meta.get('lights_flux_share', 0.0)):.3g} % of the flux; T_map without "
                     f"them {fmt_time(t_bare.cpu / len(sample))}")
    row = Measured(
        method=method, setup=setup, per_map=t_maps * (1.0 / len(sample)),
        nbytes=int(shrm.coeffs.nbytes) + light_bytes(shrm), bands=bands,
        orders=f"F={shrm.F} P={shrm.P}" + ("+L" if has_lights else ""), grid=f"{S}", notes=notes,
    )
    return row, shrm


def split_sum_row(env: EnvironmentMap, brdf: Any, lut: Any, views: np.ndarray, pairs: BandSample, ref: np.ndarray,
                  n_time_views: int) -> Measured:
    setup, ss = clocked(lambda: split_sum(env, brdf, lut=lut))
    sample = views[:: max(1, len(views) // n_time_views)][:n_time_views]
    t_maps, _ = clocked(lambda: [ss.view_map(v) for v in sample])
    rows = ss.levels[0][1].shape[0]
    return Measured(
        method="split-sum", setup=setup, per_map=t_maps * (1.0 / len(sample)), nbytes=ss.nbytes,
        bands=measure_bands(ss.radiance(pairs.R, pairs.V), ref, pairs),
        orders=f"LUT {ss.lut.mu.size}×{ss.lut.roughness.size}",
        grid=f"{rows}",
        notes=[f"setup: GGX level {fmt_time(ss.seconds['levels'])}, irradiance {fmt_time(ss.seconds['irradiance'])} "
               "(wall)"],
    )


def truncated_row(env: EnvironmentMap, brdf: Any, S: int, views: np.ndarray, pairs: BandSample, ref: np.ndarray,
                  n_samples: int, rng: np.random.Generator) -> Measured:
    setup, ts = clocked(lambda: lobe_truncated_sum(env, brdf))
    grid = pixel_directions(S, 2 * S).reshape(-1, 3)
    vi = rng.integers(len(views), size=n_samples)
    pi = rng.integers(grid.shape[0], size=n_samples)
    t_sample, (_, _, terms) = clocked(lambda: ts.radiance_and_bound(grid[pi], views[vi]))
    R, V, theta_v, w = pairs.R, pairs.V, pairs.theta_v, pairs.weights
    out, bound, _ = ts.radiance_and_bound(R, V)
    bands = measure_bands(out, ref, pairs)
    # its stated bound per band: |error| <= bound per pair and channel, so the band's relative RMS
    # is at most sqrt(Σ w bound² / Σ w ref²) on the same pairs
    deg = np.degrees(theta_v)
    for b in bands:
        lo, hi = b["theta_v_deg"]
        sel = (deg >= lo) & (deg < hi)
        den = float((w[sel, None] * ref[sel] ** 2).sum())
        b["bound"] = float(np.sqrt((w[sel, None] * bound[sel] ** 2).sum() / den)) if den > 0 else None
    lit = int(ts.lit.sum())
    cones = np.degrees(ts.cones.half_angle)
    # the same sum with the KD-tree cone query (scipy cKDTree.query_ball_point on the pixel directions)
    t_tree, kd = clocked(lambda: lobe_truncated_sum(env, brdf, cones=ts.cones, query="kdtree"))
    t_kd, _ = clocked(lambda: kd.radiance_and_bound(grid[pi], views[vi]))
    kd_note = (f"with the KD-tree cone query instead: T_map {fmt_time(t_kd.cpu * grid.shape[0] / n_samples)}* "
               f"(+ tree {fmt_time(t_tree.cpu)}); the lat-long row query is used above")
    return Measured(
        method="truncated", setup=setup, per_map=t_sample * (grid.shape[0] / n_samples), nbytes=ts.nbytes,
        bands=bands, orders=(f"cone {cones.min():.3g}°" if cones.min() == cones.max() else
                             f"cone {cones.min():.3g}-{cones.max():.3g}°"), grid=f"{S}", extrapolated=True,
        exact_bound=True,
        notes=[f"sums {terms / n_samples:.4g} pixels per output of {lit} lit ({100 * terms / n_samples / lit:.3g} %); "
               + kd_note],
    )


# ----------------------------------------------------------------------------------------
# (a) speed against error
# ----------------------------------------------------------------------------------------
def speed_table(tasks: list[tuple[str, str]], args: argparse.Namespace, lut: Any, title: str,
                eps_list: tuple[float, ...] = (EPS,), methods: tuple[str, ...] = ("bands", "rh02", "split-sum",
                                                                                   "truncated")) -> list[Flag]:
    n_maps = args.views
    views = view_grid(int(round(np.sqrt(n_maps)))) if int(round(np.sqrt(n_maps))) ** 2 == n_maps else \
        np.random.default_rng(args.seed).normal(size=(n_maps, 3))
    views = views / np.linalg.norm(views, axis=1, keepdims=True)
    table = Table(title=title, box=None, title_justify="left")
    for col, just in (("env", "left"), ("BRDF", "left"), ("ε", "right"), ("method", "left"), ("orders", "left"),
                      ("S", "right"), ("T_setup", "right"), ("T_map", "right"), (f"T_{n_maps}", "right"),
                      ("(wall)", "right"), ("×bands", "right"), ("stored", "right"), ("worst", "right"),
                      ("measured±se", "right"), ("pred/bound", "right"), ("FLAG", "left")):
        table.add_column(col, justify=just, no_wrap=True)
    flags: list[Flag] = []
    notes: list[str] = []
    envs: dict[str, EnvironmentMap | None] = {}
    rng = np.random.default_rng(args.seed)
    for env_name, spec in tasks:
        if env_name not in envs:
            envs[env_name] = make_env(env_name, args.env_height)
        env = envs[env_name]
        if env is None:
            notes.append(f"{env_name}: map not found under {DATA}, skipped")
            continue
        brdf = load_brdf(spec)
        pairs = band_sample(env.radiance, args.per_band, EDGES, seed=args.seed)
        t_ref, ref = clocked(lambda env=env, brdf=brdf, pairs=pairs: reference_radiance(env, brdf, pairs.R, pairs.V))
        short = short_name(spec)
        for eps in eps_list:
            rows: list[Measured] = []
            default = None
            for method in methods:
                if method in ("bands", "rh02"):
                    row, shrm = shrmkit_row(env, brdf, method, eps, views, pairs, ref, args.time_views)
                    if method == "bands":
                        default = shrm
                elif method == "split-sum":
                    if not (spec.startswith("cook-torrance") and "dist=ggx" in spec):
                        continue
                    row = split_sum_row(env, brdf, lut, views, pairs, ref, args.time_views)
                else:
                    row = truncated_row(env, brdf, default.height, views, pairs, ref, args.truncated_samples, rng)
                rows.append(row)
            base = rows[0].total(n_maps)
            for row in rows:
                row.notes.append("per band " + ", ".join(
                    f"{band_name(b['theta_v_deg'])} {fmt_err(b['measured_rel_rms'])}" for b in row.bands))
                worst = row.worst()
                row_flags = row.flags(args.flag_se)
                total = row.total(n_maps)
                stated = (f"{fmt_err(worst.get('predicted'))}/{fmt_err(worst.get('bound'))}" if worst else "—")
                star = "*" if row.extrapolated else ""
                table.add_row(
                    env_name, short, f"{eps:g}", row.method, row.orders, row.grid, fmt_time(row.setup.cpu),
                    fmt_time(row.per_map.cpu) + star, fmt_time(total.cpu) + star, f"({fmt_time(total.wall)})",
                    fmt_ratio(total.cpu / base.cpu), fmt_bytes(row.nbytes),
                    band_name(worst["theta_v_deg"]) if worst else "—",
                    f"{worst['measured_rel_rms']:.3g}±{worst['stderr']:.2g}" if worst else "—",
                    stated, " ".join(worst_flag_cells(row_flags)),
                )
                flags += [Flag(f.kind, f"{env_name} {short} ε={eps:g} {row.method}: {f.kind} {f.text}", f.margin)
                          for f in row_flags]
                notes += [f"{env_name} {short} ε={eps:g} {row.method}: {n}" for n in row.notes]
            n_pairs = len(pairs)
            notes.append(f"{env_name} {short}: brute force (error reference only) {fmt_clock(t_ref)} for {n_pairs} "
                         f"pairs = {fmt_time(t_ref.cpu / n_pairs * default.height * 2 * default.height)} CPU per "
                         f"{default.height}×{2 * default.height} map (extrapolated)")
            table.add_section()
        console.print(f"  done {env_name} {spec}", style="dim")
    console.print(table)
    console.print(f"  Times: CPU seconds of this process, one core (wall in brackets). S: the S×2S grid of a map. "
                  f"T_map: one distant-view map; * = EXTRAPOLATED from {args.truncated_samples} random (view, pixel) "
                  "outputs. +L: with explicit lights. stored: the float32 maps (+ lights) / levels + table / pixel "
                  f"arrays. worst: the θ_v band (inside {MAX_VIEW_DEG:g}°) of the largest relative RMS error against "
                  f"brute force on {args.per_band} pairs per band, ± one standard error; pred/bound: the statement of "
                  "that band (truncated: its per-pair bound). FLAG: pred+x / BOUND+x, x = standard errors beyond the "
                  "statement (the largest of the row's bands).", soft_wrap=True)
    if "split-sum" in methods:
        console.print(f"  split-sum environment-BRDF table: {lut.mu.size}×{lut.roughness.size}, "
                      f"{fmt_time(lut.seconds)} wall once for every GGX material and map (not in T_setup), "
                      f"{fmt_bytes(lut.nbytes)} (in stored).", soft_wrap=True)
    for n in notes:
        console.print(f"  · {n}", soft_wrap=True)
    if flags:
        console.print(f"  FLAGS (a band measured above its prediction by > {args.flag_se:g} s.e., or above its bound; "
                      "'+x' = x standard errors beyond it: below +2 it may be sampling noise, rerun with a larger "
                      "--per-band):", soft_wrap=True)
        for f in flags:
            console.print(f"  ! {f.text}", soft_wrap=True)
    else:
        console.print("  no row flagged.")
    return flags


def worst_flag_cells(flags: list[Flag]) -> list[str]:
    """One cell entry per kind of flag, with its largest margin."""
    cells = []
    for kind in ("BOUND", "pred"):
        of_kind = [f for f in flags if f.kind == kind]
        if of_kind:
            cells.append(max(of_kind, key=lambda f: f.margin).cell())
    return cells


# ----------------------------------------------------------------------------------------
# (c) targets
# ----------------------------------------------------------------------------------------
@dataclass
class Target:
    what: str
    measured: str
    target: str
    met: bool
    explanation: str = ""
    key: str = ""


def hot_spots(fn: Callable[[], Any], n: int = 3) -> str:
    """The ``n`` shrmkit functions with the most self time in one profiled call of ``fn``."""
    prof = cProfile.Profile()
    prof.runcall(fn)
    stats = pstats.Stats(prof).stats  # {(file, line, name): (cc, nc, tottime, cumtime, callers)}
    own = [(v[2], Path(k[0]).name, k[2]) for k, v in stats.items()
           if k[0].startswith(str(ROOT)) and not k[0].startswith((str(ROOT / ".venv"), str(ROOT / "benchmarks")))]
    own.sort(reverse=True)
    total = sum(v[2] for v in stats.values())
    return "profiled self time: " + ", ".join(f"{f}:{name} {fmt_time(t)}" for t, f, name in own[:n]) + \
        f" (of {fmt_time(total)})"


def target_orders(spec_or_path: str | Path, label: str, limit: float, repeats: int, loader: bool) -> Target:
    """Order choice on one core: min CPU over ``repeats`` fresh runs (an RGL file is loaded anew
    for each, outside the clock; its reparameterization happens inside ``choose_orders``)."""
    best, best_wall, o, t_load = np.inf, np.inf, None, np.inf
    for _ in range(repeats):
        t_l, brdf = clocked(lambda: load_brdf(spec_or_path))
        t_load = min(t_load, t_l.cpu)
        t, o = clocked(lambda brdf=brdf: choose_orders(brdf, eps=EPS))
        best, best_wall = min(best, t.cpu), min(best_wall, t.wall)
    met = best <= limit
    expl = ""
    if not met:
        g = o.grid
        expl = (f"final grid {g.n_theta_i}×{g.n_theta_o}×{g.n_phi} (θ_i', θ_o', φ'); "
                + hot_spots(lambda: choose_orders(load_brdf(spec_or_path), eps=EPS)))
    load_note = f"; file read {fmt_time(t_load)} CPU, not counted" if loader else ""
    return Target(f"order choice, {label}, ε={EPS:g}, one core → (F, P) = ({o.F}, {o.P})",
                  f"{fmt_time(best)} CPU ({fmt_time(best_wall)} wall){load_note}", f"<= {limit:g} s", met, expl,
                  key=f"orders {Path(str(spec_or_path)).name if loader else short_name(str(spec_or_path))}")


def target_ratio(env: EnvironmentMap, label: str, spec: str, eps: float, repeats: int) -> Target:
    """Default prefilter over RH02's bare rule (interleaved repeats, fastest CPU of each)."""
    brdf = load_brdf(spec)
    best: dict[str, tuple[float, float, SHRM]] = {}
    for _ in range(repeats):
        for method in ("bands", "rh02"):
            t, shrm = clocked(lambda method=method: prefilter(env, brdf, eps=eps, nthreads=1, **shrm_kwargs(method)))
            if method not in best or t.cpu < best[method][0]:
                best[method] = (t.cpu, t.wall, shrm)
    (c_d, w_d, d), (c_r, w_r, r) = best["bands"], best["rh02"]
    ratio = c_d / c_r
    met = ratio <= RATIO_TARGET
    expl = ""
    if not met:
        td, tr = d.meta["timings"], r.meta["timings"]
        diff = sorted(((td.get(k, 0.0) - tr.get(k, 0.0), k) for k in set(td) | set(tr) if k != "total"), reverse=True)
        parts = [f"{k} +{fmt_time(x)}" for x, k in diff[:2] if x > 0]
        reason = d.meta.get("window_reason", "")
        expl = f"default's extra time (wall): {', '.join(parts)}; default F={d.F} P={d.P} S={d.height} vs RH02 " \
               f"F={r.F} P={r.P} S={r.height}"
        if "raised" in reason:
            expl += f"; the window raised F_B ({reason.split(';')[0]}; {reason.split(';')[1].strip()})"
            if HAS_LIGHTS:
                expl += f"; lights taken out: {len(d.meta.get('lights', []))}"
            else:
                expl += " — the sun rings: light extraction (issue 23) takes it out of the map"
    what = (f"default prefilter / (rh02, window none{', lights none' if HAS_LIGHTS else ''}), {label}, {spec}, "
            f"ε={eps:g}, one core")
    measured = f"{ratio:.3g}× ({fmt_time(c_d)} / {fmt_time(c_r)} CPU; wall {fmt_time(w_d)} / {fmt_time(w_r)})"
    return Target(what, measured, f"<= {RATIO_TARGET:g}×", met, expl, key=f"prefilter ratio {label.split()[0]}")


#: run in a child: its own peak RSS (VmHWM of its address space; rusage's ru_maxrss of a child also
#: counts the parent's size at fork) on stderr at exit
_PEAK_AT_EXIT = ("import atexit, sys; atexit.register(lambda: sys.stderr.write(next(line for line in "
                 "open('/proc/self/status') if line.startswith('VmHWM'))))")


def _child_cost(code: str, *args: str) -> tuple[float, float]:
    """(CPU seconds, peak RSS MiB) of ``python -c CODE ARGS`` in a fresh process (os.wait4)."""
    proc = subprocess.Popen([sys.executable, "-c", f"{_PEAK_AT_EXIT}\n{code}", *args], stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, cwd=tempfile.gettempdir(), text=True)
    assert proc.stderr is not None
    err = proc.stderr.read()
    _, status, usage = os.wait4(proc.pid, 0)
    peak = [line.split()[1] for line in err.splitlines() if line.startswith("VmHWM")]
    if status != 0 or not peak:
        raise RuntimeError(f"{code} {' '.join(args)} failed with status {status}: {err[-500:]}")
    return usage.ru_utime + usage.ru_stime, int(peak[-1]) / 1024.0


#: run in a child: one quick report in this process, CPU seconds (every thread: process_time) of its
#: stages printed as one JSON line on stderr — where a quick report's time goes
_STAGES = """
import functools, importlib, json, os, sys, tempfile, time
t0 = time.process_time()
import shrmkit.cli.cmd_report, shrmkit.cli.report.collect, shrmkit.cli.report.writer
from shrmkit.cli.main import main
cpu = {"imports (report modules)": time.process_time() - t0}
STAGES = {"shrmkit.cli.report.collect": {"_fits": "fits", "explore": "BRDF views", "_orders": "orders",
                                         "_environments": "references and prefilters", "render_previews": "preview"},
          "shrmkit.cli.report.writer": {"_draw": "plots (matplotlib import included)"}}
def clocked(f, name):
    @functools.wraps(f)
    def run(*a, **k):
        t = time.process_time()
        try:
            return f(*a, **k)
        finally:
            cpu[name] = cpu.get(name, 0.0) + time.process_time() - t
    return run
for module, names in STAGES.items():
    mod = importlib.import_module(module)
    for attr, name in names.items():
        setattr(mod, attr, clocked(getattr(mod, attr), name))
shrmkit.cli.report.explorer.build_view = clocked(shrmkit.cli.report.explorer.build_view, "live view")
t1 = time.process_time()
with tempfile.TemporaryDirectory() as out:
    main(["report", "--quick", sys.argv[1], "--out", out, "-q", "--no-progress"])
cpu["rest (loading, checks, files)"] = time.process_time() - t1 - sum(v for k, v in cpu.items() if k[:7] != "imports")
print("STAGES " + json.dumps(cpu), file=sys.stderr)
"""


def _report_stages(spec: str) -> dict[str, float]:
    """CPU seconds by stage of one quick report of ``spec`` (:data:`_STAGES`, in a child process)."""
    proc = subprocess.run([sys.executable, "-c", _STAGES, spec], capture_output=True, text=True,
                          cwd=tempfile.gettempdir(), check=False)
    line = next((x for x in proc.stderr.splitlines() if x.startswith("STAGES ")), None)
    if proc.returncode != 0 or line is None:
        raise RuntimeError(f"stages of {spec} failed: {proc.stderr[-500:]}")
    return json.loads(line[len("STAGES "):])


def target_quick_report(spec: str, label: str, limit_s: float, repeats: int) -> Target:
    """``shrm report --quick SPEC`` in a fresh process: min CPU (user + sys) and peak RSS over
    ``repeats`` runs, beside the CPU of the imports alone (what no report can go below)."""
    costs = []
    for _ in range(repeats):
        with tempfile.TemporaryDirectory() as out:
            costs.append(_child_cost("from shrmkit.cli.main import console_main; console_main()", "report",
                                     "--quick", spec, "--out", out, "-q", "--no-progress"))
    cpu, peak = min(c[0] for c in costs), min(c[1] for c in costs)
    imports = min(_child_cost(REPORT_IMPORTS)[0] for _ in range(repeats))
    met = cpu <= limit_s and peak <= QUICK_PEAK_MB
    stages = _report_stages(spec)
    where = ", ".join(f"{name} {fmt_time(sec)}" for name, sec in sorted(stages.items(), key=lambda kv: -kv[1])
                      if sec >= 0.05)
    return Target(f"shrm report --quick, {label}", f"{fmt_time(cpu)} CPU, {peak:.0f} MiB peak",
                  f"<= {limit_s:g} s, <= {QUICK_PEAK_MB} MiB", met,
                  f"the imports alone (report modules, matplotlib, VTK): {fmt_time(imports)} CPU; by stage (CPU, "
                  f"one run in-process): {where}",
                  key=f"quick report {label.split()[0]}")


def targets_table(args: argparse.Namespace) -> list[Target]:
    repeats = 2 if args.quick else 3
    rows: list[Target] = []
    analytic = ["microfacet:sigma=0.1", "cook-torrance:alpha=0.1,dist=ggx"] if args.quick else BRDFS
    for spec in analytic:
        rows.append(target_orders(spec, f"analytic {spec}", ANALYTIC_TARGET_S, 3, False))
        console.print(f"  done orders {spec}", style="dim")
    files = sorted(RGL.glob("*.bsdf")) if RGL.is_dir() else []
    if args.quick:
        files = [f for f in files if f.name == SHARPEST_RGL] or files[:1]
    for path in files:
        rows.append(target_orders(path, f"RGL table {path.name}", RGL_TARGET_S, 3, True))
        console.print(f"  done orders {path.name}", style="dim")
    if not files:
        rows.append(Target("order choice, RGL table", "not measured", f"<= {RGL_TARGET_S:g} s", False,
                           f"no .bsdf files under {RGL}"))
    rows.append(target_ratio(load_env("builtin:sky"), "builtin:sky 256×512", "microfacet:sigma=0.1", EPS, repeats))
    console.print("  done sky ratio", style="dim")
    if VENICE.is_file():
        t_load, venice = clocked(lambda: load_env(VENICE, up="y", height=1024))
        rows.append(target_ratio(venice, f"venice_sunset 1024×2048 (read {fmt_time(t_load.cpu)})",
                                 "microfacet:sigma=0.1", 0.01, repeats))
        console.print("  done venice ratio", style="dim")
    else:
        rows.append(Target("default prefilter / rh02, venice_sunset", "not measured", f"<= {RATIO_TARGET:g}×", False,
                           f"{VENICE} not found"))
    rows.append(target_quick_report("microfacet:sigma=0.1", "analytic microfacet:sigma=0.1", QUICK_ANALYTIC_S,
                                    repeats))
    console.print("  done quick report (analytic)", style="dim")
    if files:
        sharpest = next((f for f in files if f.name == SHARPEST_RGL), files[0])
        rows.append(target_quick_report(str(sharpest), f"RGL table {sharpest.name}", QUICK_TABLE_S, repeats))
        console.print("  done quick report (RGL)", style="dim")
    # a MERL-size table (90 × 90 × 180 samples, 35 MB): issue 22's row "quick report of a MERL-size GGX
    # table", written here from the model (no MERL file is in ../shared/data)
    with tempfile.TemporaryDirectory() as folder:
        merl = write_merl(Path(folder) / "ggx_alpha0.1.binary", load_brdf(MERL_TABLE_SPEC))
        rows.append(target_quick_report(str(merl), f"MERL table of {MERL_TABLE_SPEC}", QUICK_TABLE_S, repeats))
    console.print("  done quick report (MERL)", style="dim")
    table = Table(title="(c) targets of issue 22 (measured in this run)", box=None, title_justify="left")
    for col in ("what", "measured", "target", "met", "why not (measured)"):
        table.add_column(col, justify="left", overflow="fold")
    for t in rows:
        table.add_row(t.what, t.measured, t.target, "met" if t.met else "NO", t.explanation)
    console.print(table)
    return rows


# ----------------------------------------------------------------------------------------
def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="three tasks, fewer pairs and repeats (about a minute)")
    parser.add_argument("--only", nargs="+", choices=("speed", "sweep", "targets"), default=None,
                        help="run only these tables (default: speed and targets; sweep too in a full run)")
    parser.add_argument("--env-height", type=int, default=128, help="environment rows for (a), (b) (default 128)")
    parser.add_argument("--per-band", type=int, default=None, help="brute-force pairs per view band (40 quick, 150)")
    parser.add_argument("--views", type=int, default=100, help="distant-view maps per task (default 100 = 10×10)")
    parser.add_argument("--time-views", type=int, default=10, help="view maps timed per method (default 10)")
    parser.add_argument("--truncated-samples", type=int, default=None,
                        help="outputs the truncated sum is timed on (300 quick, 1500)")
    parser.add_argument("--flag-se", type=float, default=1.0,
                        help="flag a band measured above its prediction by more than this many standard errors")
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args(argv)
    args.per_band = args.per_band or (60 if args.quick else 150)
    args.truncated_samples = args.truncated_samples or (300 if args.quick else 1500)
    only = set(args.only or (["speed", "targets"] if args.quick else ["speed", "sweep", "targets"]))
    w0, c0 = time.perf_counter(), time.process_time()
    console.print(f"prefilter_speed: {'quick' if args.quick else 'full'} run, {time.strftime('%Y-%m-%d %H:%M')}; "
                  f"one core (ducc0 nthreads=1, BLAS 1 thread); data {DATA}; light extraction in the library: "
                  f"{'yes' if HAS_LIGHTS else 'no'}.")
    flags: list[Flag] = []
    targets: list[Target] = []
    with threadpool_limits(1):
        lut = env_brdf_lut() if only & {"speed", "sweep"} else None
        if "speed" in only:
            tasks = QUICK_TASKS if args.quick else [(e, b) for e in ("sky", "venice", "grace") for b in BRDFS]
            flags += speed_table(tasks, args, lut, f"(a) speed against error at ε = {EPS:g}, environments at "
                                 f"{args.env_height}×{2 * args.env_height}, {args.views} distant-view maps per task")
        if "sweep" in only:
            flags += speed_table([("sky", "microfacet:sigma=0.1"), ("sky", "cook-torrance:alpha=0.1,dist=ggx")],
                                 args, lut, "(b) ε sweep: bands against rh02", eps_list=(0.1, 0.03, 0.01),
                                 methods=("bands", "rh02"))
        if "targets" in only:
            targets = targets_table(args)
    missed = [t for t in targets if not t.met]
    beyond = sum(f.margin > 2.0 for f in flags)
    console.print(f"summary: {len(flags)} flag(s), {beyond} more than 2 s.e. beyond the statement; targets met "
                  f"{len(targets) - len(missed)} of {len(targets)}"
                  + (f" (NO: {'; '.join(t.key or t.what for t in missed)})" if missed else "")
                  + f"; benchmark {time.process_time() - c0:.1f} s CPU, {time.perf_counter() - w0:.1f} s wall",
                  soft_wrap=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
