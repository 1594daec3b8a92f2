"""Scattered measurements through the CLI (issue 24): ``shrm fit --model zernike`` and ``shrm orders``
/ ``shrm prefilter`` on CURET, Cornell and gonioreflectometer files, analysed through the
representation with the smallest held-out error (analysis/fit/representation.py)."""

from __future__ import annotations

import json

import pytest

from shrmkit import load_brdf
from shrmkit.cli.main import main


def test_fit_zernike_writes_a_document_that_loads_back(shared_data, tmp_path, capsys) -> None:
    felt = f"{shared_data / 'brdf' / 'curet' / 'abrdf.dat'}#1"
    out = tmp_path / "felt.json"
    assert main(["fit", felt, "--model", "zernike", "--json", "-o", str(out)]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["model"] == "zernike" and doc["fit"]["status"] == "LINEAR_LSQ" and doc["fit"]["success"]
    assert doc["errors"]["rel_rms"] > doc["params"]["training"]["errors"]["rel_rms"]  # held out vs training
    assert load_brdf(out).n_max == doc["params"]["n_max"]
    assert main(["fit", felt, "--model", "zernike:order=2", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["params"]["n_max"] == 2


@pytest.mark.parametrize("bad", ["zernike:order=30", "zernike:foo=1", "lafortune:order=2", "spline"])
def test_fit_bad_model_is_a_usage_error(bad: str, capsys) -> None:
    with pytest.raises(SystemExit) as exc:
        main(["fit", "lambert", "--model", bad])
    assert exc.value.code == 2


@pytest.mark.slow
def test_orders_on_scattered_files(shared_data, capsys) -> None:
    """CURET velvet and felt, NIST PTFE: orders through the chosen representation, its line before
    the tables, ``representation`` in --json (the chosen one has the smallest held-out worst band)."""
    brdf = shared_data / "brdf"
    for source in (f"{brdf / 'curet' / 'abrdf.dat'}#7", str(brdf / "nist_ptfe" / "PTFE.data.csv") + "#532"):
        assert main(["orders", source, "--eps", "0.1", "--json"]) == 0
        doc = json.loads(capsys.readouterr().out)
        rep = doc["representation"]
        assert rep["model"] in ("lafortune", "cook-torrance", "zernike") and doc["F"] >= 0
        # CURET velvet and PTFE: some candidate succeeds, and the chosen one has the smallest held-out worst band
        scores = [c["held_out_worst_band"]["rel_rms"] for c in rep["candidates"] if c["success"]]
        assert rep["success"] and rep["held_out_worst_band"]["rel_rms"] == min(scores)
    assert main(["orders", f"{brdf / 'curet' / 'abrdf.dat'}#1", "--eps", "0.1"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("analysed through") and "held-out worst view band" in out and "anisotropy" in out


@pytest.mark.slow
def test_prefilter_on_a_cornell_file(shared_data, tmp_path, capsys) -> None:
    source = str(shared_data / "brdf" / "cornell" / "acryl_blue.brdf")
    out = tmp_path / "acryl.shrm.npz"
    assert main(["prefilter", "--env", "builtin:sky", "--brdf", source, "--eps", "0.1", "-o", str(out),
                 "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["representation"]["isotropy"] is None  # Cornell: one axis of incidence
    assert "one axis of incidence" in doc["representation"]["isotropy_note"] and out.exists()
