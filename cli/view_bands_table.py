"""One terminal table for the per-view-band error statements of every verb."""

from __future__ import annotations

from rich.table import Table

from .common import print_table

__all__ = ["print_view_bands"]


def _fmt(value: float | None) -> str:
    if value is None or value != value:  # NaN: nothing measured in the band
        return "-"
    return f"{value:.3g}"


def print_view_bands(
    bands: list[dict], title: str, *, point_light: bool = False, measured: bool = False
) -> None:
    """Print ``bands`` (``SHRM.meta["view_bands"]``, ``OrderChoice.view_bands()`` or a scene's)
    with, when ``measured``, their ``measured_rel_rms`` ± ``measured_stderr``
    (``analysis.compare.beside_measured``) beside.

    Bands beyond the view limit are marked "stated" (errors stated, not promised); bands with
    missing measurements "extrapolated" (the bound does not hold there)."""
    table = Table(title=title)
    table.add_column("theta_v (deg)", justify="right")
    if point_light:
        table.add_column("eps", justify="right")
        table.add_column("rel. RMS", justify="right")
    else:
        table.add_column("predicted rel. RMS", justify="right")
        table.add_column("bound rel. RMS", justify="right")
    if measured:
        table.add_column("measured rel. RMS", justify="right")
    table.add_column("", justify="left")
    for band in bands:
        lo, hi = band["theta_v_deg"]
        cells = [f"{lo:g}-{hi:g}"]
        if point_light:
            cells += [_fmt(band["eps"]), _fmt(band["rel_rms_point_light"])]
        else:
            cells += [_fmt(band["predicted_rel_rms"]), _fmt(band["bound_rel_rms"])]
        if measured:
            cells.append(f"{_fmt(band['measured_rel_rms'])} ± {_fmt(band['measured_stderr'])}")
        notes = [] if band["inside"] else ["stated"]
        if band.get("extrapolated_samples"):
            notes.append("extrapolated")
        cells.append(", ".join(notes))
        table.add_row(*cells)
    print_table(table)
