"""``shrmkit.report``: the Python entry point makes the report ``shrm report`` makes, returns it,
and writes the folder on request; its notebook card shows the key numbers."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

import shrmkit
from shrmkit.brdf_io.errors import BadInputError

QUICK = dict(profile="quick", models=(), preview="none", tolerances=(0.1,), n_pairs=40, plots=False,
             albedo_nodes=16)


def test_report_returns_the_document_and_writes_the_folder(tmp_path: Path) -> None:
    """Reference: the orders of the document are choose_orders' own at the main tolerance."""
    brdf = shrmkit.load_brdf("phong:s=30")  # a loaded model is reloaded from its spec
    r = shrmkit.report(brdf, out=tmp_path, **QUICK)
    # the folder as shrm report names it (issue 26: the API wrote "phong:s=30/"): no colon reaches a path
    from shrmkit.cli.report.batch import report_names

    assert r.doc["status"] == "ok" and r.folder == tmp_path / "phong_s_30" == tmp_path / report_names(["phong:s=30"])[0]
    assert r.name == r.doc["name"] == "phong_s_30" and r.doc["brdf"]["name"] == "phong:s=30"
    assert [p.name for p in tmp_path.iterdir()] == ["phong_s_30"]
    choice = shrmkit.choose_orders("phong:s=30", eps=r.doc["main"]["tolerance"], max_F=96)
    assert (r.doc["main"]["F"], r.doc["main"]["P"]) == (choice.F, choice.P)
    on_disk = json.loads((r.folder / "report.json").read_text(encoding="utf-8"))
    assert on_disk["main"] == r.doc["main"]
    assert {"report.md", "report.html"} <= {p.name for p in r.folder.iterdir()}
    assert r.summary()["F@0.03"] == choice.F
    html = r._repr_html_()
    row = r.doc["speed_vs_error"][-1]
    assert f"measured {row['measured_worst_band_rel_rms']:.3g}" in html and "# BRDF report" in html


def test_folder_names_are_the_cli_s() -> None:
    """One rule: shrmkit.report's folders are shrm report's (report_names), for specs and files."""
    from shrmkit.cli.report.api import folder_name

    assert folder_name("microfacet:sigma=0.2") == "microfacet_sigma_0.2"
    assert folder_name(Path("some/where/gold-metallic-paint.binary")) == "gold-metallic-paint"
    assert folder_name("my report: a/b") == "my_report_a_b"


def test_report_refuses_unknown_options() -> None:
    with pytest.raises(BadInputError, match="no_such_option"):
        shrmkit.report("phong:s=30", no_such_option=1)
