"""The written contract of a representation compared with the SHRM, and what builders share.

A representation is anything that predicts the radiance B(R, V) reflected by a surface under
one distant environment and states its costs; :class:`Representation` is that contract as a
``typing.Protocol``. Builders (one per kind, listed in :mod:`.registry`) receive a
:class:`BuildContext` — the inputs, the :class:`~.options.CompareOptions` whole, the SHRM
every kind is measured against — and return :class:`BuiltRepresentation` objects.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, Protocol, runtime_checkable

import numpy as np

from ...brdf_io.brdf import BRDF
from ...brdf_io.envmap import EnvironmentMap
from ..baselines.methods import shrm_model
from ..shrm import SHRM
from .options import CompareOptions

__all__ = ["RadianceModel", "Representation", "BuiltRepresentation", "BuildContext", "time_update"]


class RadianceModel(Protocol):
    """What a representation's data evaluates (an SHRM, Cabral's maps, Gaussian lobes …).

    Frame and units: directions are float64 unit vectors in the z-up frame of DESIGN §2;
    radiance is linear RGB, in the units of the environment map it was built from.
    """

    def radiance(self, R: np.ndarray, V: np.ndarray) -> np.ndarray:
        """Predicted radiance B(R, V): R, V float64 (n, 3) unit vectors (reflection and view
        directions, z-up; the normal is normalize(R + V)) → (n, 3) linear RGB radiance in
        the environment's units."""
        ...

    def view_map(self, view: np.ndarray) -> np.ndarray:
        """The distant viewer's map for one view direction ``view`` (3,): float32 (H, W, 3),
        B(R, view) at the lat-long pixel centres R of DESIGN §2, linear radiance."""
        ...


@runtime_checkable
class Representation(RadianceModel, Protocol):
    """One representation of the reflected light field B(R, V), with its costs: the
    :class:`RadianceModel` methods ``radiance(R, V)`` and ``view_map(view)`` plus the
    read-only attributes below.

    Attributes
    ----------
    key
        Machine name, the row key of the comparison table (``shrm``, ``kautz_mccool``,
        ``gaussian_lobes_k2`` …); unique within one comparison.
    label
        Human label for tables (``SHRM F=12 P=4``).
    short_label
        A label that fits a 64-pixel image panel (about 10 characters: ``KM P=4``).
    storage_bytes
        Bytes of the data a renderer uploads (float32 maps, lobe tables).
    precompute_s
        Wall seconds from the BRDF and the environment to that data.
    update_s
        Wall seconds of CPU work per new view direction before drawing, for a distant viewer
        (the :meth:`view_map` a renderer would upload); 0 when nothing changes per view.
    params
        JSON-able parameters (orders, map size, K, fit residual …).
    """

    @property
    def key(self) -> str: ...

    @property
    def label(self) -> str: ...

    @property
    def short_label(self) -> str: ...

    @property
    def storage_bytes(self) -> int: ...

    @property
    def precompute_s(self) -> float: ...

    @property
    def update_s(self) -> float: ...

    @property
    def params(self) -> Mapping[str, Any]: ...


@dataclass(frozen=True, eq=False)
class BuiltRepresentation:
    """A :class:`Representation` made by a builder: its numbers plus the ``model`` that
    evaluates it (an :class:`~shrmkit.analysis.shrm.SHRM`, Cabral maps, Gaussian lobes …)."""

    key: str
    label: str
    short_label: str
    model: RadianceModel
    storage_bytes: int
    precompute_s: float
    update_s: float
    params: dict[str, Any] = field(default_factory=dict)

    def radiance(self, R: np.ndarray, V: np.ndarray) -> np.ndarray:
        """B(R, V), (n, 3): :meth:`RadianceModel.radiance`."""
        return self.model.radiance(R, V)

    def view_map(self, view: np.ndarray) -> np.ndarray:
        """float32 (H, W, 3) distant-viewer map: :meth:`RadianceModel.view_map`."""
        return self.model.view_map(view)


def time_update(fn: Callable[[], Any], repeat: int = 5) -> float:
    """Median wall time of ``repeat`` calls of ``fn`` (after one warm-up call)."""
    fn()
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return float(np.median(times))


@dataclass(eq=False)
class BuildContext:
    """What every builder receives: the inputs as evaluated, the options, a progress hook.

    ``base_shrm()`` is the SHRM at ``options.eps`` that several kinds derive from (lower P,
    Kautz–McCool at the same (F, P), Cabral's maps from the SHRM); it is prefiltered on first
    use and shared, so the order of the registry does not matter.
    """

    env: EnvironmentMap
    brdf: BRDF
    options: CompareOptions
    progress: Callable[[str], None] | None = None
    _base: tuple[SHRM, float] | None = field(default=None, init=False, repr=False)

    def stage(self, name: str) -> None:
        """Report a stage to the progress hook."""
        if self.progress is not None:
            self.progress(name)

    @property
    def update_view(self) -> np.ndarray:
        """``options.update_view`` normalized, float64 (3,)."""
        view = np.asarray(self.options.update_view, dtype=np.float64)
        return view / np.linalg.norm(view)

    def base_shrm(self) -> tuple[SHRM, float]:
        """(the [RH02] SHRM at ``options.eps`` with the options' order rule, its prefilter seconds):
        ``analysis.baselines.methods.shrm_model``."""
        if self._base is None:
            self.stage("SHRM")
            t0 = time.perf_counter()
            shrm = shrm_model(self.env, self.brdf, **self.options.shrm_settings())
            self._base = (shrm, time.perf_counter() - t0)
        return self._base

    def make(self, key: str, label: str, short_label: str, model: RadianceModel, *, storage_bytes: int,
             precompute_s: float, params: dict[str, Any], static: bool = False) -> BuiltRepresentation:
        """A :class:`BuiltRepresentation`, timing ``model.view_map`` at :attr:`update_view` for
        ``update_s`` unless ``static`` (nothing to do per view: ``update_s = 0``)."""
        view = self.update_view
        update_s = 0.0 if static else time_update(lambda: model.view_map(view))
        return BuiltRepresentation(key, label, short_label, model, int(storage_bytes), float(precompute_s),
                                   update_s, params)
