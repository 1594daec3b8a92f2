"""shrmkit — measured-BRDF processing toolkit with a Spherical Harmonic Reflection Map renderer.

Public API (see README)::

    import shrmkit
    brdf = shrmkit.load_brdf("microfacet:sigma=0.2")   # or a path (.binary, .npz, .brdf, .json)
    env = shrmkit.load_env("builtin:sky")              # or a path (lat-long files are read y-up)
    o = shrmkit.choose_orders(brdf, eps=0.03)          # o.F, o.P, o.eps, o.table
    m = shrmkit.prefilter(env, brdf, eps=0.03)         # an SHRM
    rgb = m.radiance(R, V)
    r = shrmkit.report(brdf, out="reports", profile="quick")  # one BRDF's report (shrm report)

Public API: the names in ``__all__`` here and in the sub-packages :mod:`shrmkit.brdf_io` (files,
models, environments), :mod:`shrmkit.analysis` (the frequency-space analysis, with its public
sub-packages ``fit``, ``compare`` and ``baselines``), :mod:`shrmkit.render` (mesh rendering) and
:mod:`shrmkit.cli` (the ``shrm`` command and batch reports). Modules not listed there are
internal: their names may change without notice. Citation keys such as [RH02]:
``data_specs/bibliography.md``.

Names are imported on first use so that ``import shrmkit`` and the CLI start fast.
"""

from __future__ import annotations

import importlib
from typing import Any

from ._version import __version__

_LAZY = {
    "load_brdf": "shrmkit.brdf_io.specs",
    "BRDF": "shrmkit.brdf_io.brdf",
    "load_env": "shrmkit.brdf_io.envmap",
    "EnvironmentMap": "shrmkit.brdf_io.envmap",
    "reparameterize": "shrmkit.brdf_io.reparam",
    "BadInputError": "shrmkit.brdf_io.errors",
    "ShrmError": "shrmkit.brdf_io.errors",
    "choose_orders": "shrmkit.analysis.orders",
    "OrderChoice": "shrmkit.analysis.orders",
    "OrderRule": "shrmkit.analysis.order_rule",
    "prefilter": "shrmkit.analysis.shrm",
    "load_shrm": "shrmkit.analysis.shrm",
    "SHRM": "shrmkit.analysis.shrm",
    "fit_brdf": "shrmkit.analysis.fit",
    "FitResult": "shrmkit.analysis.fit",
    "compare": "shrmkit.analysis.compare",
    "render_scene": "shrmkit.render.api",
    "SceneRender": "shrmkit.render.api",
    "render_sequence": "shrmkit.render.api",
    "SequenceRender": "shrmkit.render.api",
    "SHRMRenderer": "shrmkit.render.vtk_renderer",
    "report": "shrmkit.cli.report.api",
    "Report": "shrmkit.cli.report.api",
}

__all__ = ["__version__", *_LAZY]


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        value = getattr(importlib.import_module(_LAZY[name]), name)
        globals()[name] = value
        return value
    if name in ("brdf_io", "analysis", "render", "cli"):  # the sub-packages, on first read
        return importlib.import_module(f"shrmkit.{name}")
    raise AttributeError(f"module 'shrmkit' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(__all__)
