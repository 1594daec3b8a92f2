"""Builders of RSIBR [Cabral99]: twelve radiance maps at the icosahedron's vertices, blended per
view with spherical barycentric weights (``rsibr_model`` of :mod:`shrmkit.analysis.baselines.methods`).

- ``rsibr``: the maps taken from the SHRM (only the view interpolation differs from it);
  precompute = the SHRM's prefilter plus the twelve eq. 12 maps. Earlier key ``cabral_shrm``.
- ``rsibr_reference``: the maps by the brute-force angular integral (the original method's
  cost), at ``options.rsibr_reference_height`` rows; skipped when that is None or 0. Earlier key
  ``cabral_reference``.
"""

from __future__ import annotations

from ..baselines.methods import rsibr_model
from ..baselines.rsibr import RSIBRMaps
from .representation import BuildContext, BuiltRepresentation

__all__ = ["build_rsibr", "build_rsibr_reference"]


def _built(ctx: BuildContext, key: str, label: str, short_label: str, maps: RSIBRMaps,
           seconds: float) -> BuiltRepresentation:
    h, w = maps.maps.shape[1:3]
    params = {"views": len(maps.views), "map": f"{h}x{w}", "source": maps.meta["source"]}
    return ctx.make(key, label, short_label, maps, storage_bytes=maps.nbytes, precompute_s=seconds, params=params)


def build_rsibr(ctx: BuildContext) -> list[BuiltRepresentation]:
    """The twelve maps from the base SHRM."""
    shrm, t_shrm = ctx.base_shrm()
    ctx.stage("RSIBR (from SHRM)")
    maps = rsibr_model(ctx.env, ctx.brdf, shrm=shrm)
    return [_built(ctx, "rsibr", "RSIBR 12 maps (SHRM)", "RSIBR", maps, t_shrm + maps.meta["seconds"])]


def build_rsibr_reference(ctx: BuildContext) -> list[BuiltRepresentation]:
    """The twelve maps by the angular reference, or nothing when the height is None or 0."""
    height = ctx.options.rsibr_reference_height
    if not height:
        return []
    ctx.stage("RSIBR (angular reference)")
    maps = rsibr_model(ctx.env, ctx.brdf, source="reference", reference_height=int(height))
    return [_built(ctx, "rsibr_reference", "RSIBR 12 maps (reference)", "RSIBR ref", maps, maps.meta["seconds"])]
