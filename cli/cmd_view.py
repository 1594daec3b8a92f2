"""``shrm view``: a self-contained HTML page that renders the SHRM of ENV and BRDF live (WebGL2).

Parse and check the options, prefilter (``analysis.shrm.prefilter``), build the page with
:func:`shrmkit.render.webgl_page.build_view` and write it. The page format, its size budget and
its URL parameters are in ``data_specs/view_html.md``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from ..analysis.notebook import stated_band
from ..analysis.orders import choose_orders
from ..analysis.shrm import prefilter
from ..analysis.tolerance import DEFAULT_EPS
from ..brdf_io.atomic import check_writable
from ..brdf_io.errors import BadInputError
from ..render.output import TONE_MAPS
from ..render.webgl_page import (
    DEFAULT_MESH,
    DEFAULT_VIEW,
    STILL_RENDERERS,
    VIEW_MODES,
    ViewBudget,
    build_view,
    page_html,
    write_view,
)
from .common import (
    add_env_orientation,
    add_lights_option,
    add_order_rule,
    add_pixel_rule_option,
    add_rgl_incident,
    add_window_option,
    env_rotation_angles,
    env_sources_arg,
    load_analysis_brdf,
    load_env_sequence,
    number_in,
    order_rule,
    print_json,
    say,
    tolerance,
)

HELP = "write a self-contained HTML page that renders the SHRM of ENV and BRDF live in the browser (WebGL2)"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("brdf", metavar="BRDF", help="BRDF spec or file")
    p.add_argument("--env", nargs="+", default=["builtin:sky"], metavar="ENV",
                   help="environment map spec or file (default builtin:sky); several maps, a folder of maps or a "
                   "glob pattern: the page switches between them without reloading (an environment menu, "
                   "#env_index=K), the BRDF's orders chosen once")
    p.add_argument("--env-rotation", default=None, metavar="AZ,EL[,ROLL]",
                   help="the lighting's starting rotation, degrees, as shrm render --env-rotation (the page's "
                   "#env_azimuth=&env_elevation=&env_roll=; the still image shows it too)")
    p.add_argument("--mesh", default=None,
                   help=f"mesh file or builtin: spec (default {DEFAULT_MESH}); decimated to the page's mesh budget")
    p.add_argument("--eps", type=tolerance, default=DEFAULT_EPS,
                   help=f"SHRM tolerance epsilon (default {DEFAULT_EPS:g})")
    p.add_argument("--size", type=number_in(8, 1024, integer=True), default=None, metavar="S",
                   help="SHRM rows S (S x 2S lat-long) for the prefilter; default: what the error needs "
                   "(shrm prefilter), then lowered to fit the page")
    add_window_option(p)
    add_pixel_rule_option(p)
    add_lights_option(p)
    add_order_rule(p)
    p.add_argument("--mode", choices=VIEW_MODES, default="distant", help="initial render mode (default distant)")
    p.add_argument("--exposure", type=number_in(-30.0, 30.0, unit=" stops"), default=None,
                   help="initial exposure in stops (default: the environment's mean brought to middle grey)")
    p.add_argument("--tone", choices=TONE_MAPS, default="filmic", help="tone mapping (default filmic)")
    p.add_argument("--azimuth", type=number_in(-360.0, 360.0, unit=" degrees"), default=DEFAULT_VIEW["azimuth"],
                   help=f"initial camera azimuth about z from +x, degrees (default {DEFAULT_VIEW['azimuth']:g})")
    p.add_argument("--elevation", type=number_in(-89.0, 89.0, unit=" degrees"), default=DEFAULT_VIEW["elevation"],
                   help=f"initial camera elevation, degrees (default {DEFAULT_VIEW['elevation']:g})")
    p.add_argument("--zoom", type=number_in(0.25, 10.0), default=DEFAULT_VIEW["zoom"], help="initial zoom (default 1)")
    p.add_argument("--no-background", action="store_true", help="start with a black background (the page toggles it)")
    default_mb = ViewBudget().page_bytes / 2**20
    p.add_argument("--budget-mb", type=number_in(0.25, 1024.0, unit=" MiB"), default=default_mb,
                   help=f"size budget of the page in MiB (default {default_mb:g}); the SHRM maps are reduced to fit")
    p.add_argument("--still", choices=STILL_RENDERERS, default="auto",
                   help="renderer of the still image shown without WebGL2: cpu (CPU reference, sphere), gl (VTK "
                   "offscreen, the mesh), auto (cpu for the sphere, gl for a mesh when available), none")
    p.add_argument("-o", "--output", required=True, help="output .html page")
    p.add_argument("--json", action="store_true",
                   help="print one JSON object (each map's SHRM and stated error, the page, the file written; "
                   "data_specs/view_html.md) instead of the text lines")
    add_env_orientation(p)
    add_rgl_incident(p)


def run(args: argparse.Namespace) -> int:
    out = Path(args.output)
    if out.suffix.lower() not in (".html", ".htm"):
        raise BadInputError(out, "output must be an .html file")
    budget = ViewBudget(page_bytes=int(args.budget_mb * 2**20))
    rotation = env_rotation_angles(args.env_rotation) if args.env_rotation is not None else (0.0, 0.0, 0.0)
    if not -90.0 <= rotation[1] <= 90.0:
        raise BadInputError(None, f"--env-rotation: the page's elevation EL must be in [-90, 90] degrees, "
                            f"got {args.env_rotation!r}")
    sources, _ = env_sources_arg(args.env)
    check_writable(out)
    envs = load_env_sequence(sources, args)  # every map read first: a bad one stops before any prefilter
    _, brdf, choice = load_analysis_brdf(args.brdf, args, quiet=args.json)  # scattered data: its representation
    if choice is not None and not args.json:
        say(choice.line())
    rule = order_rule(args)
    # the orders depend on the BRDF only: chosen once for every map
    orders = choose_orders(brdf, eps=args.eps, **rule) if len(envs) > 1 else None
    shrms = [prefilter(env, brdf, eps=args.eps, size=args.size, window=args.window, lights=args.lights,
                       pixel_rule=args.pixel_rule == "on", orders=orders, **rule) for env in envs]
    shrm, env = shrms[0], envs[0]
    page = build_view(
        shrm, env, mesh=args.mesh, mode=args.mode, exposure=args.exposure, tone=args.tone, azimuth=args.azimuth,
        elevation=args.elevation, zoom=args.zoom, background=not args.no_background, budget=budget, still=args.still,
        env_rotation=rotation, more=list(zip(shrms[1:], envs[1:], strict=True)),
    )
    text = page_html(page)
    write_view(out, text)
    s = page.data["shrm"]
    mesh = page.data["mesh"]
    page_bytes = len(text.encode("utf-8"))
    url = (f"{out.resolve().as_uri()}#azimuth={args.azimuth:g}&elevation={args.elevation:g}"
           + ("" if args.env_rotation is None else f"&env_azimuth={rotation[0]:g}&env_elevation={rotation[1]:g}"
              + (f"&env_roll={rotation[2]:g}" if rotation[2] else "")))
    if args.json:
        print_json({
            "environments": [{
                "environment": env.name, "F": one.F, "P": one.P, "height": one.height, "width": one.width,
                "eps": args.eps, "max_view_deg": one.meta["max_view_deg"], "stated_error": stated_band(one.meta),
                "view_bands": one.meta["view_bands"], "lights": len(one.meta["lights"]),
                "prefilter_seconds": one.meta["timings"]["total"],
            } for one, env in zip(shrms, envs, strict=True)],
            "page": {"P": s["P"], "height": s["height"], "width": s["width"], "mesh": mesh["name"],
                     "triangles": mesh["triangles"], "still_renderer": page.still_renderer, "notes": list(page.notes),
                     "bytes": page_bytes, "budget_bytes": budget.page_bytes},
            "output": str(out), "url": url,
            "representation": None if choice is None else choice.as_dict(),
        })
        return 0
    for one, env in zip(shrms, envs, strict=True):
        worst = max((band["predicted_rel_rms"] for band in one.meta["view_bands"] if band["inside"]), default=0.0)
        lights = len(one.meta["lights"])
        say(("" if len(shrms) == 1 else f"{env.name}: ")
            + f"SHRM F={one.F} P={one.P} on {one.height}x{one.width} (eps {args.eps:g}: predicted relative RMS "
            f"{worst:.3g} in the worst view band to {one.meta['max_view_deg']:g} degrees)"
            + (f", {lights} light(s) shaded exactly" if lights else ""))
    say(f"page: P={s['P']}, maps {s['height']}x{s['width']}, mesh {mesh['name']} {mesh['triangles']} triangles, "
        f"still image: {page.still_renderer}"
        + ("" if len(shrms) == 1 else f", {len(shrms)} environments (switched in the page, #env_index=K)"))
    for note in page.notes:
        say(f"note: {note}")
    say(f"wrote {out} ({page_bytes / 2**20:.2f} MiB of {budget.page_bytes / 2**20:g} MiB); open it "
        f"in a browser, e.g. {url}")
    return 0
