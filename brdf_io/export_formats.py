"""The registry of ``shrm export`` targets: one entry per file format written, by name.

Each :class:`ExportFormat` names its kind: ``material`` (a renderer's material snippet,
:data:`~shrmkit.brdf_io.export_material.MATERIAL_TARGETS`), ``brdf-table`` (a MERL ``.binary``
table, :func:`~shrmkit.brdf_io.merl.write_merl`) or ``cube-mip-chain`` (a prefiltered
environment, :func:`~shrmkit.brdf_io.dds.write_dds_cube`). :func:`export_format` picks the
format from a name or from the output file's suffix. Layouts: ``data_specs/export.md``.

Public objects: :class:`ExportFormat`, :data:`EXPORT_FORMATS`, :func:`export_format`.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from .errors import BadInputError
from .export_material import MATERIAL_TARGETS

__all__ = ["ExportFormat", "EXPORT_FORMATS", "export_format"]


@dataclass(frozen=True)
class ExportFormat:
    """One export target: its name, the output suffix, its kind and a one-line description."""

    name: str
    suffix: str
    kind: str
    description: str


#: Every export target, by name (``shrm export --to NAME``).
EXPORT_FORMATS: dict[str, ExportFormat] = {
    **{name: ExportFormat(name, t.suffix, "material", t.description) for name, t in MATERIAL_TARGETS.items()},
    "merl": ExportFormat("merl", ".binary", "brdf-table", "MERL .binary table (90 x 90 x 180 half/diff samples)"),
    "dds": ExportFormat("dds", ".dds", "cube-mip-chain",
                        "GGX-prefiltered environment, DX10 DDS cube map with one roughness per mip level"),
}


def export_format(name: str | None, path: str | os.PathLike[str]) -> ExportFormat:
    """The format called ``name``, or (``name`` None) the one whose suffix ``path`` has.

    Raises
    ------
    BadInputError
        An unknown name, a suffix no format (or more than one) writes, or a suffix that
        contradicts ``name``.
    """
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
        why = "is written by several formats: name one with --to" if matches else "is not a format written"
        raise BadInputError(path, f"suffix {suffix or '(none)'!r} {why}; known: {known}")
    return matches[0]
