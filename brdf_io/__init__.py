"""BRDF and environment-map input/output, analytic models and the reflection-vector
reparameterization (DESIGN §1–3): the bottom layer of the stack, importing no other layer.

Public API — the names in ``__all__``, importable from ``shrmkit.brdf_io``:

- BRDFs: :class:`BRDF` (the evaluable interface), :func:`load_brdf` (spec string or file),
  :func:`brdf_from_spec`, :func:`brdf_sources` (the members of a multi-BRDF file); the
  analytic models :class:`Lambert`, :class:`PhongLobe`, :class:`SimplifiedMicrofacet`
  ([RH02] eq. 11), :class:`CookTorrance` [CT82], :class:`Lafortune` and :class:`LafortuneLobe`
  [Laf97]; the measured and fitted kinds :class:`MerlBRDF` [MERL03], :class:`TableBRDF`,
  :class:`ScatteredBRDF` (Cornell), :class:`RGLBRDF` [DJ18], :class:`ZernikeBRDF`.
- Readers and writers: :func:`read_merl` / :func:`write_merl` / :func:`tabulate_merl`,
  :func:`read_table` / :func:`write_table` / :func:`tabulate_table`, :func:`read_cornell`,
  :func:`read_rgl`, :func:`read_curet` [CURET99], :func:`read_gonio_csv`; HDR images
  :func:`read_image` / :func:`write_image` (``.exr``, ``.hdr``, ``.pfm``).
- Environments: :class:`EnvironmentMap`, :func:`load_env`, :func:`save_env`,
  :func:`env_rotation_matrix` (the one definition of a turned map).
- Conventions (DESIGN §2): :func:`pixel_directions`, :func:`row_solid_angles` and
  :func:`bilinear_lookup` (the lat-long grid), :func:`directions_to_halfdiff` and
  :func:`halfdiff_to_directions` [Rus98].
- The reparameterization by the reflection vector ([RH02] §3.1): :func:`reparameterize`,
  :class:`ReparamBRDF`, :class:`ReparamGrid`.
- Errors: :class:`ShrmError` (every error of the package), :class:`BadInputError` (a bad file,
  spec or argument), :class:`ScatteredEvalError`.

Modules not listed here are internal: their names may change without notice. The file formats
are documented in ``data_specs/``; the short citation keys in ``data_specs/bibliography.md``.
Names are imported on first use, so ``import shrmkit.brdf_io`` stays fast.
"""

from __future__ import annotations

from .errors import BadInputError, ScatteredEvalError, ShrmError
from .lazy import lazy_exports as _lazy_exports

#: Public name → the module that defines it (imported on first use).
_LAZY = {
    # also BRDF and the spec readers: importing the package (e.g. for its errors, as the command line's
    # start-up does) must not import numpy
    "BRDF": "shrmkit.brdf_io.brdf",
    "brdf_from_spec": "shrmkit.brdf_io.specs",
    "load_brdf": "shrmkit.brdf_io.specs",
    "brdf_sources": "shrmkit.brdf_io.specs",
    "Lambert": "shrmkit.brdf_io.models",
    "PhongLobe": "shrmkit.brdf_io.models",
    "SimplifiedMicrofacet": "shrmkit.brdf_io.models",
    "CookTorrance": "shrmkit.brdf_io.models",
    "Lafortune": "shrmkit.brdf_io.models",
    "LafortuneLobe": "shrmkit.brdf_io.models",
    "MerlBRDF": "shrmkit.brdf_io.merl",
    "read_merl": "shrmkit.brdf_io.merl",
    "write_merl": "shrmkit.brdf_io.merl",
    "tabulate_merl": "shrmkit.brdf_io.merl",
    "TableBRDF": "shrmkit.brdf_io.table",
    "read_table": "shrmkit.brdf_io.table",
    "write_table": "shrmkit.brdf_io.table",
    "tabulate_table": "shrmkit.brdf_io.table",
    "ScatteredBRDF": "shrmkit.brdf_io.cornell",
    "read_cornell": "shrmkit.brdf_io.cornell",
    "RGLBRDF": "shrmkit.brdf_io.rgl",
    "read_rgl": "shrmkit.brdf_io.rgl",
    "read_curet": "shrmkit.brdf_io.curet",
    "read_gonio_csv": "shrmkit.brdf_io.gonio",
    "ZernikeBRDF": "shrmkit.brdf_io.zernike",
    "read_image": "shrmkit.brdf_io.hdr_codecs",
    "write_image": "shrmkit.brdf_io.hdr_codecs",
    "EnvironmentMap": "shrmkit.brdf_io.envmap",
    "load_env": "shrmkit.brdf_io.envmap",
    "save_env": "shrmkit.brdf_io.envmap",
    "env_rotation_matrix": "shrmkit.brdf_io.env_rotation",
    "pixel_directions": "shrmkit.brdf_io.latlong",
    "row_solid_angles": "shrmkit.brdf_io.latlong",
    "bilinear_lookup": "shrmkit.brdf_io.latlong",
    "directions_to_halfdiff": "shrmkit.brdf_io.halfdiff",
    "halfdiff_to_directions": "shrmkit.brdf_io.halfdiff",
    "reparameterize": "shrmkit.brdf_io.reparam",
    "ReparamBRDF": "shrmkit.brdf_io.reparam",
    "ReparamGrid": "shrmkit.brdf_io.reparam",
}

__all__ = ["BadInputError", "ScatteredEvalError", "ShrmError", *_LAZY]


__getattr__, __dir__ = _lazy_exports(__name__, _LAZY, __all__)
