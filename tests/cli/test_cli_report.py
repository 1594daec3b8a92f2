"""`shrm report` and `shrm bench`: exit codes (0 all made, 1 some failed, 2 bad usage), outputs."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest

from shrmkit.cli.main import main

FAST = ["--quick", "--preview", "none", "--models", "lafortune", "--tolerances", "0.1", "--eps", "0.1",
        "--pairs", "30", "--fit-samples", "1024", "--no-progress"]


def test_report_all_ok_exit_0(tmp_path, capsys):
    out = tmp_path / "rep"
    assert main(["report", "phong:s=16", "--out", str(out), *FAST]) == 0
    printed = capsys.readouterr().out
    assert "phong_s_16" in printed and "summary:" in printed
    doc = json.loads((out / "phong_s_16" / "report.json").read_text())
    assert doc["status"] == "ok" and doc["options"]["profile"] == "quick"
    # RH02 Appendix D: Phong s = 16 at eps 0.1 needs F ≈ sqrt(16 ln 10) ≈ 6.1, P = 0
    assert abs(doc["main"]["F"] - np.sqrt(-16 * np.log(0.1))) <= 1.5 and doc["main"]["P"] == 0


def test_report_some_failed_exit_1(tmp_path, capsys):
    bad = tmp_path / "empty.brdf"
    bad.write_text("# nothing\n")
    out = tmp_path / "rep"
    assert main(["report", "lambert:albedo=0.3", str(bad), "--out", str(out), *FAST]) == 1
    printed = capsys.readouterr().out
    assert "FAILED" in printed and "empty" in printed
    with open(out / "summary.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert [r["status"] for r in rows] == ["ok", "failed"]
    assert "empty.brdf" in rows[1]["error"]


@pytest.mark.parametrize(
    "argv",
    [
        ["report"],  # no BRDF
        ["report", "phong:s=8", "--eps", "2"],
        ["report", "phong:s=8", "--workers", "0"],
        ["report", "phong:s=8", "--tolerances", "0.1,abc"],
        ["report", "phong:s=8", "--preview", "magic"],
    ],
)
def test_report_bad_usage_exit_2(argv, capsys):
    with pytest.raises(SystemExit) as exc:
        main(argv)
    assert exc.value.code == 2


def test_report_bad_option_values_exit_2(tmp_path, capsys):
    assert main(["report", "phong:s=8", "--models", "blinn", "--out", str(tmp_path), "--no-progress"]) == 2
    assert "unknown model" in capsys.readouterr().err
    assert main(["report", "phong:s=8", "--dask-scheduler", "bogus://nowhere", "--out", str(tmp_path), *FAST]) == 2
    assert "Dask scheduler" in capsys.readouterr().err


def test_bench_reports_missing_folder(tmp_path, capsys):
    assert main(["bench", "--benchmarks", str(tmp_path / "none")]) == 2
    assert "benchmarks" in capsys.readouterr().err


def test_bench_runs_a_script_entry_point(tmp_path, capsys):
    """Each script's main(argv) gets --quick; a failing one gives exit 1."""
    (tmp_path / "fit_speed.py").write_text(
        "def main(argv=None):\n    print('FIT TABLE', argv)\n    return 0\n")
    (tmp_path / "prefilter_speed.py").write_text(
        "def main(argv=None):\n    print('PREFILTER TABLE', argv)\n    return 0\n")
    assert main(["bench", "--quick", "--only", "fit", "prefilter", "--benchmarks", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "FIT TABLE ['--quick']" in out and "PREFILTER TABLE ['--quick']" in out
    (tmp_path / "fit_speed.py").write_text("def main(argv=None):\n    raise RuntimeError('boom')\n")
    assert main(["bench", "--only", "fit", "--benchmarks", str(tmp_path)]) == 1
    assert "FAILED: RuntimeError: boom" in capsys.readouterr().out


def test_report_refuses_file_orientation_for_builtin_maps(tmp_path, capsys):
    """The same orientation rule as every other verb (cli.common.load_oriented_env): exit 2,
    one line, nothing written."""
    out = tmp_path / "r"
    assert main(["report", "phong:s=8", "--quick", "--env", "builtin:sky", "--env-flip", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "apply to map files" in err and err.count("\n") == 1
    assert not out.exists()


def test_report_missing_brdf_file_is_a_usage_error(tmp_path, capsys):
    out = tmp_path / "r"
    assert main(["report", "phong:s=8", str(tmp_path / "nope.binary"), "--quick", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "nope.binary" in err and "no such BRDF file" in err and err.count("\n") == 1
    assert not out.exists()
