"""Numpy-free names of brdf_io's registries, for what must start fast (``shrm VERB --help`` and
usage errors: issue 26).

The one home of the tone curves' names (:data:`~shrmkit.brdf_io.display.TONE_MAPS`) and of the
largest Zernike order (:data:`~shrmkit.brdf_io.zernike.MAX_ORDER`). The registries hold readers
and writers (numpy), so their names are mirrored here, in their order: the BRDF file types
(:data:`~shrmkit.brdf_io.specs.BRDF_FILE_TYPES`), the RGL incident directions
(:data:`~shrmkit.brdf_io.rgl.RGL_INCIDENT`), the export formats
(:data:`~shrmkit.brdf_io.export_formats.EXPORT_FORMATS`), the DDS texel formats
(:data:`~shrmkit.brdf_io.dds.DDS_FORMATS`); ``tests/cli/test_cli_startup.py`` checks that both
agree. Internal module.
"""

from __future__ import annotations

__all__ = [
    "BRDF_FILE_SUFFIXES",
    "BRDF_SELECTOR_SUFFIXES",
    "BRDF_MEMBER_SUFFIXES",
    "RGL_INCIDENT_NAMES",
    "EXPORT_FORMAT_SUFFIXES",
    "DDS_FORMAT_NAMES",
    "TONE_MAP_NAMES",
    "ZERNIKE_MAX_ORDER",
]

#: The BRDF file suffixes ``load_brdf`` reads (the keys of ``specs.BRDF_FILE_TYPES``).
BRDF_FILE_SUFFIXES = (".binary", ".npz", ".brdf", ".bsdf", ".dat", ".csv", ".json")
#: The suffixes whose files take a selector, ``FILE#...`` (an RGL incident direction, a CURET
#: sample, a gonioreflectometer wavelength).
BRDF_SELECTOR_SUFFIXES = (".bsdf", ".dat", ".csv")
#: The suffixes of multi-BRDF files: the whole file names every member.
BRDF_MEMBER_SUFFIXES = (".dat", ".csv")
#: The directions that may play an RGL file's incident direction (the keys of ``rgl.RGL_INCIDENT``).
RGL_INCIDENT_NAMES = ("camera", "light")
#: Export format name -> the suffix of its files (``export_formats.EXPORT_FORMATS``).
EXPORT_FORMAT_SUFFIXES = {
    "mitsuba": ".xml",
    "mitsuba-dict": ".json",
    "pbrt": ".pbrt",
    "materialx": ".mtlx",
    "merl": ".binary",
    "dds": ".dds",
    "ktx2": ".ktx2",
}
#: The DDS texel formats ``write_dds_cube`` writes (the keys of ``dds.DDS_FORMATS``).
DDS_FORMAT_NAMES = ("rgba16f", "rgba32f", "rgba8")
#: The tone curves of ``display.tone_map`` (``display.TONE_MAPS``).
TONE_MAP_NAMES = ("srgb", "filmic")
#: Largest supported Zernike order (506 terms); the limit keeps basis matrices small (``zernike.MAX_ORDER``).
ZERNIKE_MAX_ORDER = 20
