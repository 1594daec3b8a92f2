"""A BRDF as another renderer's material, with the error of the conversion measured.

:func:`export_material` takes any BRDF shrmkit reads (a model, a fit document, a measured
table) and a target of :data:`~shrmkit.brdf_io.export_material.MATERIAL_TARGETS`:

1. the **closest model the renderers share**: a Lambert or Cook–Torrance model is used as it
   is; a Lafortune model without lobes (or with zero ks) is its Lambert term; every other BRDF (Lafortune lobes,
   [RH02]'s Phong and simplified microfacet, Zernike expansions, tables) has no counterpart and
   goes through its closest Cook–Torrance GGX model, fitted by :func:`~shrmkit.analysis.fit.fit_brdf`
   (cosine-weighted relative RMS);
2. the target's closest material to that model
   (:func:`~shrmkit.brdf_io.export_material.to_target`);
3. the **error** of the exported material against the source BRDF, measured on the fit
   samples (Sobol direction pairs, θ_i, θ_o ≤ 80°, quadrature weights; ``analysis/fit/sampling.py``):
   the cosine-weighted relative RMS of ρ cos θ_i over all samples and per view-elevation band
   (``analysis/fit/summary.py``), the worst band stated first. The material is evaluated as the
   renderer defines it (:meth:`~shrmkit.brdf_io.export_material.ExportedMaterial.eval`).

Public objects: :class:`MaterialExport`, :func:`export_material`, :func:`closest_shared_model`.

Reference: [RH02] (the view-band errors of DESIGN §4).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..brdf_io.brdf import BRDF
from ..brdf_io.export_material import ExportedMaterial, to_target
from ..brdf_io.models import AnalyticModel, CookTorrance, Lafortune, Lambert
from ..brdf_io.zernike import ZernikeBRDF
from .fit import fit_brdf
from .fit.metrics import rel_rms
from .fit.sampling import collect_samples
from .fit.summary import BandError, band_errors, worst_band

__all__ = ["MaterialExport", "export_material", "closest_shared_model"]

#: Direction pairs drawn to measure an export's error (before the 80° cut).
ERROR_SAMPLES = 16384


@dataclass(frozen=True, eq=False)
class MaterialExport:
    """An exported material and its measured error.

    Attributes
    ----------
    source
        Name of the BRDF exported.
    model
        The Lambert or Cook–Torrance model converted (the source itself, or its closest fit).
    model_note
        Empty when ``model`` is the source; else one line saying why and how it was chosen.
    material
        The target's material (:class:`~shrmkit.brdf_io.export_material.ExportedMaterial`).
    rel_rms
        Cosine-weighted relative RMS of ρ cos θ_i, exported material against the source, all samples.
    bands
        The same per view-elevation band θ_o.
    worst
        The band with the largest error (None when no band has enough samples).
    """

    source: str
    model: AnalyticModel | ZernikeBRDF
    model_note: str
    material: ExportedMaterial
    rel_rms: float
    bands: tuple[BandError, ...]
    worst: BandError | None

    @property
    def exact(self) -> bool:
        """The renderer's BSDF is the source BRDF (no closest model, no approximate mapping)."""
        return not self.model_note and self.material.exact

    def error_line(self) -> str:
        """One line: the measured error, worst view band first."""
        worst = "" if self.worst is None else (
            f"worst view band {self.worst.lo_deg:g}-{self.worst.hi_deg:g} deg rel. RMS {self.worst.rel_rms:.3g}, ")
        return f"measured error against {self.source}: {worst}all views {self.rel_rms:.3g} (rho cos theta_i)"

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready summary (``data_specs/export.md``)."""
        return {"target": self.material.target, "source": self.source, "model": self.model.to_spec(),
                "model_note": self.model_note or None, "exact": self.exact, "note": self.material.note or None,
                "native": self.material.native, "rel_rms": self.rel_rms,
                "worst_band": None if self.worst is None else self.worst.as_dict(),
                "bands": [b.as_dict() for b in self.bands]}


def closest_shared_model(brdf: BRDF, *, seed: int = 0, n_samples: int = 8192, starts: int = 2
                         ) -> tuple[AnalyticModel | ZernikeBRDF, str]:
    """(model, note): ``brdf`` itself when it is Lambert or Cook–Torrance (note empty), a
    lobeless Lafortune model's Lambert term, else its closest Cook–Torrance GGX fit
    (``fit_brdf(..., "cook-torrance", distribution="ggx")``) with a note naming why.

    Raises
    ------
    BadInputError
        A BRDF the fit cannot sample (all zero, negative values).
    """
    if isinstance(brdf, Lambert | CookTorrance):
        return brdf, ""
    if isinstance(brdf, Lafortune) and not any(np.any(np.asarray(lobe.ks) > 0) for lobe in brdf.lobes):
        return Lambert(albedo=np.asarray(brdf.kd, dtype=np.float64) * np.ones(3)), ""
    kind = type(brdf).__name__ if brdf.kind == "analytic" else f"{brdf.kind} data"
    fit = fit_brdf(brdf, "cook-torrance", distribution="ggx", seed=seed, n_samples=n_samples, starts=starts)
    return fit.brdf, (f"no exact counterpart for {kind}: exported its closest Cook-Torrance GGX fit "
                      f"({fit.brdf.to_spec()})")


def export_material(brdf: BRDF, target: str, *, reference: BRDF | None = None, seed: int = 0,
                    n_samples: int = ERROR_SAMPLES, fit_samples: int = 8192, fit_starts: int = 2) -> MaterialExport:
    """Convert ``brdf`` to ``target``'s closest material and measure the error (module docstring).

    Parameters
    ----------
    brdf
        Any BRDF (analytic, tabulated; scattered measurements through their chosen representation).
    target
        A key of :data:`~shrmkit.brdf_io.export_material.MATERIAL_TARGETS`.
    reference
        What the error is measured against (default ``brdf``): the measurements themselves when
        ``brdf`` is the representation chosen for scattered data (their own points are the samples).
    seed, n_samples
        The error's Sobol direction pairs (the same seed gives the same numbers).
    fit_samples, fit_starts
        The closest-model fit's samples and multi-start seeds (when one is needed).

    Raises
    ------
    BadInputError
        Unknown target; a BRDF that cannot be sampled.
    """
    model, note = closest_shared_model(brdf, seed=seed, n_samples=fit_samples, starts=fit_starts)
    material = to_target(model, target)
    reference = brdf if reference is None else reference
    samples = collect_samples(reference, n_samples=n_samples, seed=seed)
    rho = material.eval(samples.L, samples.V)
    bands = band_errors(samples, rho)
    return MaterialExport(source=reference.name, model=model, model_note=note, material=material,
                          rel_rms=rel_rms(samples, rho), bands=bands, worst=worst_band(bands))
