"""Builders of the SHRM family: the SHRM itself, the SHRM at a lower P, Kautz–McCool.

- ``shrm``: the global SHRM at the (F, P) RH02's order rule gives for ε (R. Ramamoorthi,
  P. Hanrahan, "Frequency Space Environment Map Rendering", SIGGRAPH 2002,
  doi:10.1145/566654.566611; "RH02"). Storage (P+1)² float32 maps.
- ``shrm_low_p``: the same F and map size with a lower view order P (default P − 2).
- ``kautz_mccool``: J. Kautz, M. McCool, "Approximation of Glossy Reflection with
  Prefiltered Environment Maps", Graphics Interface 2000 — the q = 0 (azimuth-free) SHRM
  at the same (F, P). They store the P+1 local maps B_p0(α, β); the renderer is fed the
  equivalent global SHRM, so storage counts P+1 maps and the update times eq. 12.
"""

from __future__ import annotations

import time
from typing import Any

from ..shrm import SHRM, prefilter
from .representation import BuildContext, BuiltRepresentation

__all__ = ["build_shrm", "build_shrm_low_p", "build_kautz_mccool"]


def _params(shrm: SHRM, **extra: Any) -> dict[str, Any]:
    meta = shrm.meta
    return {"F": shrm.F, "P": shrm.P, "map": f"{shrm.height}x{shrm.width}", "window": meta["window"],
            "window_strength": meta["window_strength"], "eps_B": shrm.eps["reflected"],
            "negative_before": meta["negative_before"], "negative_after": meta["negative_after"],
            "view_bands": meta["view_bands"], "lights": len(meta.get("lights", [])), **extra}


def _same_grid(ctx: BuildContext, P: int, **kwargs: Any) -> tuple[SHRM, float]:
    """An SHRM at the base SHRM's F and map size with view order P (window ``options.window``,
    decided for this SHRM), and its seconds."""
    base, _ = ctx.base_shrm()
    t0 = time.perf_counter()
    shrm = prefilter(ctx.env, ctx.brdf, eps=ctx.options.eps, F=base.F, P=P, size=base.height,
                     window=ctx.options.window, criterion=ctx.options.criterion,
                     max_view_deg=ctx.options.rule_max_view_deg, lights=ctx.options.lights, **kwargs)
    return shrm, time.perf_counter() - t0


def build_shrm(ctx: BuildContext) -> list[BuiltRepresentation]:
    """The SHRM at ``options.eps``."""
    shrm, seconds = ctx.base_shrm()
    return [ctx.make("shrm", f"SHRM F={shrm.F} P={shrm.P}", f"SHRM P={shrm.P}", shrm,
                     storage_bytes=shrm.coeffs.nbytes, precompute_s=seconds, params=_params(shrm))]


def build_shrm_low_p(ctx: BuildContext) -> list[BuiltRepresentation]:
    """The SHRM at ``options.lower_P`` (default max(P − 2, 0)); nothing when that is not below P."""
    base, _ = ctx.base_shrm()
    p_low = max(base.P - 2, 0) if ctx.options.lower_P is None else int(ctx.options.lower_P)
    if p_low >= base.P:
        return []
    ctx.stage(f"SHRM P={p_low}")
    low, seconds = _same_grid(ctx, p_low)
    return [ctx.make("shrm_low_p", f"SHRM F={low.F} P={low.P}", f"SHRM P={low.P}", low,
                     storage_bytes=low.coeffs.nbytes, precompute_s=seconds, params=_params(low))]


def build_kautz_mccool(ctx: BuildContext) -> list[BuiltRepresentation]:
    """Kautz & McCool 2000: the q = 0 terms at the base SHRM's (F, P)."""
    base, _ = ctx.base_shrm()
    ctx.stage("Kautz-McCool")
    km, seconds = _same_grid(ctx, base.P, azimuth_free=True)
    storage = (km.P + 1) * km.height * km.width * 3 * 4
    return [ctx.make("kautz_mccool", f"Kautz-McCool q=0 P={km.P}", f"KM P={km.P}", km, storage_bytes=storage,
                     precompute_s=seconds, params=_params(km, stored_maps=km.P + 1))]
