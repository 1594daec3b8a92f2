"""Report rendering: Markdown subset -> HTML, the sortable index page, summary CSV columns."""

from __future__ import annotations

import base64

from shrmkit.cli.report.html import data_uri, index_html, markdown_to_html
from shrmkit.cli.report.markdown import fmt, md_table
from shrmkit.cli.report.writer import summary_columns


def test_markdown_table_round_trips_to_html():
    md = md_table(["a", "b|c"], [[1, 0.123456], [None, True]])
    assert md.splitlines()[0] == "| a | b\\|c |"
    html = markdown_to_html(md)
    assert "<th>a</th><th>b|c</th>" in html
    assert "<td>1</td><td>0.123</td>" in html and "<td>—</td><td>yes</td>" in html


def test_markdown_images_are_embedded_and_text_escaped():
    png = b"\x89PNG\r\n\x1a\nrest"
    html = markdown_to_html("Some **bold** `code` <tag>\n\n![plot](plot.png)\n\n- item", {"plot.png": data_uri(png)})
    assert "<strong>bold</strong>" in html and "<code>code</code>" in html and "&lt;tag&gt;" in html
    src = html.split('src="')[1].split('"')[0]
    assert base64.b64decode(src.split(",", 1)[1]) == png
    assert "<ul><li>item</li></ul>" in html


def test_index_is_sortable_and_links_reports():
    page = index_html(["name", "status", "F@0.1"], [{"name": "a", "status": "ok", "F@0.1": 3},
                                                    {"name": "b", "status": "failed", "F@0.1": None}])
    assert 'href="a/report.html"' in page and 'class="failed"' in page
    assert 'data-v="3"' in page and "sortable" in page and "<script>" in page


def test_summary_columns_union_with_error_last():
    cols = summary_columns([{"name": "a", "error": None, "x": 1}, {"name": "b", "y": 2}])
    assert cols == ["name", "x", "y", "error"]
    assert fmt(1234.5678) == "1.23e+03" and fmt([3, 4]) == "3×4"


def test_index_headers_are_readable_with_the_csv_key_as_tooltip_and_thumbnails():
    from shrmkit.cli.report.html import column_label

    assert column_label("F@0.03") == "F at ε 0.03" and column_label("P@0.1") == "P at ε 0.1"
    assert column_label("fit_worst_band_rel_rms_lafortune") == "lafortune fit: worst band rel. RMS"
    assert column_label("fit_worst_band_lafortune") == "lafortune fit: worst band (°)"
    assert column_label("shrm_rel_rms_sky") == "SHRM error under sky (measured rel. RMS)"
    assert column_label("fit_cook-torrance_seconds") == "cook-torrance fit (s)" and column_label("name") == "name"
    page = index_html(["name", "F@0.03"], [{"name": "a", "F@0.03": 7}], thumbnails={"a": "a/preview_sphere.png"})
    assert '<th title="F@0.03">F at ε 0.03</th>' in page
    assert '<img class="thumb" alt="" src="a/preview_sphere.png">' in page and 'class="scroll"' in page
