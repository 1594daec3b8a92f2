"""index.html puts the answer on its first screen (issue 26): after the orders, the SHRM's measured
error and the prefilter time, before the fits' columns (at 1280 px the first screen showed 12 of 29
columns, the measured error 15 columns further); summary.csv keeps its own order."""

from __future__ import annotations

import re

from shrmkit.cli.report.html import index_html

COLUMNS = ["name", "status", "kind", "F@0.1", "P@0.1", "F@0.03", "P@0.03", "representation",
           "fit_rel_rms_lafortune", "fit_worst_band_rel_rms_lafortune", "shrm_rel_rms_sky", "warnings",
           "fit_lafortune_seconds", "prefilter_seconds", "total_seconds", "error"]


def test_index_puts_the_measured_error_and_prefilter_time_after_the_orders():
    page = index_html(COLUMNS, [{c: 1 for c in COLUMNS} | {"name": "a", "status": "ok"}])
    keys = re.findall(r'<th title="([^"]+)">', page)
    assert sorted(keys) == sorted(COLUMNS)
    assert keys[:9] == ["name", "status", "kind", "F@0.1", "P@0.1", "F@0.03", "P@0.03", "shrm_rel_rms_sky",
                        "prefilter_seconds"]
    assert keys[9:] == ["representation", "fit_rel_rms_lafortune", "fit_worst_band_rel_rms_lafortune", "warnings",
                        "fit_lafortune_seconds", "total_seconds", "error"]
    # the cells follow their headers
    cells = re.findall(r'<td data-v="([^"]*)">', page)
    assert len(cells) == len(COLUMNS) and cells[0] == "a" and cells[1] == "ok"
