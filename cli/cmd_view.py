"""``shrm view``: a self-contained HTML page that renders the SHRM of ENV and BRDF live (WebGL2).

Parse and check the options, prefilter (``analysis.shrm.prefilter``), build the page with
:func:`shrmkit.render.webgl_page.build_view` and write it. The page format, its size budget and
its URL parameters are in ``data_specs/view_html.md``.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from ..analysis.order_rule import OrderRule
from ..analysis.orders import choose_orders
from ..analysis.shrm import SHRM, prefilter
from ..brdf_io.atomic import check_writable
from ..brdf_io.envmap import EnvironmentMap
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
    out, budget, rotation = _checked_options(args)
    sources, _ = env_sources_arg(args.env)
    check_writable(out)
    envs = load_env_sequence(sources, args)  # every map read first: a bad one stops before any prefilter
    _, brdf, choice = load_analysis_brdf(args.brdf, args, quiet=args.json)  # scattered data: its representation
    if choice is not None and not args.json:
        say(choice.line())
    shrms = _prefiltered(args, envs, brdf)
    page = build_view(
        shrms[0], envs[0], mesh=args.mesh, mode=args.mode, exposure=args.exposure, tone=args.tone,
        azimuth=args.azimuth, elevation=args.elevation, zoom=args.zoom, background=not args.no_background,
        budget=budget, still=args.still, env_rotation=rotation, more=list(zip(shrms[1:], envs[1:], strict=True)),
    )
    text = page_html(page)
    write_view(out, text)
    page_bytes = len(text.encode("utf-8"))
    url = _page_url(out, args, rotation)
    if args.json:
        print_json({
            "environments": [_environment_record(one, env, args.eps) for one, env in zip(shrms, envs, strict=True)],
            "page": {**_page_record(page), "bytes": page_bytes, "budget_bytes": budget.page_bytes},
            "output": str(out), "url": url,
            "representation": None if choice is None else choice.as_dict(),
        })
        return 0
    for one, env in zip(shrms, envs, strict=True):
        say(("" if len(shrms) == 1 else f"{env.name}: ") + _shrm_line(one, args.eps))
    s, mesh = page.data["shrm"], page.data["mesh"]
    say(f"page: P={s['P']}, maps {s['height']}x{s['width']}, mesh {mesh['name']} {mesh['triangles']} triangles, "
        f"still image: {page.still_renderer}"
        + ("" if len(shrms) == 1 else f", {len(shrms)} environments (switched in the page, #env_index=K)"))
    for note in page.notes:
        say(f"note: {note}")
    say(f"wrote {out} ({page_bytes / 2**20:.2f} MiB of {budget.page_bytes / 2**20:g} MiB); open it "
        f"in a browser, e.g. {url}")
    return 0


def _checked_options(args: argparse.Namespace) -> tuple[Path, ViewBudget, tuple[float, float, float]]:
    """The output path (an ``.html`` name), the page's size budget and the environment's rotation
    (AZ, EL, ROLL) in degrees, checked before anything is loaded."""
    out = Path(args.output)
    if out.suffix.lower() not in (".html", ".htm"):
        raise BadInputError(out, "output must be an .html file")
    budget = ViewBudget(page_bytes=int(args.budget_mb * 2**20))
    rotation = env_rotation_angles(args.env_rotation) if args.env_rotation is not None else (0.0, 0.0, 0.0)
    if not -90.0 <= rotation[1] <= 90.0:
        raise BadInputError(None, f"--env-rotation: the page's elevation EL must be in [-90, 90] degrees, "
                            f"got {args.env_rotation!r}")
    return out, budget, rotation


def _prefiltered(args: argparse.Namespace, envs: list[EnvironmentMap], brdf: Any) -> list[SHRM]:
    """One SHRM per map under the options' order rule; the orders depend on the BRDF only, so a
    sequence of maps chooses them once."""
    rule = OrderRule(eps=args.eps, **order_rule(args))
    orders = choose_orders(brdf, rule=rule) if len(envs) > 1 else None
    return [prefilter(env, brdf, rule=rule, size=args.size, window=args.window, lights=args.lights,
                      pixel_rule=args.pixel_rule == "on", orders=orders) for env in envs]


def _page_url(out: Path, args: argparse.Namespace, rotation: tuple[float, float, float]) -> str:
    """The page's file URL with the view's and the rotation's URL parameters (``data_specs/view_html.md``)."""
    return (f"{out.resolve().as_uri()}#azimuth={args.azimuth:g}&elevation={args.elevation:g}"
            + ("" if args.env_rotation is None else f"&env_azimuth={rotation[0]:g}&env_elevation={rotation[1]:g}"
               + (f"&env_roll={rotation[2]:g}" if rotation[2] else "")))


def _environment_record(shrm: SHRM, env: EnvironmentMap, eps: float) -> dict[str, Any]:
    """One environment of ``--json``: the SHRM's orders, map, stated error and prefilter seconds."""
    info = shrm.info
    worst = info.stated_band()
    return {"environment": env.name, "F": shrm.F, "P": shrm.P, "height": shrm.height, "width": shrm.width,
            "eps": eps, "max_view_deg": info.max_view_deg, "stated_error": None if worst is None else worst.to_json(),
            "view_bands": [band.to_json() for band in info.view_bands], "lights": len(info.lights),
            "prefilter_seconds": info.timings.total}


def _page_record(page: Any) -> dict[str, Any]:
    """The page of ``--json``: its maps, mesh, still renderer and notes (sizes added by the caller)."""
    s, mesh = page.data["shrm"], page.data["mesh"]
    return {"P": s["P"], "height": s["height"], "width": s["width"], "mesh": mesh["name"],
            "triangles": mesh["triangles"], "still_renderer": page.still_renderer, "notes": list(page.notes)}


def _shrm_line(shrm: SHRM, eps: float) -> str:
    """The SHRM as the terminal reads it: orders, map, the worst stated band inside the view limit, lights."""
    info = shrm.info
    worst = info.stated_band()
    rms = 0.0 if worst is None or worst.predicted_rel_rms is None else worst.predicted_rel_rms
    lights = len(info.lights)
    return (f"SHRM F={shrm.F} P={shrm.P} on {shrm.height}x{shrm.width} (eps {eps:g}: predicted relative RMS "
            f"{rms:.3g} in the worst view band to {info.max_view_deg:g} degrees)"
            + (f", {lights} light(s) shaded exactly" if lights else ""))
