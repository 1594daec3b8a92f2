"""Cost per frame of an environment sequence (issue 25): one frame per map, the BRDF's orders chosen once.

Measures, in one run and on the same maps:

- ``sequence``: :func:`~shrmkit.analysis.orders.choose_orders` once, then per map
  ``prefilter(orders=...)`` (what ``shrm render --env A B ...`` and ``render_sequence`` do);
- ``full``: per map a full ``prefilter`` that chooses the orders again (what separate
  ``shrm render`` runs do);
- optionally (``--render``) the offscreen render of each frame (``render_sequence``, distant mode).

The frames of the two are the same (the order choice is deterministic; tests/cli/test_cli_env_sequence.py).
Maps are given as files or folders (``env_sources_arg``: a folder's .exr/.hdr/.pfm sorted by name);
shared data are read from ``../shared/data`` (never copied into the repository).

Run:  .venv/bin/python benchmarks/env_sequence.py ../shared/data/env/ict_small \\
          ../shared/data/env/polyhaven_cc0 ../shared/data/env/grace_latlong.exr [--brdf microfacet:sigma=0.2]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from shrmkit.analysis.orders import choose_orders
from shrmkit.analysis.shrm import prefilter
from shrmkit.brdf_io.envmap import load_env
from shrmkit.brdf_io.specs import load_brdf
from shrmkit.cli.common import env_sources_arg

__all__ = ["main", "measure"]


def measure(sources: list[str], brdf_spec: str, eps: float, render: bool, size: int) -> dict:
    """Seconds per map of both ways (and of the renders), with each map's stated worst-band error."""
    envs = [load_env(s) for s in sources]
    brdf = load_brdf(brdf_spec)
    t0 = time.perf_counter()
    orders = choose_orders(brdf, eps=eps)
    orders_s = time.perf_counter() - t0
    rows = []
    for k, env in enumerate(envs):
        seconds = {}
        # which way goes first alternates between maps (a warm cache, if any, favours neither)
        for way in (("sequence", "full") if k % 2 == 0 else ("full", "sequence")):
            t0 = time.perf_counter()
            model = prefilter(env, brdf, eps=eps, orders=orders if way == "sequence" else None)
            seconds[way] = time.perf_counter() - t0
            if way == "sequence":
                shared = model
            else:
                full = model
        seq_s, full_s = seconds["sequence"], seconds["full"]
        assert (shared.F, shared.P) == (full.F, full.P) and np.array_equal(shared.coeffs, full.coeffs)
        worst = max(b["predicted_rel_rms"] for b in shared.meta["view_bands"] if b["inside"])
        rows.append({"env": env.name, "shape": env.radiance.shape[:2], "F_B": shared.F, "P": shared.P,
                     "sequence_s": seq_s, "full_s": full_s, "stated": worst})
    out = {"orders_s": orders_s, "rows": rows}
    if render:
        from shrmkit.render.api import render_sequence  # optional: needs an offscreen OpenGL context

        result = render_sequence("builtin:sphere", envs, brdf, eps=eps, size=size)
        out["render_s"] = [r.timings.first_frame_s for r in result.renders]
        out["frame_s"] = list(result.frame_seconds)
    return out


def main(argv: list[str] | None = None) -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("env", nargs="+", help="map files or folders (sorted), in sequence order")
    p.add_argument("--brdf", default="microfacet:sigma=0.2")
    p.add_argument("--eps", type=float, default=0.03)
    p.add_argument("--render", action="store_true", help="also render each frame offscreen (distant mode)")
    p.add_argument("--size", type=int, default=256)
    args = p.parse_args(argv)
    sources, _ = env_sources_arg(args.env)
    result = measure(sources, args.brdf, args.eps, args.render, args.size)
    print(f"{len(sources)} maps, {args.brdf}, eps {args.eps:g}; orders chosen once in {result['orders_s']:.3f} s")
    print(f"{'map':<22} {'size':>10} {'F_B':>4} {'P':>2} {'sequence s':>10} {'full s':>8} {'stated':>8}")
    for r in result["rows"]:
        print(f"{r['env']:<22} {r['shape'][0]:>4}x{r['shape'][1]:<5} {r['F_B']:>4} {r['P']:>2} "
              f"{r['sequence_s']:>10.3f} {r['full_s']:>8.3f} {r['stated']:>8.3g}")
    seq = sum(r["sequence_s"] for r in result["rows"])
    full = sum(r["full_s"] for r in result["rows"])
    n = len(result["rows"])
    print(f"per map: sequence {seq / n:.3f} s (+ {result['orders_s'] / n:.3f} s of the one order choice), "
          f"full prefilter {full / n:.3f} s; total {seq + result['orders_s']:.2f} s against {full:.2f} s")
    if "frame_s" in result:
        print(f"render_sequence frames (prefilter + render {args.size}^2): "
              + ", ".join(f"{s:.2f}" for s in result["frame_s"]) + " s")


if __name__ == "__main__":
    main()
