"""The registry of representation kinds: one entry per kind, key → builder.

The kinds are the published methods of :mod:`shrmkit.analysis.baselines.methods` under the same
keys (``shrm`` [RH02], ``kautz_mccool`` [KM00], ``rsibr`` [Cabral99], ``gaussian_lobes``
[Green07]), built by that table, plus two variants a comparison adds: ``shrm_low_p`` (the SHRM at
a lower P) and ``rsibr_reference`` (RSIBR's maps by the angular integral). The earlier keys
(``cabral_shrm``, ``cabral_reference``, ``gaussian``) still index :data:`REGISTRY` with a
:class:`DeprecationWarning`, and :func:`deprecated_row_key` gives a row's earlier key.

A builder is ``builder(ctx: BuildContext) -> Sequence[Representation]``: it reads what it
needs from the context (inputs, :class:`~.options.CompareOptions`, the shared base SHRM)
and returns zero or more representations (none when its option turns it off, several for
one row per parameter value). The rows of a comparison come in registry order.

Adding a kind: write its module (a builder that returns :class:`~.representation.BuiltRepresentation`
objects with a ``short_label`` for image panels) and add one line here — two files. A new
option, if it needs one, is a field of :class:`~.options.CompareOptions` (a third file).
"""

from __future__ import annotations

import re
import warnings
from collections.abc import Callable, Iterator, Mapping, Sequence
from typing import Any

from ...brdf_io.brdf import BRDF
from ...brdf_io.envmap import EnvironmentMap
from .cabral import build_rsibr, build_rsibr_reference
from .green_lobes import build_green_lobes
from .options import CompareOptions
from .representation import BuildContext, Representation
from .shrm_kinds import build_kautz_mccool, build_shrm, build_shrm_low_p

__all__ = ["Builder", "REGISTRY", "build_representations"]

#: The type of a builder, from the comparison's context to its representations (none, one, or one per value).
Builder = Callable[[BuildContext], Sequence[Representation]]

#: Earlier kind keys → the keys of the table of methods.
_OLD_KINDS = {"cabral_shrm": "rsibr", "cabral_reference": "rsibr_reference", "gaussian": "gaussian_lobes"}
#: Earlier row keys → row keys (``gaussian_k{K}`` → ``gaussian_lobes_k{K}`` by pattern).
_OLD_ROWS = {"rsibr": "cabral_shrm", "rsibr_reference": "cabral_reference"}


class _Registry(Mapping[str, "Builder"]):
    """A read-only kind → builder mapping whose earlier keys still resolve, with a DeprecationWarning."""

    def __init__(self, builders: dict[str, Builder]) -> None:
        self._builders = dict(builders)

    def __getitem__(self, key: str) -> Builder:
        if key in _OLD_KINDS:
            warnings.warn(f"representation kind {key!r} is deprecated: use {_OLD_KINDS[key]!r}",
                          DeprecationWarning, stacklevel=2)
            key = _OLD_KINDS[key]
        return self._builders[key]

    def __iter__(self) -> Iterator[str]:
        return iter(self._builders)

    def __len__(self) -> int:
        return len(self._builders)

    def __repr__(self) -> str:
        return f"REGISTRY({list(self._builders)})"


#: Kind key → builder, in row order. Row keys: the kind key, except ``gaussian_lobes`` which gives
#: ``gaussian_lobes_k1`` … one per K.
REGISTRY: Mapping[str, Builder] = _Registry({
    "shrm": build_shrm,  # [RH02], the (F, P) of the order rule
    "shrm_low_p": build_shrm_low_p,  # [RH02] at a lower view order P
    "kautz_mccool": build_kautz_mccool,  # [KM00], q = 0 on the SHRM's (F, P)
    "rsibr": build_rsibr,  # [Cabral99], maps from the SHRM
    "rsibr_reference": build_rsibr_reference,  # [Cabral99], maps by the angular integral
    "gaussian_lobes": build_green_lobes,  # [Green07], one row per K
})


def deprecated_row_key(key: str) -> dict[str, Any]:
    """``{"deprecated_key": old}`` for a row whose key changed with the table of methods
    (``rsibr`` was ``cabral_shrm``, ``gaussian_lobes_k3`` was ``gaussian_k3`` …), else ``{}``:
    compare's JSON rows carry it for one release (``data_specs/compare_json.md``)."""
    if key in _OLD_ROWS:
        return {"deprecated_key": _OLD_ROWS[key]}
    match = re.fullmatch(r"gaussian_lobes_k(\d+)", key)
    return {"deprecated_key": f"gaussian_k{match.group(1)}"} if match else {}


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
