"""The (R, V) samplers of the project's error measurements: one home, :mod:`shrmkit.analysis.pairs`
(the prefilter's statements use them too); re-exported here for the comparison package."""

from ..pairs import band_pairs, brightest_pixels, sample_pairs, sample_pairs_focused

__all__ = ["sample_pairs", "sample_pairs_focused", "brightest_pixels", "band_pairs"]
