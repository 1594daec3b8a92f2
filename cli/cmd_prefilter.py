"""``shrm prefilter``: environment + BRDF -> global SHRM file ([RH02] §4–5).

Reference: [RH02] (``data_specs/bibliography.md``).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from rich.progress import Progress, SpinnerColumn, TextColumn, TimeElapsedColumn
from rich.table import Table

from ..analysis.order_rule import OrderRule
from ..analysis.pixels import pixel_line
from ..analysis.shrm import prefilter
from ..brdf_io.atomic import check_writable
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
    out = Path(args.output)
    if not out.name.endswith(".npz"):
        raise BadInputError(out, "the SHRM output must end in .shrm.npz (or .npz)")
    if args.cube_size is not None and not args.cube:
        raise BadInputError(None, "--cube-size needs --cube")
    if args.size is not None:  # memory plan (data_specs/limits.md): 2.4 GB measured at 6000 rows, 33 B a map pixel
        check_memory(f"--size {args.size}", 40 * 2 * args.size**2, f"an SHRM map of {args.size} x {2 * args.size}")
    check_writable(out)
    env = load_env_arg(args.env, args)
    source_brdf, brdf, choice = load_analysis_brdf(args.brdf, args, quiet=args.json)
    with Progress(SpinnerColumn(), TextColumn("{task.description}"), TimeElapsedColumn(), console=stderr,
                  disable=not progress_shown(args)) as bar:
        task = bar.add_task("prefiltering", total=None)
        shrm = prefilter(
            env, brdf, rule=OrderRule(eps=args.eps, max_F=args.max_F, max_P=args.max_P, **order_rule(args)),
            size=args.size, cube=args.cube, cube_size=args.cube_size, window=args.window, lights=args.lights,
            pixel_rule=args.pixel_rule == "on",
            progress=lambda stage: bar.update(task, description=f"prefiltering: {stage}"),
        )
    shrm.save(out)
    if args.json:
        print_json({"output": str(out), "F": shrm.F, "P": shrm.P, "height": shrm.height, "width": shrm.width,
                    "eps": shrm.eps, "bytes": out.stat().st_size, "meta": shrm.meta,
                    "representation": None if choice is None else choice.as_dict()})
        return 0
    if choice is not None:
        stdout.print(choice.line(), markup=False, soft_wrap=True)
    table = Table(title=f"SHRM {source_brdf.name} x {env.name}")
    for key in ("F", "P", "map", "lights", "eps brdf", "eps reflected", "bound", "total s", "MB"):
        table.add_column(key, justify="right")
    t = shrm.meta["timings"]
    n_lights = len(shrm.meta["lights"])
    assert not n_lights or shrm.lights is not None  # the meta describes the SHRM's own lights
    light_samples = 0 if shrm.lights is None else len(shrm.lights)
    table.add_row(
        str(shrm.F), str(shrm.P), f"{shrm.height}x{shrm.width}",
        f"{n_lights} ({light_samples} samples)" if n_lights else "0", f"{shrm.eps['brdf']:.3g}",
        f"{shrm.eps['reflected']:.3g}", f"{shrm.eps['bound']:.3g}", f"{t['total']:.3f}",
        f"{out.stat().st_size / 1e6:.2f}",
    )
    print_table(table)
    stdout.print("time by stage (s): " + ", ".join(f"{key} {value:.3f}" for key, value in t.items() if key != "total"),
                 markup=False, soft_wrap=True)
    if n_lights:
        lights = Table(title=f"lights taken out of the map ({shrm.meta['lights_flux_share']:.1%} of its flux), "
                             "shaded exactly")
        for key in ("elevation", "azimuth", "radius", "flux share", "RGB power", "pixels", "samples", "merge"):
            lights.add_column(key, justify="right")
        for light in shrm.meta["lights"]:
            lights.add_row(f"{light['elevation_deg']:.2f}°", f"{light['azimuth_deg']:.2f}°",
                           f"{light['radius_deg']:.2f}°", f"{light['flux_share']:.2%}",
                           " ".join(f"{x:.3g}" for x in light["power"]), str(light["pixels"]), str(light["samples"]),
                           f"{light['merge_deg']:.2f}°" if light["merge_deg"] else "exact")
        print_table(lights)
    limit = f"view limit {shrm.meta['max_view_deg']:g}°, rule {shrm.meta['criterion']}"
    print_view_bands(shrm.meta["view_bands"], f"error by view band ({limit})")
    if shrm.cube is not None:
        stdout.print(f"cube map: 6 x {shrm.cube.shape[2]}^2 texels, {t['cube']:.3f} s")
    meta = shrm.meta
    before = "not measured" if meta["negative_before"] is None else f"{meta['negative_before']:.3%}"
    used = meta["window"] if meta["window"] == "none" else f"{meta['window']} x{meta['window_strength']:.3g}"
    stdout.print(f"window: {used} ({meta['window_reason']})", markup=False, soft_wrap=True)
    stdout.print(pixel_line(meta), markup=False, soft_wrap=True)
    stdout.print(f"undershoot (most negative radiance / peak): before {before}, after {meta['negative_after']:.3%}; "
                 f"eps reflected {shrm.eps['reflected']:.3g} includes the window's {meta['window_cost']:.3g}",
                 markup=False, soft_wrap=True)
    if shrm.meta.get("capped"):
        stdout.print(f"[yellow]capped:[/yellow] eps {shrm.tolerance:g} is not met in every view band inside the "
                     f"limit ({in_cli_terms(', '.join(shrm.meta['capped_by']))})", soft_wrap=True)
    if shrm.meta.get("orders_message"):
        stdout.print(f"[yellow]note:[/yellow] {in_cli_terms(shrm.meta['orders_message'])}")
    stdout.print(f"wrote {out}")
    return 0
