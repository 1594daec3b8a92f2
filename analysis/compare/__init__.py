"""The numbers of a comparison: the SHRM [RH02] against Kautz–McCool [KM00], RSIBR [Cabral99] and
Gaussian lobes [Green07], the published methods of :mod:`shrmkit.analysis.baselines.methods` under
their keys there (citation keys: ``data_specs/bibliography.md``).

- :func:`compare` / :func:`compare_representations` (:mod:`.table`): every representation
  against the angular reference, one JSON-able table (``data_specs/compare_json.md``); the
  latter also returns the built representations (for ``shrmkit.render.strip``).
- :class:`CompareOptions` (:mod:`.options`): every option, passed whole.
- :class:`Representation` (:mod:`.representation`): the contract of a representation;
  :data:`REGISTRY` (:mod:`.registry`): kind key → builder.
- :func:`sample_pairs` (:mod:`.pairs`) and :func:`relative_rms` (:mod:`.metrics`): the one
  (R, V) sampler and the one error metric of the project.
- :func:`band_sample` and :func:`band_error` (:mod:`.band_error`): the per-view-band measurement
  (importance-sampled, stratified pairs; a standard error that matches the seed-to-seed spread).

This package never imports the render layer.
"""

from .band_error import BandSample, band_error, band_sample, pairs_per_band, pixel_density
from .metrics import band_relative_rms, beside_measured, relative_rms
from .options import DEFAULT_ENV_HEIGHT, CompareOptions
from .pairs import band_pairs, brightest_pixels, sample_pairs, sample_pairs_focused
from .registry import REGISTRY, Builder, build_representations
from .representation import BuildContext, BuiltRepresentation, RadianceModel, Representation, time_update
from .table import FRONTAL_DEG, GRAZING_DEG, Comparison, compare, compare_representations, table_markdown

__all__ = [
    "compare", "compare_representations", "Comparison", "table_markdown", "GRAZING_DEG", "FRONTAL_DEG",
    "CompareOptions", "DEFAULT_ENV_HEIGHT",
    "Representation", "RadianceModel", "BuiltRepresentation", "BuildContext", "time_update",
    "REGISTRY", "Builder", "build_representations",
    "sample_pairs", "sample_pairs_focused", "band_pairs", "brightest_pixels",
    "relative_rms", "band_relative_rms", "beside_measured",
    "BandSample", "band_sample", "band_error", "pixel_density", "pairs_per_band",
]
