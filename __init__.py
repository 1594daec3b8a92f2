"""shrmkit — measured-BRDF processing toolkit with a Spherical Harmonic Reflection Map renderer.

Public API (see README)::

    import shrmkit
    brdf = shrmkit.load_brdf("microfacet:sigma=0.2")   # or a path (.binary, .npz, .brdf, .json)
    env = shrmkit.load_env("builtin:sky")              # or a path; lat-long, z-up
    o = shrmkit.choose_orders(brdf, eps=0.03)          # o.F, o.P, o.eps, o.table
    m = shrmkit.prefilter(env, brdf, eps=0.03)         # an SHRM
    rgb = m.radiance(R, V)
    r = shrmkit.report(brdf, out="reports", profile="quick")  # one BRDF's report (shrm report)

Names are imported on first use so that ``import shrmkit`` and the CLI start fast.
"""

from __future__ import annotations

import importlib
from typing import Any

from ._version import __version__

_LAZY = {
    "load_brdf": "shrmkit.brdf_io.specs",
    "load_env": "shrmkit.brdf_io.envmap",
    "reparameterize": "shrmkit.brdf_io.reparam",
    "BadInputError": "shrmkit.brdf_io.errors",
    "ShrmError": "shrmkit.brdf_io.errors",
    "choose_orders": "shrmkit.analysis.orders",
    "prefilter": "shrmkit.analysis.shrm",
    "load_shrm": "shrmkit.analysis.shrm",
    "SHRM": "shrmkit.analysis.shrm",
    "fit_brdf": "shrmkit.analysis.fit",
    "compare": "shrmkit.analysis.compare",
    "render_scene": "shrmkit.render.api",
    "render_sequence": "shrmkit.render.api",
    "SHRMRenderer": "shrmkit.render.vtk_renderer",
    "report": "shrmkit.cli.report.api",
}

__all__ = ["__version__", *_LAZY]


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        value = getattr(importlib.import_module(_LAZY[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'shrmkit' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(__all__)
