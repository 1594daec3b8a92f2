"""The order choice's CPU time, an older checkout against this one, interleaved (issue 22).

Each round runs one child process for the older package and one for this checkout, one after the
other; a child times ``choose_orders(brdf, eps=0.03)`` as ``benchmarks/prefilter_speed.py``'s
``target_orders`` does (the BRDF loaded anew for each repeat, outside the clock; min CPU
``time.process_time`` over the repeats) and reports the choice. The table gives the fastest
child of each side over the rounds, the chosen orders and worst-band ε of each side, and the
differences between the two sides' stated values: ε at the choice and ε of every view band at the
choice (``OrderChoice.view_bands``) relative to the value, every computed entry of the searched
table absolutely (entries run down to ~1e-15, the rounding of the energy sums).

The older package is a ``git worktree`` linked as ``shrmkit`` in a folder of its own::

    git worktree add /tmp/old_x <rev>; mkdir -p /tmp/oldpkg_x; ln -sfn /tmp/old_x /tmp/oldpkg_x/shrmkit
    .venv/bin/python benchmarks/orders_ab.py --old /tmp/oldpkg_x              # ~1-2 min wall
    .venv/bin/python benchmarks/orders_ab.py --old /tmp/oldpkg_x --rounds 5 microfacet:sigma=0.1

Default BRDFs: microfacet σ = 0.1 and 0.3, GGX α = 0.1, Phong s = 512 and the sharpest RGL file
of ../shared/data (``cc_iris_purple_gem_rgb.bsdf``, the one ``prefilter_speed.py`` times).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
SHARPEST_RGL = Path("/work/shared/data/brdf/rgl/cc_iris_purple_gem_rgb.bsdf")
DEFAULT_SPECS = ["microfacet:sigma=0.1", "microfacet:sigma=0.3", "cook-torrance:alpha=0.1,dist=ggx", "phong:s=512"]
EPS = 0.03

#: the child: min CPU of ``repeats`` order choices per BRDF, and what each states, as JSON on stdout
CHILD = r"""
import json, sys, time, warnings
import numpy as np
warnings.simplefilter("ignore")
from shrmkit.analysis.orders import choose_orders
from shrmkit.brdf_io.specs import load_brdf
repeats, eps, specs = int(sys.argv[1]), float(sys.argv[2]), sys.argv[3:]
out = {}
for spec in specs:
    best = float("inf")
    for _ in range(repeats):
        brdf = load_brdf(spec)
        c0 = time.process_time()
        o = choose_orders(brdf, eps=eps)
        best = min(best, time.process_time() - c0)
    out[spec] = {"cpu": best, "F": o.F, "P": o.P, "eps": o.eps, "capped": o.capped, "converged": o.converged,
                 "table": np.where(np.isnan(o.searched_table), -1.0, o.searched_table).tolist(),
                 "bands": [b["eps"] for b in o.view_bands()]}
json.dump(out, sys.stdout)
"""


def run_child(pythonpath: str | None, repeats: int, specs: list[str]) -> dict:
    """One child's JSON (``pythonpath`` first on the path: the older package; None: this checkout)."""
    env = dict(os.environ)
    env.pop("PYTHONPATH", None)
    if pythonpath:
        env["PYTHONPATH"] = pythonpath
    cwd = "/" if pythonpath else str(HERE.parent)  # the older package must not be shadowed by this one
    done = subprocess.run([sys.executable, "-c", CHILD, str(repeats), str(EPS), *specs], env=env, cwd=cwd,
                          capture_output=True, text=True, check=True)
    return json.loads(done.stdout)


def stated_difference(old: dict, new: dict) -> tuple[float, float, float]:
    """Between the sides: the relative difference of ε at the choice, the largest relative
    difference of a band's ε at the choice, and the largest absolute difference of a computed
    table entry (inf where one side computed a table column the other did not)."""
    eps = abs(new["eps"] - old["eps"]) / abs(old["eps"])
    bands = max((abs(y - x) / x if x > 0 else abs(y) for x, y in zip(old["bands"], new["bands"], strict=True)),
                default=0.0)
    table = 0.0
    for row_a, row_b in zip(old["table"], new["table"], strict=True):
        for x, y in zip(row_a, row_b, strict=True):
            if (x < 0) != (y < 0):
                return eps, bands, float("inf")
            table = max(table, abs(x - y))
    return eps, bands, table


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--old", required=True, help="folder holding the older package as 'shrmkit'")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--repeats", type=int, default=3, help="order choices per BRDF in one child (min CPU)")
    parser.add_argument("specs", nargs="*", help="BRDF specs or files (default: module docs)")
    args = parser.parse_args(argv)
    specs = args.specs or DEFAULT_SPECS + ([str(SHARPEST_RGL)] if SHARPEST_RGL.is_file() else [])
    best: dict[str, dict] = {"old": {}, "new": {}}
    for r in range(args.rounds):
        for side, path in (("old", args.old), ("new", None)):
            for spec, res in run_child(path, args.repeats, specs).items():
                if spec not in best[side] or res["cpu"] < best[side][spec]["cpu"]:
                    best[side][spec] = res
        print(f"round {r + 1}/{args.rounds} done", file=sys.stderr)
    print(f"order choice, ε = {EPS:g}, CPU ms (min over {args.rounds} rounds × {args.repeats} repeats, "
          "old and new interleaved)")
    print("| BRDF | old ms | new ms | new/old | old (F, P), ε | new (F, P), ε | rel. diff ε | max rel. diff bands "
          "| max abs. diff table |")
    print("|---|---|---|---|---|---|---|---|---|")
    for spec in specs:
        o, n = best["old"][spec], best["new"][spec]
        name = Path(spec).name if os.sep in spec else spec
        print(f"| {name} | {o['cpu'] * 1e3:.0f} | {n['cpu'] * 1e3:.0f} | {n['cpu'] / o['cpu']:.2f} | "
              f"({o['F']}, {o['P']}), {o['eps']:.6g} | ({n['F']}, {n['P']}), {n['eps']:.6g} | "
              "{:.1e} | {:.1e} | {:.1e} |".format(*stated_difference(o, n)))


if __name__ == "__main__":
    main()
