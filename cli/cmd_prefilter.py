"""``shrm prefilter``: environment + BRDF -> global SHRM file ([RH02] §4–5).

Reference: [RH02] (``data_specs/bibliography.md``).
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from rich.progress import Progress, SpinnerColumn, TextColumn, TimeElapsedColumn
from rich.table import Table

from ..analysis.order_rule import OrderRule
from ..analysis.pixels import pixel_line
from ..analysis.records import LightsInfo
from ..analysis.shrm import SHRM, prefilter
from ..brdf_io.atomic import check_writable
from ..brdf_io.envmap import EnvironmentMap
from ..brdf_io.errors import BadInputError
from ..brdf_io.limits import check_memory
from .common import (
    in_cli_terms,
    load_analysis_brdf,
    load_env_arg,
    order_rule,
    print_json,
    print_table,
    progress_shown,
    stderr,
    stdout,
)
from .view_bands_table import print_view_bands


def run(args: argparse.Namespace) -> int:
    out = _checked_output(args)
    env = load_env_arg(args.env, args)
    source_brdf, brdf, choice = load_analysis_brdf(args.brdf, args, quiet=args.json)
    shrm = _prefiltered(args, env, brdf)
    shrm.save(out)
    if args.json:
        print_json({"output": str(out), "F": shrm.F, "P": shrm.P, "height": shrm.height, "width": shrm.width,
                    "eps": shrm.eps, "bytes": out.stat().st_size, "meta": shrm.meta,
                    "representation": None if choice is None else choice.as_dict()})
        return 0
    if choice is not None:
        stdout.print(choice.line(), markup=False, soft_wrap=True)
    _print_summary(shrm, out, f"SHRM {source_brdf.name} x {env.name}")
    if shrm.info.lights:
        _print_lights(shrm.info.lights)
    info = shrm.info
    print_view_bands([band.to_json() for band in info.view_bands],
                     f"error by view band (view limit {info.max_view_deg:g}°, rule {info.criterion})")
    if shrm.cube is not None:
        stdout.print(f"cube map: 6 x {shrm.cube.shape[2]}^2 texels, {info.timings.cube:.3f} s")
    _print_window(shrm)
    if info.capped:
        stdout.print(f"[yellow]capped:[/yellow] eps {shrm.tolerance:g} is not met in every view band inside the "
                     f"limit ({in_cli_terms(', '.join(info.capped_by))})", soft_wrap=True)
    if info.orders_message:
        stdout.print(f"[yellow]note:[/yellow] {in_cli_terms(info.orders_message)}")
    stdout.print(f"wrote {out}")
    return 0


def _checked_output(args: argparse.Namespace) -> Path:
    """The output path, checked with the options that size it before anything is loaded: a
    ``.npz`` name, ``--cube-size`` only with ``--cube``, the memory of ``--size``, a writable place."""
    out = Path(args.output)
    if not out.name.endswith(".npz"):
        raise BadInputError(out, "the SHRM output must end in .shrm.npz (or .npz)")
    if args.cube_size is not None and not args.cube:
        raise BadInputError(None, "--cube-size needs --cube")
    if args.size is not None:  # memory plan (data_specs/limits.md): 2.4 GB measured at 6000 rows, 33 B a map pixel
        check_memory(f"--size {args.size}", 40 * 2 * args.size**2, f"an SHRM map of {args.size} x {2 * args.size}")
    check_writable(out)
    return out


def _prefiltered(args: argparse.Namespace, env: EnvironmentMap, brdf: Any) -> SHRM:
    """``prefilter`` with the options' order rule, size, cube, window, lights and pixel rule, its
    stages on a spinner (stderr)."""
    rule = OrderRule(eps=args.eps, max_F=args.max_F, max_P=args.max_P, **order_rule(args))
    with Progress(SpinnerColumn(), TextColumn("{task.description}"), TimeElapsedColumn(), console=stderr,
                  disable=not progress_shown(args)) as bar:
        task = bar.add_task("prefiltering", total=None)
        return prefilter(
            env, brdf, rule=rule, size=args.size, cube=args.cube, cube_size=args.cube_size, window=args.window,
            lights=args.lights, pixel_rule=args.pixel_rule == "on",
            progress=lambda stage: bar.update(task, description=f"prefiltering: {stage}"),
        )


def _print_summary(shrm: SHRM, out: Path, title: str) -> None:
    """The table of orders, map, lights, errors, seconds and file size; the seconds by stage."""
    table = Table(title=title)
    for key in ("F", "P", "map", "lights", "eps brdf", "eps reflected", "bound", "total s", "MB"):
        table.add_column(key, justify="right")
    timings = shrm.info.timings
    n_lights = len(shrm.info.lights)
    assert not n_lights or shrm.lights is not None  # the meta describes the SHRM's own lights
    light_samples = 0 if shrm.lights is None else len(shrm.lights)
    table.add_row(
        str(shrm.F), str(shrm.P), f"{shrm.height}x{shrm.width}",
        f"{n_lights} ({light_samples} samples)" if n_lights else "0", f"{shrm.eps['brdf']:.3g}",
        f"{shrm.eps['reflected']:.3g}", f"{shrm.eps['bound']:.3g}", f"{timings.total:.3f}",
        f"{out.stat().st_size / 1e6:.2f}",
    )
    print_table(table)
    stages = ", ".join(f"{key} {value:.3f}" for key, value in timings.to_json().items() if key != "total")
    stdout.print("time by stage (s): " + stages, markup=False, soft_wrap=True)


def _print_lights(lights: LightsInfo) -> None:
    """The table of the lights taken out of the map (``data_specs/lights.md``)."""
    table = Table(title=f"lights taken out of the map ({lights.flux_share:.1%} of its flux), shaded exactly")
    for key in ("elevation", "azimuth", "radius", "flux share", "RGB power", "pixels", "samples", "merge"):
        table.add_column(key, justify="right")
    for light in lights.lights:
        table.add_row(f"{light['elevation_deg']:.2f}°", f"{light['azimuth_deg']:.2f}°",
                      f"{light['radius_deg']:.2f}°", f"{light['flux_share']:.2%}",
                      " ".join(f"{x:.3g}" for x in light["power"]), str(light["pixels"]), str(light["samples"]),
                      f"{light['merge_deg']:.2f}°" if light["merge_deg"] else "exact")
    print_table(table)


def _print_window(shrm: SHRM) -> None:
    """The window and why, the per-pixel statement, the undershoot before and after the window."""
    window = shrm.info.window
    before = "not measured" if window.negative_before is None else f"{window.negative_before:.3%}"
    stdout.print(f"window: {window.describe()} ({window.reason})", markup=False, soft_wrap=True)
    stdout.print(pixel_line(shrm.info), markup=False, soft_wrap=True)
    stdout.print(f"undershoot (most negative radiance / peak): before {before}, after {window.negative_after:.3%}; "
                 f"eps reflected {shrm.eps['reflected']:.3g} includes the window's {window.cost:.3g}",
                 markup=False, soft_wrap=True)
