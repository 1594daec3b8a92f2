"""Write one BRDF's report folder atomically, and the batch summary (CSV and index.html).

A report folder is assembled in a temporary folder beside its target and renamed into
place, so a crash leaves either the old folder or the new one, never a half-written one
(an existing folder is moved aside first and removed after the rename).
"""

from __future__ import annotations

import csv
import io
import json
import os
import shutil
import tempfile
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from ...brdf_io.atomic import atomic_path
from .explorer import LiveView, ReportImage
from .html import index_html, report_html
from .markdown import report_markdown
from .plot_names import plots_wanted
from .shared_state import lean_matplotlib

__all__ = ["report_files", "write_folder", "summary_row", "summary_columns", "write_summary"]


def _draw(doc: dict[str, Any], keys: Sequence[str]) -> dict[str, bytes]:
    """``plots.make_plots``: matplotlib (~0.5 s CPU of import) is loaded by the first report that draws."""
    lean_matplotlib()  # the console script's process: no docstring tables (before matplotlib's import)
    from .plots import make_plots  # matplotlib: only for a report that draws plots

    return make_plots(doc, keys)


def report_files(doc: dict[str, Any], previews: Sequence[Any] = ()) -> dict[str, bytes]:
    """Every file of a report folder: ``report.json``, ``report.md``, ``report.html`` and
    the PNG plots the report's options ask for (``plots``, ``explorer_plots``) and previews, as
    ``{file name: bytes}``.

    ``previews`` is what ``collect_report`` returns beside the document: preview images
    (``preview_<key>.png``), ``explorer.ReportImage`` (the lit spheres, under their own file
    name) and ``explorer.LiveView`` (live WebGL2 previews, embedded in ``report.html`` only)."""
    wanted = plots_wanted(doc)  # the plots the options ask for; matplotlib is imported only to draw some
    drawn = _draw(doc, wanted) if wanted else {}
    pngs = {f"plot_{key}.png": data for key, data in drawn.items()}
    views = []
    for p in previews:
        if isinstance(p, LiveView):  # embedded in report.html only
            views.append(p)
        elif isinstance(p, ReportImage):
            pngs[p.file] = p.png
        else:
            pngs[f"preview_{p.key}.png"] = p.png
    files = {
        "report.json": (json.dumps(doc, indent=1, ensure_ascii=False, allow_nan=False) + "\n").encode("utf-8"),
        "report.md": report_markdown(doc).encode("utf-8"),
        "report.html": report_html(doc, pngs, views).encode("utf-8"),
    }
    files.update(pngs)
    return files


def write_folder(out_dir: str | os.PathLike[str], name: str, files: Mapping[str, bytes]) -> Path:
    """Write ``files`` into ``out_dir/name/`` atomically (temporary folder + rename)."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    final = out / name
    stem = name[:64]  # temporary siblings stay within file-name limits whatever the name
    tmp = Path(tempfile.mkdtemp(prefix=f".{stem}.", suffix=".tmp", dir=out))
    try:
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o777 & ~umask)
        for file_name, data in files.items():
            (tmp / file_name).write_bytes(data)
        if final.exists():
            old = Path(tempfile.mkdtemp(prefix=f".{stem}.", suffix=".old", dir=out))
            os.replace(final, old / name)
            os.replace(tmp, final)
            shutil.rmtree(old, ignore_errors=True)
        else:
            os.replace(tmp, final)
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)
    return final


def summary_row(doc: dict[str, Any]) -> dict[str, Any]:
    """One summary row: name, status, (F, P) at each tolerance, fit errors, errors of the
    SHRM against the reference, times (``*_seconds``), and the error of a failed report."""
    row: dict[str, Any] = {"name": doc["name"], "status": doc["status"], "source": doc["source"]}
    if doc["status"] != "ok":
        row["error"] = doc.get("error")
        row["total_seconds"] = doc.get("total_seconds")
        return row
    row["kind"] = doc["brdf"]["kind"]
    for o in doc["orders"]:
        row[f"F@{o['tolerance']:g}"] = o["F"]
        row[f"P@{o['tolerance']:g}"] = o["P"]
    rep = doc["brdf"].get("representation")  # what the orders describe, and its held-out worst band
    band = rep.get("held_out_worst_band") if rep else None
    row["representation"] = rep["label"] if rep else "as given"
    row["representation_worst_band_rel_rms"] = band["rel_rms"] if band else None
    row["representation_worst_band"] = f"{band['lo_deg']:g}-{band['hi_deg']:g}" if band else None
    row["representation_ok"] = rep["success"] if rep else None
    for f in doc["fits"]:
        row[f"fit_rel_rms_{f['model']}"] = None if f.get("error") else f["errors"].get("rel_rms")
        band = None if f.get("error") else f.get("worst_band")
        row[f"fit_worst_band_rel_rms_{f['model']}"] = band["rel_rms"] if band else None
        row[f"fit_worst_band_{f['model']}"] = f"{band['lo_deg']:g}-{band['hi_deg']:g}" if band else None
        row[f"fit_ok_{f['model']}"] = bool(f.get("success")) and not f.get("error")
    for e in doc["environments"]:
        row[f"shrm_rel_rms_{e['name']}"] = e["measured_rel_rms"]
    row["warnings"] = len(doc["warnings"])
    for f in doc["fits"]:
        row[f"fit_{f['model']}_seconds"] = f.get("fit_seconds")
    main = [r for r in doc["speed_vs_error"] if r["tolerance"] == doc["main"]["tolerance"]]
    if main:
        row["prefilter_seconds"] = main[0]["prefilter_seconds"]
    row["total_seconds"] = doc.get("total_seconds")
    row["error"] = None
    return row


def summary_columns(rows: Sequence[Mapping[str, Any]]) -> list[str]:
    """Union of the rows' keys, in first-seen order, with ``error`` last."""
    columns: list[str] = []
    for row in rows:
        for key in row:
            if key not in columns:
                columns.append(key)
    if "error" in columns:
        columns.remove("error")
        columns.append("error")
    return columns


#: A spreadsheet reads a cell that starts with one of these as a formula (OWASP "CSV injection").
_FORMULA_START = ("=", "+", "-", "@", "\t", "\r")


def csv_cell(value: Any) -> Any:
    """A summary value as written to ``summary.csv``: None as empty; a text that a spreadsheet
    would run as a formula (a report named after a file ``=HYPERLINK(…).binary``) prefixed with
    ``'``; numbers, and texts that are numbers (``-0.5``), as they are."""
    if value is None:
        return ""
    if isinstance(value, str) and value.startswith(_FORMULA_START):
        try:
            float(value)
        except ValueError:
            return "'" + value
    return value


def write_summary(out_dir: str | os.PathLike[str], rows: Sequence[Mapping[str, Any]],
                  notes: Sequence[str] = ()) -> tuple[Path, Path]:
    """Write ``summary.csv`` and the sortable ``index.html`` (without the long ``source``
    column) into ``out_dir``, atomically."""
    out = Path(out_dir)
    columns = summary_columns(rows)
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=columns, lineterminator="\n")
    writer.writeheader()
    for row in rows:
        writer.writerow({c: csv_cell(row.get(c)) for c in columns})
    csv_path, html_path = out / "summary.csv", out / "index.html"
    with atomic_path(csv_path) as tmp:
        tmp.write_text(buf.getvalue(), encoding="utf-8")
    thumbnails = {}
    for row in rows:  # the report's preview, else its lit sphere: a picture per material
        for image in ("preview_sphere.png", "explorer_sphere.png"):
            if (out / str(row["name"]) / image).is_file():
                thumbnails[str(row["name"])] = f"{row['name']}/{image}"
                break
    with atomic_path(html_path) as tmp:
        tmp.write_text(index_html([c for c in columns if c != "source"], rows, notes=notes, thumbnails=thumbnails),
                       encoding="utf-8")
    return csv_path, html_path
