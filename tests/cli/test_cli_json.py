"""``--json`` of shrm render, view, report, demo and bench: one JSON object on stdout and nothing
else, whose numbers are the API's own (``shrmkit.prefilter``, ``shrmkit.choose_orders``)."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest

import shrmkit
from shrmkit.cli import cmd_demo
from shrmkit.cli.main import main
from shrmkit.cli.report.demo import DemoStep

ENV, BRDF = "builtin:sky,height=32", "phong:s=8"


def _doc(capsys) -> dict:
    out = capsys.readouterr().out
    assert out.count("\n") == 1  # one JSON line, no text lines
    return json.loads(out)


@pytest.mark.render
def test_render_json(offscreen, tmp_path: Path, capsys) -> None:
    png = tmp_path / "s.png"
    assert main(["render", "builtin:sphere:subdivisions=3", "--env", ENV, "--brdf", BRDF, "--size", "24",
                 "--fps-frames", "0", "-o", str(png), "--json"]) == 0
    doc = _doc(capsys)
    shrm = shrmkit.prefilter(ENV, BRDF, eps=0.03)
    model = doc["model"]
    assert (model["F"], model["P"], model["height"]) == (shrm.F, shrm.P, shrm.height)
    worst = max(b["predicted_rel_rms"] for b in shrm.meta["view_bands"] if b["inside"])
    assert model["stated_error"]["predicted_rel_rms"] == pytest.approx(worst)
    assert doc["outputs"] == [str(png)] and png.is_file()
    assert doc["timings"]["first_frame_s"] > 0 and doc["environment"] == "sky"


def test_view_json(tmp_path: Path, capsys) -> None:
    page = tmp_path / "v.html"
    assert main(["view", BRDF, "--env", ENV, "--still", "none", "-o", str(page), "--json"]) == 0
    doc = _doc(capsys)
    shrm = shrmkit.prefilter(ENV, BRDF, eps=0.03)
    (one,) = doc["environments"]
    assert (one["F"], one["P"], one["height"]) == (shrm.F, shrm.P, shrm.height)
    assert doc["output"] == str(page) and doc["page"]["bytes"] == len(page.read_bytes())


def test_report_json(tmp_path: Path, capsys) -> None:
    out = tmp_path / "r"
    assert main(["report", "phong:s=16", "--out", str(out), "--quick", "--preview", "none", "--models", "lafortune",
                 "--tolerances", "0.1", "--eps", "0.1", "--pairs", "20", "--fit-samples", "256", "--no-plots",
                 "--json"]) == 0
    doc = _doc(capsys)
    (row,) = doc["rows"]
    assert row["F@0.1"] == shrmkit.choose_orders("phong:s=16", eps=0.1, max_F=96).F
    with open(doc["summary_csv"], newline="", encoding="utf-8") as f:
        (written,) = list(csv.DictReader(f))
    assert written["name"] == row["name"] and int(written["F@0.1"]) == row["F@0.1"]
    assert doc["n_failed"] == 0 and doc["n_reports"] == 1


def test_demo_json(tmp_path: Path, capsys, monkeypatch) -> None:
    """The JSON of the demo's steps (the steps themselves are tests/cli/test_cli_demo.py's, slow)."""
    steps = [DemoStep("prefilter", (tmp_path / "a.shrm.npz",), "SHRM F=5", 0.5, {"F": 5, "P": 1}),
             DemoStep("reports", (tmp_path / "index.html", tmp_path / "summary.csv"), "1 of 1", 2.0, {"n_failed": 0})]
    monkeypatch.setattr(cmd_demo, "run_demo", lambda *a, **k: steps)
    assert main(["demo", "--out", str(tmp_path), "--json"]) == 0
    doc = _doc(capsys)
    assert [s["step"] for s in doc["steps"]] == ["prefilter", "reports"]
    assert doc["steps"][0]["F"] == 5 and doc["open"] == str(tmp_path / "index.html") and doc["n_failed"] == 0


BENCH = '''from rich.console import Console
from rich.table import Table


def main(argv=None):
    t = Table(title="fits")
    t.add_column("model")
    t.add_column("rel. RMS")
    t.add_row("lafortune", "[green]0.12[/green]")
    Console().print(t)
    print("done")
    return 0
'''


def test_bench_json(tmp_path: Path, capsys) -> None:
    (tmp_path / "fit_speed.py").write_text(BENCH, encoding="utf-8")
    assert main(["bench", "--only", "fit", "--benchmarks", str(tmp_path), "--json"]) == 0
    captured = capsys.readouterr()
    doc = json.loads(captured.out)
    (bench,) = doc["benchmarks"]
    assert bench["status"] == "ok" and bench["tables"] == [
        {"title": "fits", "columns": ["model", "rel. RMS"], "rows": [["lafortune", "0.12"]]}]
    assert bench["text"][-1] == "done" and "done" in captured.err  # the benchmark's own output on stderr
