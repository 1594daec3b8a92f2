"""Builders of Cabral, Olano, Nemec, "Reflection Space Image Based Rendering", SIGGRAPH 1999.

Twelve radiance maps at the icosahedron's vertices, blended per view with spherical
barycentric weights (:mod:`~shrmkit.analysis.baselines.rsibr`):

- ``cabral_shrm``: the maps taken from the SHRM (only the view interpolation differs from
  it); precompute = the SHRM's prefilter plus the twelve eq. 12 maps.
- ``cabral_reference``: the maps by the brute-force angular integral (the original method's
  cost), at ``options.cabral_reference_height`` rows; skipped when that is None or 0.
"""

from __future__ import annotations

from ..baselines.rsibr import RSIBRMaps, rsibr_from_shrm, rsibr_reference
from .representation import BuildContext, BuiltRepresentation

__all__ = ["build_cabral_shrm", "build_cabral_reference"]


def _built(ctx: BuildContext, key: str, label: str, short_label: str, maps: RSIBRMaps,
           seconds: float) -> BuiltRepresentation:
    h, w = maps.maps.shape[1:3]
    params = {"views": len(maps.views), "map": f"{h}x{w}", "source": maps.meta["source"]}
    return ctx.make(key, label, short_label, maps, storage_bytes=maps.nbytes, precompute_s=seconds, params=params)


def build_cabral_shrm(ctx: BuildContext) -> list[BuiltRepresentation]:
    """The twelve maps from the base SHRM."""
    shrm, t_shrm = ctx.base_shrm()
    ctx.stage("Cabral (from SHRM)")
    maps = rsibr_from_shrm(shrm)
    return [_built(ctx, "cabral_shrm", "Cabral 12 maps (SHRM)", "Cabral", maps, t_shrm + maps.meta["seconds"])]


def build_cabral_reference(ctx: BuildContext) -> list[BuiltRepresentation]:
    """The twelve maps by the angular reference, or nothing when the height is None or 0."""
    height = ctx.options.cabral_reference_height
    if not height:
        return []
    ctx.stage("Cabral (angular reference)")
    maps = rsibr_reference(ctx.env, ctx.brdf, int(height))
    return [_built(ctx, "cabral_reference", "Cabral 12 maps (reference)", "Cabral ref", maps,
                   maps.meta["seconds"])]
