"""The isotropic BRDF interface every source (model, table, measurement) implements.

Directions are unit vectors in the local frame of the surface (normal +z), both
pointing away from the surface. ``eval`` returns rho without the cosine factor;
``rho_hat`` returns the cosine-weighted transfer function rho * max(N.L, 0) used by the
frequency analysis ([RH02] §3.1), which some models (Phong, [RH02]'s simplified microfacet)
define directly.

Reference: [RH02] (``data_specs/bibliography.md``).
"""

from __future__ import annotations

import abc
from typing import Literal

import numpy as np

from .notebook import brdf_html, brdf_png

__all__ = ["BRDF", "Kind", "as_directions"]

Kind = Literal["analytic", "tabulated", "scattered"]


def as_directions(L: np.ndarray, V: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Broadcast two arrays of 3-vectors against each other as float64."""
    L = np.asarray(L, dtype=np.float64)
    V = np.asarray(V, dtype=np.float64)
    if L.shape[-1:] != (3,) or V.shape[-1:] != (3,):
        raise ValueError(f"directions must have a last axis of 3, got {L.shape} and {V.shape}")
    L, V = np.broadcast_arrays(L, V)
    return L, V


class BRDF(abc.ABC):
    """An isotropic BRDF.

    Attributes
    ----------
    name
        Human-readable name (the spec string or the file stem).
    kind
        ``"analytic"``, ``"tabulated"`` or ``"scattered"``.
    """

    name: str
    kind: Kind

    @abc.abstractmethod
    def eval(self, L: np.ndarray, V: np.ndarray) -> np.ndarray:
        """RGB rho(L, V) in 1/sr, shape ``(..., 3)``, without the cosine factor.

        Zero where either direction is below the surface.
        """

    def eval_counted(self, L: np.ndarray, V: np.ndarray) -> tuple[np.ndarray, int]:
        """``eval`` plus the number of query points that had no data to use.

        Tabulated BRDFs with missing measurements override this; models return 0.
        """
        return self.eval(L, V), 0

    def rho_hat(self, L: np.ndarray, V: np.ndarray) -> np.ndarray:
        """Cosine-weighted transfer rho(L, V) * max(L_z, 0), shape ``(..., 3)`` (RH02 §3.1)."""
        L, V = as_directions(L, V)
        return self.eval(L, V) * np.maximum(L[..., 2], 0.0)[..., None]

    def _repr_html_(self) -> str:
        """Notebook card: name, kind, a lit-sphere thumbnail (``brdf_io.notebook``)."""
        return brdf_html(self)

    def _repr_png_(self) -> bytes | None:
        """Notebook picture: the lit sphere as PNG (None for scattered measurements)."""
        return brdf_png(self)

    def __repr__(self) -> str:
        return f"<{type(self).__name__} {self.name!r} ({self.kind})>"
