"""Builders of the SHRM family of a comparison: the SHRM [RH02], the SHRM at a lower P, and
Kautz–McCool [KM00], each through the table of published methods
(:mod:`shrmkit.analysis.baselines.methods`).

- ``shrm``: the SHRM at the (F, P) its order rule gives for ε; storage (P+1)² float32 maps.
- ``shrm_low_p``: the same F and map size with a lower view order P (default P − 2).
- ``kautz_mccool``: the q = 0 (azimuth-free) SHRM on the SHRM's (F, P) and map rows. Kautz &
  McCool store the P+1 local maps B_p0(α, β); the renderer is fed the equivalent global SHRM,
  so storage counts P+1 maps and the update times eq. 12.
"""

from __future__ import annotations

import time
from typing import Any

from ..baselines.methods import kautz_mccool_model
from ..shrm import SHRM, prefilter
from .representation import BuildContext, BuiltRepresentation

__all__ = ["build_shrm", "build_shrm_low_p", "build_kautz_mccool"]


def _params(shrm: SHRM, **extra: Any) -> dict[str, Any]:
    info = shrm.info
    return {"F": shrm.F, "P": shrm.P, "map": f"{shrm.height}x{shrm.width}", "window": info.window.used,
            "window_strength": info.window.strength, "eps_B": shrm.eps["reflected"],
            "negative_before": info.window.negative_before, "negative_after": info.window.negative_after,
            "view_bands": [band.to_json() for band in info.view_bands], "lights": len(info.lights), **extra}


def build_shrm(ctx: BuildContext) -> list[BuiltRepresentation]:
    """The SHRM at ``options.eps``."""
    shrm, seconds = ctx.base_shrm()
    return [ctx.make("shrm", f"SHRM F={shrm.F} P={shrm.P}", f"SHRM P={shrm.P}", shrm,
                     storage_bytes=shrm.coeffs.nbytes, precompute_s=seconds, params=_params(shrm))]


def build_shrm_low_p(ctx: BuildContext) -> list[BuiltRepresentation]:
    """The SHRM at ``options.lower_P`` (default max(P − 2, 0)) on the base SHRM's F and map size,
    its window decided for itself; nothing when that P is not below the base's."""
    base, _ = ctx.base_shrm()
    p_low = max(base.P - 2, 0) if ctx.options.lower_P is None else int(ctx.options.lower_P)
    if p_low >= base.P:
        return []
    ctx.stage(f"SHRM P={p_low}")
    t0 = time.perf_counter()
    settings = ctx.options.shrm_settings()
    low = prefilter(ctx.env, ctx.brdf, F=base.F, P=p_low, size=base.height, **settings)
    seconds = time.perf_counter() - t0
    return [ctx.make("shrm_low_p", f"SHRM F={low.F} P={low.P}", f"SHRM P={low.P}", low,
                     storage_bytes=low.coeffs.nbytes, precompute_s=seconds, params=_params(low))]


def build_kautz_mccool(ctx: BuildContext) -> list[BuiltRepresentation]:
    """[KM00]: the q = 0 terms on the base SHRM's (F, P) and map rows (``kautz_mccool_model``)."""
    base, _ = ctx.base_shrm()
    ctx.stage("Kautz-McCool")
    t0 = time.perf_counter()
    km = kautz_mccool_model(ctx.env, ctx.brdf, shrm=base, **ctx.options.shrm_settings())
    seconds = time.perf_counter() - t0
    storage = (km.P + 1) * km.height * km.width * 3 * 4
    return [ctx.make("kautz_mccool", f"Kautz-McCool q=0 P={km.P}", f"KM P={km.P}", km, storage_bytes=storage,
                     precompute_s=seconds, params=_params(km, stored_maps=km.P + 1))]
