"""A tour of shrmkit in a notebook: every object shows itself as a card with a picture.

Run it as a script (``python docs/examples/notebook_tour.py [OUT]``) or open it in Jupyter or
VS Code, where the ``# %%`` lines separate cells and each cell's last object is displayed by its
``_repr_html_``. As a script, the cards are gathered into ``OUT/tour.html`` (default
``./shrm-notebook-tour``) and one line per cell is printed. Built-in data only; about 20–40 s.
"""

# %% Setup: show() displays a card in a notebook, and collects it when run as a script
from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

import shrmkit

OUT = Path(sys.argv[1] if len(sys.argv) > 1 and not sys.argv[1].startswith("-") else "shrm-notebook-tour")
CARDS: list[str] = []
T0 = time.perf_counter()


def show(obj: object, line: str) -> object:
    """Display ``obj`` (in IPython) or keep its card for ``tour.html`` and print ``line``."""
    try:
        from IPython import get_ipython
        from IPython.display import display

        if get_ipython() is not None:
            display(obj)
            return obj
    except ImportError:
        pass
    CARDS.append(obj._repr_html_())
    print(f"[{time.perf_counter() - T0:5.1f} s] {line}")
    return obj


# %% An environment map: a tone-mapped thumbnail, its size, orientation and dynamic range
env = shrmkit.load_env("builtin:sky")
show(env, f"environment {env.name}: {env.height}x{env.width}")

# %% A BRDF: its name, kind and a lit sphere
brdf = shrmkit.load_brdf("microfacet:sigma=0.2")
show(brdf, f"BRDF {brdf.name} ({brdf.kind})")

# %% The orders it needs (RH02 §5.1): F, P, ε, and the error in every view band
orders = shrmkit.choose_orders(brdf, eps=0.03)
show(orders, f"orders F={orders.F} P={orders.P}, eps {orders.eps:.3g} in {orders.seconds:.2f} s")

# %% The SHRM of the scene: its orders, map size, stated error (worst view band) and timings
shrm = shrmkit.prefilter(env, brdf, eps=0.03)
worst = max(b["predicted_rel_rms"] for b in shrm.meta["view_bands"] if b["inside"])
show(shrm, f"SHRM F={shrm.F} P={shrm.P} on {shrm.height}x{shrm.width}, stated relative RMS {worst:.3g}, "
     f"{shrm.meta['timings']['total']:.2f} s")

# %% Reflected radiance B(R, V) at a few directions (RH02 eq. 8), an array like any other
R = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])
V = np.array([[0.0, 0.6, 0.8], [0.0, 0.0, 1.0]])
rgb = shrm.radiance(R, V)
print(f"B(R, V) = {np.array2string(rgb, precision=3)}")

# %% A render (offscreen OpenGL; skipped where there is no context)
try:
    render = shrmkit.render_scene("builtin:sphere", env, brdf, size=256, fps_frames=5)
    show(render, f"render {render.mode}: first frame {render.timings.first_frame_s:.2f} s, "
         f"{render.timings.fps:.0f} fps ({render.timings.backend})")
except shrmkit.ShrmError as err:  # no offscreen OpenGL context (OffscreenError)
    print(f"render skipped: {err}")

# %% The accuracy report of the BRDF, written to OUT/<name>/ and shown by its first screen
report = shrmkit.report(brdf, out=OUT, profile="quick", models=("lafortune",), plots=False)
show(report, f"report {report.name}: {report.folder / 'report.html'}")

# %% As a script: the cards in one page
if CARDS:
    OUT.mkdir(parents=True, exist_ok=True)
    page = OUT / "tour.html"
    page.write_text("<!doctype html><meta charset='utf-8'><title>shrmkit notebook tour</title>"
                    + "<hr>".join(CARDS), encoding="utf-8")
    print(f"[{time.perf_counter() - T0:5.1f} s] wrote {page}")
