"""The registry of representation kinds: one entry per kind, key → builder.

A builder is ``builder(ctx: BuildContext) -> Sequence[Representation]``: it reads what it
needs from the context (inputs, :class:`~.options.CompareOptions`, the shared base SHRM)
and returns zero or more representations (none when its option turns it off, several for
one row per parameter value). The rows of a comparison come in registry order.

Adding a kind: write its module (a builder that returns :class:`~.representation.BuiltRepresentation`
objects with a ``short_label`` for image panels) and add one line here — two files. A new
option, if it needs one, is a field of :class:`~.options.CompareOptions` (a third file).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from types import MappingProxyType

from ...brdf_io.brdf import BRDF
from ...brdf_io.envmap import EnvironmentMap
from .cabral import build_cabral_reference, build_cabral_shrm
from .green_lobes import build_green_lobes
from .options import CompareOptions
from .representation import BuildContext, Representation
from .shrm_kinds import build_kautz_mccool, build_shrm, build_shrm_low_p

__all__ = ["Builder", "REGISTRY", "build_representations"]

#: The type of a builder, from the comparison's context to its representations (none, one, or one per value).
Builder = Callable[[BuildContext], Sequence[Representation]]

#: Kind key → builder, in row order. Row keys: the kind key, except ``gaussian`` which gives
#: ``gaussian_k1`` … one per K.
REGISTRY: Mapping[str, Builder] = MappingProxyType({
    "shrm": build_shrm,  # RH02, the (F, P) of the order rule
    "shrm_low_p": build_shrm_low_p,  # RH02 at a lower view order P
    "kautz_mccool": build_kautz_mccool,  # Kautz & McCool 2000, q = 0
    "cabral_shrm": build_cabral_shrm,  # Cabral, Olano, Nemec 1999, maps from the SHRM
    "cabral_reference": build_cabral_reference,  # Cabral et al. 1999, maps by the angular integral
    "gaussian": build_green_lobes,  # Green, Kautz, Durand 2007, one row per K
})


def build_representations(
    env: EnvironmentMap,
    brdf: BRDF,
    options: CompareOptions | None = None,
    *,
    progress: Callable[[str], None] | None = None,
) -> list[Representation]:
    """Build every registered representation for one BRDF under one environment.

    Parameters
    ----------
    env
        EnvironmentMap as evaluated (use a small one, ~64 rows: the angular reference is
        O(W S_L²); :func:`~.table.compare_representations` resamples it for you).
    brdf
        Any evaluable BRDF.
    options
        :class:`~.options.CompareOptions` (default: all defaults).
    progress
        ``progress(stage)`` callback.

    Returns
    -------
    list
        :class:`~.representation.Representation` objects in registry order.
    """
    ctx = BuildContext(env, brdf, CompareOptions() if options is None else options, progress)
    reps: list[Representation] = []
    for build in REGISTRY.values():
        reps.extend(build(ctx))
    keys = [rep.key for rep in reps]
    if len(set(keys)) != len(keys):
        raise ValueError(f"representation keys must be unique, got {keys}")
    return reps
