"""The published representations the SHRM is compared against and the renderer can draw, and the
angular-domain methods its speed is measured against.

Public API — the table of published methods (:mod:`.methods`, ``data_specs/methods.md``): one
:class:`Method` per method (key, display name, cite key, settings with limits, a builder that
returns the plain model) in :data:`METHODS`, looked up by :func:`get_method` / :func:`method_key`;
the builders :func:`shrm_model` [RH02], :func:`kautz_mccool_model` [KM00], :func:`rsibr_model`
[Cabral99] and :func:`gaussian_lobes_model` [Green07]. ``shrmkit.render.modes`` and
``shrmkit.analysis.compare`` build through it.

The modules behind it, importable by their paths: :mod:`.rsibr` and :mod:`.icosahedron`
(twelve maps blended with spherical barycentric weights [Cabral99]); :mod:`.gaussian_lobes` and
:mod:`.selfshadow` (Gaussian lobes over a spherical-Gaussian mip stack, per-vertex SH visibility
[Green07]); :mod:`.lobe_truncated` (the angular sum over the lobe's significant pixels, [RH02]
Table 4) and :mod:`.split_sum` (the engines' split sum for GGX [Karis13], [LdR14]), the speed
baselines of ``benchmarks/prefilter_speed.py``. Citation keys: ``data_specs/bibliography.md``.
"""

from __future__ import annotations

from ...brdf_io.lazy import lazy_exports as _lazy_exports

#: Public name → the module that defines it (imported on first use).
_LAZY = {
    "Method": "shrmkit.analysis.baselines.methods",
    "Setting": "shrmkit.analysis.baselines.methods",
    "METHODS": "shrmkit.analysis.baselines.methods",
    "get_method": "shrmkit.analysis.baselines.methods",
    "method_key": "shrmkit.analysis.baselines.methods",
    "shrm_model": "shrmkit.analysis.baselines.methods",
    "kautz_mccool_model": "shrmkit.analysis.baselines.methods",
    "rsibr_model": "shrmkit.analysis.baselines.methods",
    "gaussian_lobes_model": "shrmkit.analysis.baselines.methods",
}

__all__ = list(_LAZY)


__getattr__, __dir__ = _lazy_exports(__name__, _LAZY, __all__)
