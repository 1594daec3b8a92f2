"""``shrm orders``: how many coefficients a BRDF needs ([RH02] §5.1); its parser is ``options_orders.py``.

Scattered measurements (CURET, Cornell, gonioreflectometer CSV) are analysed through the
representation with the smallest held-out worst-view-band error (``cli.common.load_analysis_brdf``,
``data_specs/representation_json.md``); its line is printed before the orders and ``--json``
carries it as ``representation``.

Reference: [RH02] (``data_specs/bibliography.md``).
"""

from __future__ import annotations

import argparse
import contextlib

import numpy as np
from rich.table import Table

from ..analysis.lights import extract_lights
from ..analysis.order_rule import OrderRule
from ..analysis.orders import choose_orders
from ..analysis.scene import scene_for
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
    source_brdf, brdf, choice = load_analysis_brdf(args.brdf, args)
    busy = (stderr.status(f"choosing orders for {brdf.name} ...", spinner="dots") if progress_shown(args)
            else contextlib.nullcontext())
    with busy:
        rule = OrderRule(eps=args.eps, max_F=args.max_F, max_P=args.max_P, **order_rule(args))
        orders = choose_orders(brdf, rule=rule)
    doc = {
        "brdf": source_brdf.name,
        # scattered measurements: the representation the orders describe (data_specs/representation_json.md)
        "representation": None if choice is None else choice.as_dict(),
        "F": orders.F,
        "P": orders.P,
        "eps": orders.eps,
        "tolerance": orders.tolerance,
        "capped": orders.capped,
        "converged": orders.converged,
        "message": orders.message,
        "seconds": orders.seconds,
        "criterion": orders.criterion,
        "max_view_deg": orders.max_view_deg,
        "eps_rh02": orders.eps_rh02,
        "view_bands": orders.view_bands(),
        "extrapolated_samples": orders.n_without_data,
        "table": orders.table,
    }
    if args.env:
        env = load_env_arg(args.env, args)
        extraction = extract_lights(env, args.lights)  # the SHRM holds the map without its lights
        _, scene = scene_for(extraction.residual, orders)
        doc.update(
            environment=env.name, lights=[light.to_dict() for light in extraction.lights.lights], F_L=scene.F_L,
            F_B=scene.F_B, P_B=scene.P_B, eps_L=scene.eps_L,
            lighting_capped=scene.lighting_capped, bound=scene.bound, bound_units=scene.bound_units,
            scene_capped=scene.capped, scene_view_bands=list(scene.view_bands),
        )
    if args.json:
        print_json(doc)
        return 0
    _print_tables(doc, orders.table)
    return 0


def _print_tables(doc: dict, table: np.ndarray) -> None:
    rule = ("every view band to " f"{doc['max_view_deg']:g}°" if doc["criterion"] == "bands" else "RH02, all views")
    if doc["representation"] is not None:
        stdout.print(doc["representation"]["line"], markup=False, soft_wrap=True)
    summary = Table(title=f"orders for {doc['brdf']} at eps = {doc['tolerance']:g} ({rule})")
    for key in ("F", "P", "eps", "eps RH02", "capped", "converged", "seconds"):
        summary.add_column(key, justify="right")
    summary.add_row(
        str(doc["F"]), str(doc["P"]), f"{doc['eps']:.4g}", f"{doc['eps_rh02']:.4g}", str(doc["capped"]),
        str(doc["converged"]), f"{doc['seconds']:.2f}",
    )
    print_table(summary)
    print_view_bands(doc["view_bands"], f"error by view band at (F, P) = ({doc['F']}, {doc['P']}) under a point light",
                     point_light=True)
    if "F_B" in doc:
        lights = doc["lights"]
        with_lights = f" without its {len(lights)} light(s), shaded exactly" if lights else ""
        scene = Table(title=f"scene orders with {doc['environment']}{with_lights}")
        bound_name = "residual bound (eps)" if doc["criterion"] == "rh02" else "bound (rel. RMS, worst band)"
        for key in ("F_L", "F_B", "P_B", "eps_L(F_L)", bound_name):
            scene.add_column(key, justify="right")
        # a capped F_L means ε_L > tol up to the largest order computed: F_L is at least that
        scene.add_row(
            f">= {doc['F_L']}" if doc["lighting_capped"] else str(doc["F_L"]),
            str(doc["F_B"]),
            str(doc["P_B"]),
            f"{doc['eps_L']:.3g}",
            f"{doc['bound']:.3g}",
        )
        print_table(scene)
        if doc["scene_view_bands"]:
            print_view_bands(doc["scene_view_bands"], f"reflected field by view band at (F_B, P_B) = "
                             f"({doc['F_B']}, {doc['P_B']}), exact lookup")
    if doc["message"]:
        stdout.print(f"[yellow]note:[/yellow] {in_cli_terms(doc['message'])}")
    F, P = doc["F"], doc["P"]
    rows = sorted(set(np.unique(np.linspace(0, min(table.shape[0] - 1, max(2 * F, 8)), 9).astype(int))) | {F})
    cols = list(range(min(table.shape[1], max(P + 3, 5))))
    what = "worst view band inside the limit, point light" if doc["criterion"] == "bands" else "all views"
    # as many P columns per table as the console holds (9 characters each, the F column 8): a
    # narrow terminal gets the table in parts instead of cells squeezed to "…"
    per_table = max(1, (stdout.width - 8) // 9)
    for start in range(0, len(cols), per_table):
        part = cols[start : start + per_table]
        suffix = "" if len(cols) <= per_table else f", P = {part[0]}–{part[-1]}"
        eps_tab = Table(title=f"eps(F, P): uncaptured energy fraction ({what}, worst channel{suffix})")
        eps_tab.add_column("F \\ P", justify="right")
        for p in part:
            eps_tab.add_column(str(p), justify="right")
        for f in rows:
            cells = []
            for p in part:
                text = "-" if np.isnan(table[f, p]) else f"{table[f, p]:.3g}"
                cells.append(f"[bold green]{text}[/bold green]" if (f, p) == (F, P) else text)
            eps_tab.add_row(str(f), *cells)
        stdout.print(eps_tab)
