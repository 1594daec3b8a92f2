"""Self-contained HTML: ``report.html`` (PNG plots embedded as base64 data URIs) and the
batch ``index.html`` (a table sortable by clicking its headers, a few lines of inline JS).

The report body is the Markdown of ``markdown.report_sections`` turned into HTML by a
small converter for exactly the subset it writes (tables, bullet lists, bold, code,
fenced code, images), so no Markdown package is needed. A line ``<!-- live-view ID -->``
(invisible in report.md) is replaced by the live WebGL2 preview of that id
(``explorer.LiveView``, ``render.webgl_page.view_fragment``); the viewer script, its shaders
and its style are kept once per page.
"""

from __future__ import annotations

import base64
import html
import re
from collections.abc import Mapping, Sequence
from typing import Any

from ...render.webgl_page import webgl_sources
from .markdown import LIVE_VIEW_MARK, fmt, report_sections

__all__ = ["markdown_to_html", "report_html", "index_html", "data_uri"]

#: The pages' style. Nothing may be wider than the window (1280 px and narrower): the page never
#: scrolls sideways. A table scrolls inside its own box (``.wide`` in the report, ``.scroll`` on the
#: index), code in a table cell and long words in text break where they must, images and the live
#: view shrink to the column (``tests/cli/report/test_html_layout.py`` checks these rules).
_STYLE = """
body{font-family:system-ui,-apple-system,Segoe UI,Helvetica,Arial,sans-serif;margin:1.5em auto;
max-width:1100px;color:#222;padding:0 1em;overflow-wrap:break-word}
h1{font-size:1.6em;border-bottom:2px solid #444}h2{font-size:1.2em;margin-top:1.6em;border-bottom:1px solid #ccc}
table{border-collapse:collapse;margin:.6em 0;font-size:.88em}th,td{border:1px solid #ccc;padding:.25em .55em;
text-align:right}th{background:#f0f0f0}td:first-child,th:first-child{text-align:left}
img{max-width:100%;border:1px solid #ddd;margin:.3em 0}code{background:#f4f4f4;padding:0 .2em}
pre{background:#f4f4f4;padding:.6em;overflow:auto}.failed{color:#b00;font-weight:bold}.ok{color:#070}
th.sortable{cursor:pointer}th.sortable:after{content:" \\2195";color:#999}
.live-view{margin:.6em 0}.live-view .shrm-view{max-width:480px}.live-view .shrm-view img{border:0;margin:0}
body.index{max-width:none}.wide{overflow-x:auto;max-width:100%}td code{overflow-wrap:anywhere}figure{margin:.6em 0}
.scroll{overflow-x:auto;max-width:100%}.scroll th{white-space:normal;min-width:4.5em;vertical-align:bottom}
.scroll td:first-child,.scroll th:first-child{position:sticky;left:0;background:#fff;z-index:1}
.scroll th:first-child{background:#f0f0f0}img.thumb{width:48px;height:48px;border:0;margin:0;vertical-align:middle}
"""

_SORT_JS = """
document.querySelectorAll('table.sortable').forEach(function(t){
 t.querySelectorAll('th').forEach(function(th,i){th.classList.add('sortable');th.onclick=function(){
  var b=t.tBodies[0],rows=Array.from(b.rows),asc=th.dataset.asc!=='1';th.dataset.asc=asc?'1':'0';
  rows.sort(function(x,y){var a=x.cells[i].dataset.v||x.cells[i].textContent,
   c=y.cells[i].dataset.v||y.cells[i].textContent;
   var na=parseFloat(a),nc=parseFloat(c);if(!isNaN(na)&&!isNaN(nc))return asc?na-nc:nc-na;
   return asc?a.localeCompare(c):c.localeCompare(a);});rows.forEach(function(r){b.appendChild(r);});};});});
"""


# view.js draws its first frame inside mount(), while the canvas is still hidden (data-state
# "loading"): a 1 x 1 frame. A resize event makes every viewer draw again at its laid-out size.
_REDRAW_JS = "<script>window.dispatchEvent(new Event('resize'));</script>"


def data_uri(png: bytes) -> str:
    """``data:image/png;base64,...`` for embedding a PNG."""
    return "data:image/png;base64," + base64.b64encode(png).decode("ascii")


def _inline(text: str) -> str:
    out = html.escape(text, quote=False)
    out = re.sub(r"`([^`]+)`", r"<code>\1</code>", out)
    out = re.sub(r"\*\*([^*]+)\*\*", r"<strong>\1</strong>", out)
    return out


def _cells(line: str) -> list[str]:
    parts = re.split(r"(?<!\\)\|", line.strip())[1:-1]
    return [p.strip().replace("\\|", "|") for p in parts]


def markdown_to_html(text: str, images: Mapping[str, str] | None = None, raw: Mapping[str, str] | None = None) -> str:
    """HTML of the Markdown subset written by ``markdown.py``.

    ``images`` maps an image file name to the ``src`` to use (e.g. a data URI); images
    not in it are left out. ``raw`` maps a live-view id to the HTML that replaces its
    ``<!-- live-view ID -->`` line (left out when absent).
    """
    images = images or {}
    raw = raw or {}
    lines = text.split("\n")
    out: list[str] = []
    i = 0
    while i < len(lines):
        line = lines[i]
        if m := LIVE_VIEW_MARK.fullmatch(line.strip()):
            if m.group(1) in raw:
                out.append(f'<div class="live-view">{raw[m.group(1)]}</div>')
            i += 1
        elif line.startswith("```"):
            j = i + 1
            while j < len(lines) and not lines[j].startswith("```"):
                j += 1
            out.append("<pre>" + html.escape("\n".join(lines[i + 1 : j])) + "</pre>")
            i = j + 1
        elif line.startswith("| "):
            header = _cells(line)
            rows = []
            i += 2
            while i < len(lines) and lines[i].startswith("| "):
                rows.append(_cells(lines[i]))
                i += 1
            # in a box of its own that scrolls sideways when the table is wider than the page
            out.append('<div class="wide"><table><thead><tr>' + "".join(f"<th>{_inline(h)}</th>" for h in header)
                       + "</tr></thead><tbody>"
                       + "".join("<tr>" + "".join(f"<td>{_inline(c)}</td>" for c in r) + "</tr>" for r in rows)
                       + "</tbody></table></div>")
        elif line.startswith("- "):
            items = []
            while i < len(lines) and lines[i].startswith("- "):
                items.append(f"<li>{_inline(lines[i][2:])}</li>")
                i += 1
            out.append("<ul>" + "".join(items) + "</ul>")
        elif m := re.fullmatch(r"!\[([^\]]*)\]\(([^)]+)\)", line.strip()):
            alt, file = m.group(1), m.group(2)
            src = images.get(file)
            if src is not None:
                out.append(f'<figure><img alt="{html.escape(alt)}" src="{src}"><figcaption>{html.escape(alt)}'
                           "</figcaption></figure>")
            i += 1
        elif line.strip():
            para = []
            while i < len(lines) and lines[i].strip() and not lines[i].startswith(("| ", "- ", "```", "![")):
                para.append(lines[i])
                i += 1
            out.append("<p>" + _inline(" ".join(para)) + "</p>")
        else:
            i += 1
    return "\n".join(out)


def _page(title: str, body: str, script: str = "", body_class: str = "") -> str:
    opening = f'<body class="{body_class}">' if body_class else "<body>"
    return (f"<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{html.escape(title)}</title>"
            f"<style>{_STYLE}</style></head>{opening}\n{body}\n"
            + (f"<script>{script}</script>" if script else "") + "</body></html>\n")


def _viewer_once(fragments: Sequence[str]) -> list[str]:
    """The fragments with the viewer's style, script and shaders left only in the first
    (``view.js`` defines ``window.ShrmView`` once and every fragment mounts with it)."""
    sources = webgl_sources()
    shared = [f"<style>{sources['view.css']}</style>\n", f"<script>{sources['view.js']}</script>\n"]
    shaders = re.compile(r"<script>window\.ShrmViewShaders = window\.ShrmViewShaders \|\| .*?;</script>\n", re.S)
    out = []
    for k, text in enumerate(fragments):
        if k:
            for part in shared:
                text = text.replace(part, "", 1)
            text = shaders.sub("", text, count=1)
        out.append(text)
    return out


def report_html(doc: dict[str, Any], pngs: Mapping[str, bytes], views: Sequence[Any] = ()) -> str:
    """The self-contained ``report.html``: ``pngs`` maps file names (``plot_energy.png``,
    ``preview_sphere.png``, ...) to PNG bytes, embedded as data URIs; ``views`` are the live
    previews (``explorer.LiveView``: ``element_id``, ``html``), placed where the Markdown marks
    them."""
    images = {name: data_uri(data) for name, data in pngs.items()}
    raw = dict(zip([v.element_id for v in views], _viewer_once([v.html for v in views]), strict=True))
    parts = [f"<h1>BRDF report: {html.escape(doc['name'])}</h1>"]
    for title, body in report_sections(doc):
        parts.append(f"<h2>{html.escape(title)}</h2>")
        parts.append(markdown_to_html(body, images, raw))
    if views:
        parts.append(_REDRAW_JS)
    return _page(f"shrm report: {doc['name']}", "\n".join(parts))


_LABELS = (  # summary.csv column → header people read (the key stays the header's tooltip)
    (r"^F@(.+)$", r"F at ε \1"), (r"^P@(.+)$", r"P at ε \1"),
    (r"^representation_worst_band_rel_rms$", "analysed as: held-out worst band rel. RMS"),
    (r"^representation_worst_band$", "analysed as: worst band (°)"), (r"^representation_ok$", "analysed as: ok"),
    (r"^representation$", "analysed as"),
    (r"^fit_rel_rms_(.+)$", r"\1 fit: rel. RMS, all"),
    (r"^fit_worst_band_rel_rms_(.+)$", r"\1 fit: worst band rel. RMS"),
    (r"^fit_worst_band_(.+)$", r"\1 fit: worst band (°)"), (r"^fit_ok_(.+)$", r"\1 fit ok"),
    (r"^shrm_rel_rms_(.+)$", r"SHRM error under \1 (measured rel. RMS)"),
    (r"^fit_(.+)_seconds$", r"\1 fit (s)"), (r"^prefilter_seconds$", "prefilter (s)"),
    (r"^total_seconds$", "total (s)"),
)


def column_label(key: str) -> str:
    """The index page's header of a ``summary.csv`` column (``F@0.03`` → ``F at ε 0.03``)."""
    for pattern, label in _LABELS:
        if re.match(pattern, key):
            return re.sub(pattern, label, key)
    return key


def index_columns(columns: Sequence[str]) -> list[str]:
    """The index page's column order: name, status and kind, the orders (``F@``/``P@``), the SHRM's
    measured error under each environment and the prefilter time, then the rest as in ``summary.csv``."""
    lead = [c for c in columns if c in ("name", "status", "kind") or c.startswith(("F@", "P@"))]
    answer = [c for c in columns if c.startswith("shrm_rel_rms_") or c == "prefilter_seconds"]
    return lead + answer + [c for c in columns if c not in lead and c not in answer]


def index_html(columns: Sequence[str], rows: Sequence[Mapping[str, Any]], title: str = "shrm report summary",
               notes: Sequence[str] = (), thumbnails: Mapping[str, str] | None = None) -> str:
    """The batch summary page: one row per BRDF, linked to its report, sortable columns with
    readable headers (:func:`column_label`; the ``summary.csv`` key as each header's tooltip), the
    table scrolling sideways under a fixed name column, and a thumbnail per material where
    ``thumbnails`` maps its name to an image path relative to the page (the report's preview).
    The answer comes first (:func:`index_columns`): at 1280 px the first screen held only the
    orders and the first fit's columns, the SHRM's measured error and times 15 columns further.
    The page takes the window's whole width (the report pages keep a 1100 px column of text)."""
    thumbnails = thumbnails or {}
    columns = index_columns(columns)
    head = "".join(f'<th title="{html.escape(c)}">{html.escape(column_label(c))}</th>' for c in columns)
    body_rows = []
    for row in rows:
        cells = []
        for c in columns:
            value = row.get(c)
            sort_key = "" if value is None else str(value)
            if c == "name":
                thumb = thumbnails.get(str(row["name"]))
                img = f'<img class="thumb" alt="" src="{html.escape(thumb)}"> ' if thumb else ""
                text = f'{img}<a href="{html.escape(str(row["name"]))}/report.html">{html.escape(str(value))}</a>'
            elif c == "status":
                text = f'<span class="{"ok" if value == "ok" else "failed"}">{html.escape(str(value))}</span>'
            else:
                text = html.escape(fmt(value))
            cells.append(f'<td data-v="{html.escape(sort_key)}">{text}</td>')
        body_rows.append("<tr>" + "".join(cells) + "</tr>")
    table = (f'<div class="scroll"><table class="sortable"><thead><tr>{head}</tr></thead>'
             f'<tbody>{"".join(body_rows)}</tbody></table></div>')
    note_html = "".join(f"<p>{html.escape(n)}</p>" for n in notes)
    return _page(title, f"<h1>{html.escape(title)}</h1>{note_html}{table}<p>Click a column header to sort.</p>",
                 _SORT_JS, body_class="index")
