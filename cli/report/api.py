"""The report from Python: :func:`report` (``shrmkit.report``) and the :class:`Report` it returns.

``shrmkit.report(brdf, out=..., profile="quick", **options)`` is one BRDF of ``shrm report``:
the options of :func:`~shrmkit.cli.report.options.profile` (``eps``, ``envs``, ``models``,
``n_pairs`` …, as :class:`~shrmkit.cli.report.options.ReportOptions` names them), the document of
:func:`~shrmkit.cli.report.collect.collect_report` (``report.json``, data_specs/report_json.md),
and with ``out=`` the report folder ``out/<name>/`` written as ``shrm report`` writes it
(:func:`~shrmkit.cli.report.writer.report_files`, :func:`~shrmkit.cli.report.writer.write_folder`),
named as ``shrm report`` names it (:func:`~shrmkit.cli.report.batch.report_names`: the file stem or
the sanitized spec, ``phong:s=100`` → ``phong_s_100``; no ``:`` reaches a path).
The object shows itself in a notebook (``_repr_html_``): the preview, the key numbers, and the
first lines of ``report.md``.

Public objects: :func:`report`, :class:`Report`, :func:`folder_name`.
"""

from __future__ import annotations

import html
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ...brdf_io.brdf import BRDF
from ...brdf_io.errors import BadInputError
from ...brdf_io.notebook import card, html_table, png_img
from .batch import report_names
from .collect import collect_report
from .markdown import report_markdown
from .options import profile as report_profile
from .writer import report_files, summary_row, write_folder

__all__ = ["report", "Report", "folder_name", "SUMMARY_LINES"]

#: Lines of ``report.md`` the notebook card shows.
SUMMARY_LINES = 12


@dataclass(frozen=True, eq=False)
class Report:
    """One BRDF's report.

    Attributes
    ----------
    doc
        The ``report.json`` document (JSON types; data_specs/report_json.md).
    previews
        What the report shows beside the document: preview images, lit spheres, live views
        (as :func:`~shrmkit.cli.report.writer.report_files` takes them).
    folder
        The report folder written (``out/<name>/``, ``name`` as :func:`folder_name` makes it), or None.
    """

    doc: dict[str, Any]
    previews: tuple[Any, ...] = ()
    folder: Path | None = None

    @property
    def name(self) -> str:
        """The report's name: its folder's (:func:`folder_name` of the BRDF's file or spec, or of the one given)."""
        return str(self.doc["name"])

    @property
    def markdown(self) -> str:
        """``report.md``: the report as Markdown."""
        return report_markdown(self.doc)

    def files(self) -> dict[str, bytes]:
        """Every file of the report folder, ``{file name: bytes}`` (``report.json``, ``report.md``,
        ``report.html``, the plots and previews)."""
        return report_files(self.doc, self.previews)

    def summary(self) -> dict[str, Any]:
        """The report's row of ``summary.csv`` (``writer.summary_row``)."""
        return summary_row(self.doc)

    def write(self, out: str | Path) -> Path:
        """Write the report folder ``out/<name>/`` atomically (``name`` as :func:`folder_name` makes
        it: no ``:`` or ``/`` of a spec reaches the path); returns its path."""
        return write_folder(out, folder_name(self.name), self.files())

    def _preview_png(self) -> bytes | None:
        for p in self.previews:
            if getattr(p, "key", None) == "sphere" and isinstance(getattr(p, "png", None), bytes):
                return p.png
        return None

    def key_rows(self) -> list[tuple[str, Any]]:
        """The numbers of the report's first screen: orders per tolerance, per environment at the main
        tolerance the scene orders, the worst band's stated error (and bound) beside the measured one
        and the prefilter's time; the fits' worst-band errors; warnings; the total time."""
        doc = self.doc
        if doc["status"] != "ok":
            return [("status", doc["status"]), ("error", doc.get("error"))]
        rows: list[tuple[str, Any]] = [("BRDF", f"{doc['brdf']['name']} ({doc['brdf']['kind']})")]
        rows.append(("orders (ε: F, P)", "; ".join(f"{o['tolerance']:g}: {o['F']}, {o['P']}" for o in doc["orders"])))
        main = doc["main"]["tolerance"]
        for row in doc["speed_vs_error"]:
            if row["tolerance"] != main:
                continue
            rows.append((f"{row['env']} at ε {main:g}",
                         f"F_B={row['F_B']} P_B={row['P_B']}; worst band stated {row['predicted_rel_rms']:.3g} "
                         f"(bound {row['bound_rel_rms']:.3g}), worst band measured "
                         f"{row.get('measured_worst_band_rel_rms', row['measured_rel_rms']):.3g} (rel. RMS); "
                         f"prefilter {row['prefilter_seconds']:.3g} s"))
        for fit in doc["fits"]:
            band = fit.get("worst_band")
            text = fit["error"] if fit.get("error") else (
                f"{'ok' if fit.get('success') else 'FAILED'}, rel. RMS {fit['errors']['rel_rms']:.3g}"
                + (f", worst band {band['lo_deg']:g}–{band['hi_deg']:g}° {band['rel_rms']:.3g}" if band else ""))
            rows.append((f"fit {fit['model']}", text))
        rows.append(("warnings", len(doc["warnings"])))
        rows.append(("total", f"{doc['total_seconds']:.3g} s"))
        if self.folder is not None:
            rows.append(("written to", str(self.folder)))
        return rows

    def _repr_html_(self) -> str:
        """Notebook card: the preview, :meth:`key_rows`, the per-band table of the first environment
        at the main tolerance, and the first lines of ``report.md``."""
        png = self._preview_png()
        image = png_img(png, "preview") if png else ""
        extra = ""
        if self.doc["status"] == "ok" and self.doc["environments"]:
            env = self.doc["environments"][0]
            extra += html_table(
                ["θ_v", "stated rel. RMS", "bound", "measured", "± s.e."],
                [[f"{b['theta_v_deg'][0]:g}–{b['theta_v_deg'][1]:g}°", b["predicted_rel_rms"], b["bound_rel_rms"],
                  b.get("measured_rel_rms"), b.get("measured_stderr")] for b in env["view_bands"] if b["inside"]],
                caption=f"{env['name']}: error by view band at ε {env['tolerance']:g}")
        head = "\n".join(self.markdown.splitlines()[:SUMMARY_LINES])
        extra += f"<pre style='font-size:80%;white-space:pre-wrap'>{html.escape(head)}\n…</pre>"
        return card(f"Report {self.name}", self.key_rows(), image=image, extra=extra)

    def __repr__(self) -> str:
        where = "" if self.folder is None else f", written to {self.folder}"
        return f"<Report {self.name!r} ({self.doc['status']}{where})>"


def folder_name(name: str | Path) -> str:
    """The report folder's name for a BRDF source or report name, as ``shrm report`` names its
    folders (:func:`~shrmkit.cli.report.batch.report_names`, the one home of that rule): a file's
    stem, or the spec with every run of characters other than letters, digits and ``._-`` made
    ``_`` (``"microfacet:sigma=0.2"`` → ``"microfacet_sigma_0.2"``), cut to 100 characters with a hash."""
    return report_names([str(name)])[0]


def _source(brdf: BRDF | str | Path) -> str | Path:
    """What ``collect_report`` loads: a spec or path as given; a loaded BRDF by the file it came from
    (``source``) or its name when that is a spec."""
    if not isinstance(brdf, BRDF):
        return brdf
    source = getattr(brdf, "source", None) or brdf.name
    if brdf.kind == "analytic" or getattr(brdf, "source", None):
        return source
    raise BadInputError(brdf.name, "a report reloads its BRDF: pass the spec or the file it came from")


def report(
    brdf: BRDF | str | Path,
    *,
    out: str | Path | None = None,
    profile: str = "full",
    name: str | None = None,
    progress: Callable[[str], None] | None = None,
    **options: Any,
) -> Report:
    """The accuracy report of one BRDF, as ``shrm report`` makes it (``shrmkit.report``).

    Parameters
    ----------
    brdf
        A spec, a file (``shrmkit.load_brdf``), or a loaded BRDF that remembers its spec or file.
    out
        Write the report folder ``out/<name>/`` (``report.json``, ``report.md``, ``report.html``,
        plots, previews); None (default) writes nothing.
    profile
        ``"full"`` (the defaults of ``shrm report``) or ``"quick"`` (``shrm report --quick``).
    name
        The report's name (default: the BRDF's file stem or spec); as the report folder's name and
        ``report.json``'s ``name``, made safe for a path as ``shrm report`` does (:func:`folder_name`).
    progress
        Optional callable told each stage (``"load"``, ``"fits"``, ``"orders"`` …).
    **options
        Fields of :class:`~shrmkit.cli.report.options.ReportOptions` (``eps``, ``tolerances``,
        ``envs``, ``models``, ``n_pairs``, ``preview`` …), checked there.

    Returns
    -------
    Report
        The document, the previews and the folder written (if any).

    Raises
    ------
    BadInputError
        An unknown profile or option value, an unreadable BRDF, a BRDF object without a source.

    Examples
    --------
    >>> r = shrmkit.report("phong:s=30", profile="quick", models=(), preview="none")  # doctest: +SKIP
    >>> r.doc["main"]["F"], r.summary()["F@0.03"]                                      # doctest: +SKIP
    """
    try:
        chosen = report_profile(profile, **options)
    except TypeError as err:  # an unknown keyword: name it in the terms of this call
        raise BadInputError(None, f"shrmkit.report: {err}") from None
    source = _source(brdf)
    doc, previews = collect_report(source, chosen, name=folder_name(source if name is None else name),
                                   progress=progress)
    result = Report(doc, tuple(previews))
    if out is None:
        return result
    return Report(doc, tuple(previews), result.write(out))
