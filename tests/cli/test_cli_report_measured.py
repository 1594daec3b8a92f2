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
    # CURET #7 (velvet): neither one-lobe model represents it (worst view band > 0.5 for both, issue 24):
    # both fits are marked failed, and the analysis goes through the Zernike expansion
    sources = [f"{brdf / 'curet' / 'abrdf.dat'}#7", str(brdf / "rgl" / "paper_white_rgb.bsdf"),
               f"{brdf / 'nist_ptfe' / 'PTFE.data.csv'}#532"]
    # one tolerance and 30 pairs: the checks are that every kind of measured file makes a report
    assert main(["report", *sources, "--quick", "--no-progress", "--preview", "none", "--no-plots",
                 "--tolerances", "0.1", "--eps", "0.1", "--pairs", "30", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "3 of 3 reports made" in out
    for name in ("abrdf-7", "paper_white_rgb", "PTFE.data-532"):
        doc = json.loads((tmp_path / name / "report.json").read_text())
        assert doc["status"] == "ok"
        assert (tmp_path / name / "report.html").stat().st_size > 10_000
    velvet = json.loads((tmp_path / "abrdf-7" / "report.json").read_text())
    for fit in velvet["fits"]:
        band = fit["worst_band"]
        assert band["rel_rms"] == max(b["rel_rms"] for b in fit["bands"] if b["n"] >= 10)
        assert fit["success"] == (band["rel_rms"] <= 0.5)
    assert not any(f["success"] for f in velvet["fits"])
    failed = [w["message"] for w in velvet["warnings"] if w["code"] == "fit_failed"]
    assert len(failed) == 2 and all("view band" in m for m in failed)
    # the analysis goes through the representation with the smallest held-out worst band: the
    # cross-validated Zernike expansion, which holds velvet (held-out worst band 0.2)
    note = next(w["message"] for w in velvet["warnings"] if w["code"] == "analysis_on_fit")
    assert "analysed through zernike" in note and "held-out worst view band" in note and "FAILED" not in note
    assert velvet["brdf"]["analysis_of"] == "fit:zernike"
    md = (tmp_path / "abrdf-7" / "report.md").read_text()
    assert "Fits (worst view band first): lafortune **FAILED**" in md
    import csv

    with (tmp_path / "summary.csv").open(newline="") as fh:
        rows = {r["name"]: r for r in csv.DictReader(fh)}
    assert rows["abrdf-7"]["fit_ok_lafortune"] == "False"
    assert float(rows["abrdf-7"]["fit_worst_band_rel_rms_lafortune"]) > 0.5
    # beside the orders: what they describe and its held-out worst band (the representation record's)
    rep = velvet["brdf"]["representation"]
    band = rep["held_out_worst_band"]
    assert rows["abrdf-7"]["representation"] == rep["label"] and rep["label"].startswith("zernike order")
    assert float(rows["abrdf-7"]["representation_worst_band_rel_rms"]) == pytest.approx(band["rel_rms"], rel=1e-9)
    assert rows["abrdf-7"]["representation_ok"] == "True" and band["rel_rms"] < 0.5
    assert f"held-out worst view band rel. RMS **{band['rel_rms']:.3g}** ({band['lo_deg']:g}–{band['hi_deg']:g}°)" in md
    white = rows["paper_white_rgb"]
    assert white["representation"] == "as given" and white["representation_ok"] == ""


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
