"""The report pages fit the window (issue 26: every column visible at 1280 px, or a table that
scrolls inside its own box): nothing in ``report.html`` or ``index.html`` may widen the page.

Checked on the page's own CSS and markup (no browser): every table sits in a box whose rule
scrolls sideways, code in table cells and long words may break, pre blocks scroll, images shrink
to the column. ``benchmarks/report_layout.py`` measures the real pages in headless chromium
(``document.documentElement.scrollWidth`` at 1280 × 800).
"""

from __future__ import annotations

import re
from html.parser import HTMLParser

from shrmkit.cli.report import html as report_html
from shrmkit.cli.report.html import index_html, markdown_to_html
from shrmkit.cli.report.markdown import md_table


def _rules(css: str) -> dict[str, dict[str, str]]:
    """{selector: {property: value}} of a flat style sheet (no @-rules), later rules winning."""
    out: dict[str, dict[str, str]] = {}
    for selectors, body in re.findall(r"([^{}]+)\{([^{}]*)\}", css):
        props = dict((k.strip(), v.strip()) for k, v in
                     (d.split(":", 1) for d in body.split(";") if ":" in d))
        for sel in selectors.split(","):
            out.setdefault(" ".join(sel.split()), {}).update(props)
    return out


RULES = _rules(report_html._STYLE)


def _scrolls(cls: str) -> bool:
    props = RULES.get("." + cls, {})
    return props.get("overflow-x", props.get("overflow")) in ("auto", "scroll")


class _Tables(HTMLParser):
    """For each <table>: the classes of its ancestors."""

    def __init__(self) -> None:
        super().__init__()
        self.stack: list[tuple[str, set[str]]] = []
        self.tables: list[set[str]] = []

    def handle_starttag(self, tag, attrs):
        classes = set((dict(attrs).get("class") or "").split())
        if tag == "table":
            self.tables.append(set().union(*(c for _, c in self.stack)) if self.stack else set())
        if tag not in ("img", "br", "meta"):
            self.stack.append((tag, classes))

    def handle_endtag(self, tag):
        while self.stack:
            if self.stack.pop()[0] == tag:
                break


def _table_boxes(page: str) -> list[set[str]]:
    parser = _Tables()
    parser.feed(page)
    return parser.tables


def test_report_tables_scroll_inside_their_own_box_and_long_code_breaks():
    spec = "lafortune:kd=0," + ",".join(f"cxy{k}=-1,cz{k}=0.997450856,n{k}=74.0100406" for k in range(2, 9))
    md = md_table(["model", "fitted spec"] + [f"column {k}" for k in range(20)],
                  [["lafortune", f"`{spec}`"] + [0.123456] * 20])
    page = markdown_to_html(md + "\n\n```\n" + "x" * 400 + "\n```\n")
    boxes = _table_boxes(page)
    assert len(boxes) == 1
    assert any(_scrolls(c) for c in boxes[0]), f"a report table outside a scrolling box: ancestors {boxes[0]}"
    assert RULES["td code"]["overflow-wrap"] == "anywhere"  # a long spec string breaks, not the page
    assert RULES["pre"]["overflow"] == "auto" and RULES["img"]["max-width"] == "100%"
    assert RULES["body"]["overflow-wrap"] in ("break-word", "anywhere")


def test_index_table_scrolls_under_the_full_window_width():
    columns = ["name", "status"] + [f"F@{k}" for k in range(30)]
    page = index_html(columns, [{"name": "a", "status": "ok", **{f"F@{k}": k for k in range(30)}}])
    boxes = _table_boxes(page)
    assert len(boxes) == 1 and any(_scrolls(c) for c in boxes[0])
    assert '<body class="index">' in page and RULES["body.index"]["max-width"] == "none"
    # the report pages keep their column of text
    assert RULES["body"]["max-width"] == "1100px"
