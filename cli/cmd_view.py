"""``shrm view``: a self-contained HTML page that renders the SHRM of ENV and BRDF live (WebGL2).

Parse and check the options, prefilter (``analysis.shrm.prefilter``), build the page with
:func:`shrmkit.render.webgl_page.build_view` and write it. The page format, its size budget and
its URL parameters are in ``data_specs/view_html.md``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from ..analysis.notebook import stated_band
from ..analysis.order_rule import OrderRule
from ..analysis.orders import choose_orders
from ..analysis.shrm import prefilter
from ..brdf_io.atomic import check_writable
from ..brdf_io.errors import BadInputError
from ..render.webgl_page import (
    ViewBudget,
    build_view,
    page_html,
    write_view,
)
from .common import (
    env_rotation_angles,
    env_sources_arg,
    load_analysis_brdf,
    load_env_sequence,
    order_rule,
    print_json,
    say,
)


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
    rule = OrderRule(eps=args.eps, **order_rule(args))
    # the orders depend on the BRDF only: chosen once for every map
    orders = choose_orders(brdf, rule=rule) if len(envs) > 1 else None
    shrms = [prefilter(env, brdf, rule=rule, size=args.size, window=args.window, lights=args.lights,
                       pixel_rule=args.pixel_rule == "on", orders=orders) for env in envs]
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
