"""The registry of ``shrm export`` targets: one entry per file format written, by name.

Each :class:`ExportFormat` names its kind: ``material`` (a renderer's material snippet,
:data:`~shrmkit.brdf_io.export_material.MATERIAL_TARGETS`), ``brdf-table`` (a MERL ``.binary``
table, :func:`~shrmkit.brdf_io.merl.write_merl`) or ``cube-mip-chain`` (a prefiltered
environment as a DDS or KTX2 cube map, :func:`~shrmkit.brdf_io.dds.write_dds_cube`,
:func:`~shrmkit.brdf_io.ktx2.write_ktx2_cube`: the entry's ``write_cube``). :func:`export_format`
picks the format from a name or from the output file's suffix. Layouts: ``data_specs/export.md``.

Public objects: :class:`ExportFormat`, :data:`EXPORT_FORMATS`, :func:`export_format`.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from .dds import write_dds_cube
from .errors import BadInputError
from .export_material import MATERIAL_TARGETS
from .ktx2 import write_ktx2_cube

__all__ = ["ExportFormat", "EXPORT_FORMATS", "export_format"]


@dataclass(frozen=True)
class ExportFormat:
    """One export target: its name, the output suffix, its kind and a one-line description;
    for a ``cube-mip-chain`` its writer ``write_cube(path, levels, *, fmt)`` (levels largest
    first, (6, S_m, S_m, 3) each; ``fmt`` a key of ``brdf_io.dds.DDS_FORMATS``)."""

    name: str
    suffix: str
    kind: str
    description: str
    write_cube: Callable[..., Path] = field(default=lambda path, *_, **__: _no_cube(path))


def _no_cube(path: str | os.PathLike[str]) -> Path:
    """``write_cube`` of a format that is not a cube map: refuses."""
    raise BadInputError(path, "this export format does not hold a cube map")


#: Every export target, by name (``shrm export --to NAME``).
EXPORT_FORMATS: dict[str, ExportFormat] = {
    **{name: ExportFormat(name, t.suffix, "material", t.description) for name, t in MATERIAL_TARGETS.items()},
    "merl": ExportFormat("merl", ".binary", "brdf-table", "MERL .binary table (90 x 90 x 180 half/diff samples)"),
    "dds": ExportFormat("dds", ".dds", "cube-mip-chain",
                        "GGX-prefiltered environment, DX10 DDS cube map with one roughness per mip level",
                        write_dds_cube),
    "ktx2": ExportFormat("ktx2", ".ktx2", "cube-mip-chain",
                         "GGX-prefiltered environment, KTX 2.0 cube map with one roughness per mip level",
                         write_ktx2_cube),
}


def export_format(name: str | None, path: str | os.PathLike[str]) -> ExportFormat:
    """The format called ``name``, or (``name`` None) the one whose suffix ``path`` has.

    Raises
    ------
    BadInputError
        An unknown name, a suffix no format (or more than one) writes, a suffix that
        contradicts ``name``, or a file name with no stem (``.ktx2``, a hidden file name).
    """
    file_name = Path(path).name
    if file_name.startswith(".") and not Path(path).suffix:  # ".ktx2": Python reads a hidden file's name as its stem
        written = any(f.suffix == file_name.lower() for f in EXPORT_FORMATS.values())
        example = f", e.g. sky{file_name}" if written else ""
        raise BadInputError(path, f"the file name {file_name!r} has no stem (a hidden file name, no suffix): "
                                  f"name the file{example}")
    suffix = Path(path).suffix.lower()
    if name is not None:
        if name not in EXPORT_FORMATS:
            raise BadInputError(None, f"unknown export format {name!r}; choose from {', '.join(EXPORT_FORMATS)}")
        fmt = EXPORT_FORMATS[name]
        if suffix != fmt.suffix:
            raise BadInputError(path, f"{name} files end in {fmt.suffix}")
        return fmt
    matches = [f for f in EXPORT_FORMATS.values() if f.suffix == suffix]
    if len(matches) != 1:
        known = ", ".join(f"{f.suffix} ({f.name})" for f in EXPORT_FORMATS.values())
        why = "is written by several formats: name one with name=FORMAT" if matches else "is not a format written"
        raise BadInputError(path, f"suffix {suffix or '(none)'!r} {why}; known: {known}")
    return matches[0]
