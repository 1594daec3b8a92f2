"""`shrm report` on the measured datasets of ../shared/data: a CURET sample, an RGL file and
a NIST wavelength in one batch (scattered data through their fit), and the expansion of a
whole CURET file into its 61 members."""

from __future__ import annotations

import json

import pytest

from shrmkit.cli.main import main
from shrmkit.cli.report.batch import report_names
from shrmkit.cli.report.plots import _luma


def test_member_names_keep_the_selector():
    assert report_names(["/d/abrdf.dat#12", "/d/PTFE.data.csv#532", "/d/abrdf.dat#12"]) == [
        "abrdf-12", "PTFE.data-532", "abrdf-12-2"]


def test_luma_of_no_samples_is_empty():
    assert _luma([]).shape == (0,)
    assert _luma([[1.0, 1.0, 1.0]]).tolist() == pytest.approx([1.0])


@pytest.mark.slow
def test_report_on_curet_rgl_and_nist(shared_data, tmp_path, capsys):
    brdf = shared_data / "brdf"
    sources = [f"{brdf / 'curet' / 'abrdf.dat'}#12", str(brdf / "rgl" / "paper_white_rgb.bsdf"),
               f"{brdf / 'nist_ptfe' / 'PTFE.data.csv'}#532"]
    # one tolerance and 30 pairs: the checks are that every kind of measured file makes a report
    assert main(["report", *sources, "--quick", "--no-progress", "--preview", "none", "--tolerances", "0.1",
                 "--eps", "0.1", "--pairs", "30", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "3 of 3 reports made" in out
    for name in ("abrdf-12", "paper_white_rgb", "PTFE.data-532"):
        doc = json.loads((tmp_path / name / "report.json").read_text())
        assert doc["status"] == "ok"
        assert (tmp_path / name / "report.html").stat().st_size > 10_000


def test_whole_curet_file_expands_to_61_reports(shared_data, monkeypatch, tmp_path):
    """The batch receives one source per CURET sample (the run itself is stubbed here)."""
    import shrmkit.cli.cmd_report as cmd_report

    seen = {}

    def fake_run(sources, out, options, **kw):
        seen["sources"] = sources
        raise SystemExit(0)

    monkeypatch.setattr(cmd_report, "run_with_progress", fake_run)
    with pytest.raises(SystemExit):
        main(["report", str(shared_data / "brdf" / "curet" / "abrdf.dat"), "--quick", "--out", str(tmp_path)])
    assert len(seen["sources"]) == 61 and seen["sources"][11].endswith("abrdf.dat#12")
