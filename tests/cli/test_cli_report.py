"""`shrm report` and `shrm bench`: exit codes (0 all made, 1 some failed, 2 bad usage), outputs."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest

from shrmkit.cli.main import main

FAST = ["--quick", "--preview", "none", "--models", "lafortune", "--tolerances", "0.1", "--eps", "0.1",
        "--pairs", "30", "--fit-samples", "1024", "--no-progress", "--no-plots"]


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


def test_bench_refuses_a_folder_without_the_scripts(tmp_path, capsys):
    """A folder that lacks the chosen scripts: exit 2, one line naming the folder and the
    missing scripts, nothing run (the present script would print)."""
    (tmp_path / "fit_speed.py").write_text("def main(argv=None):\n    print('RAN')\n    return 0\n")
    assert main(["bench", "--benchmarks", str(tmp_path)]) == 2
    captured = capsys.readouterr()
    assert captured.err == (f"shrm bench: error: {tmp_path}: benchmark scripts missing: prefilter_speed.py, "
                            "render_speed.py (pass --benchmarks DIR holding them, or --only the ones present)\n")
    assert "RAN" not in captured.out
    assert main(["bench", "--only", "render", "--benchmarks", str(tmp_path)]) == 2
    assert "benchmark script missing: render_speed.py" in capsys.readouterr().err


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


# ----------------------------------------------------------------------------- long names, per-item failures


@pytest.mark.slow
def test_report_with_245_character_file_names(tmp_path, capsys):
    """A table and a model file whose stems are 245 characters and share their first 100:
    both reports are made into distinct folders of at most 100 + 11 characters (a cut stem
    and a hash of the full stem), and the summary lists the full paths."""
    import shutil
    from pathlib import Path

    from shrmkit.cli.report.batch import MAX_NAME_CHARS

    table = tmp_path / ("t" * 245 + ".npz")
    shutil.copy(Path(__file__).parents[1] / "resources" / "tiny_table.npz", table)
    model = tmp_path / ("t" * 244 + "u.json")
    model.write_text('{"model_spec": "phong:s=16"}\n')
    out = tmp_path / "rep"
    assert main(["report", str(table), str(model), "--out", str(out), *FAST]) == 0
    printed = capsys.readouterr().out
    folders = sorted(d.name for d in out.iterdir() if d.is_dir())
    assert len(folders) == 2 and folders[0] != folders[1]
    for name in folders:
        assert len(name) == MAX_NAME_CHARS + 11 and name.startswith("t" * MAX_NAME_CHARS + "-")
        assert (out / name / "report.json").is_file()
    assert not [p.name for p in out.iterdir() if p.name.startswith(".")]  # no temporary leftovers
    with open(out / "summary.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert [r["status"] for r in rows] == ["ok", "ok"]
    assert [r["source"] for r in rows] == [str(table), str(model)]
    assert sorted(r["name"] for r in rows) == folders
    assert "summary:" in printed and "2 of 2 reports made" in printed


def test_report_names_are_short_unique_and_stable():
    from shrmkit.cli.report.batch import MAX_NAME_CHARS, report_names

    long_a, long_b = "a" * 245 + ".json", "a" * 244 + "b.json"
    spec = "lambert:albedo=0.3" + ",x=1" * 100  # longer than a file name may be
    names = report_names([long_a, long_b, long_a, spec, "phong:s=8"])
    assert names[0] != names[1] and names[2] == names[0] + "-2"
    assert all(len(n) <= MAX_NAME_CHARS + 13 for n in names)
    assert names[3].startswith("lambert_albedo_0.3_x_1") and len(names[3]) == MAX_NAME_CHARS + 11
    assert names[4] == "phong_s_8"
    assert report_names([long_a]) == names[:1]  # the same name on every run


def _fake_outcome(task, progress=None):
    from shrmkit.cli.report.batch import ReportOutcome

    row = {"name": task.name, "status": "ok", "source": task.source, "total_seconds": 0.0, "error": None}
    return ReportOutcome(task.name, True, row, {"report.json": b"{}\n"})


def test_report_folder_write_failure_fails_that_brdf_only(tmp_path, capsys, monkeypatch):
    """An OSError writing one folder (here: forced) fails that BRDF; the others are written
    and the summary is printed (exit 1)."""
    import errno

    from shrmkit.cli.report import batch

    real_write = batch.write_folder

    def write(out, name, files):
        if name == "lambert_albedo_0.3":
            raise OSError(errno.ENAMETOOLONG, "File name too long")
        return real_write(out, name, files)

    monkeypatch.setattr(batch, "run_task", _fake_outcome)
    monkeypatch.setattr(batch, "write_folder", write)
    out = tmp_path / "rep"
    assert main(["report", "phong:s=8", "lambert:albedo=0.3", "phong:s=16", "--out", str(out), *FAST]) == 1
    printed = capsys.readouterr().out
    assert "lambert_albedo_0.3: FAILED: cannot write the report folder" in printed
    assert "File name too long" in printed and "2 of 3 reports made" in printed and "summary:" in printed
    with open(out / "summary.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert [r["status"] for r in rows] == ["ok", "failed", "ok"]
    assert (out / "phong_s_16" / "report.json").is_file() and not (out / "lambert_albedo_0.3").exists()


def test_report_engine_failure_still_writes_the_summary(tmp_path, capsys, monkeypatch):
    """The engine dies after the first result: the rest are failed rows, the summary says why."""
    from shrmkit.cli.report import batch

    def dying(tasks, progress):
        yield _fake_outcome(tasks[0])
        raise RuntimeError("worker process died")

    monkeypatch.setattr(batch, "_serial", dying)
    out = tmp_path / "rep"
    assert main(["report", "phong:s=8", "lambert:albedo=0.3", "--out", str(out), *FAST]) == 1
    printed = capsys.readouterr().out
    assert "lambert_albedo_0.3: FAILED: no result: the serial engine stopped: RuntimeError: worker process died" \
        in printed
    assert "1 of 2 reports made" in printed
    with open(out / "summary.csv", newline="") as f:
        assert [r["status"] for r in csv.DictReader(f)] == ["ok", "failed"]
    assert "Incomplete" in (out / "index.html").read_text()


@pytest.mark.parametrize("option, value, bound", [
    ("--lobes", "1000", "1..4"), ("--fit-samples", "1000000000", "1..4,194,304"),
    ("--pairs", "10000000", "1..1,000,000"), ("--workers", "100000", "1..256"),
])
def test_absurd_sizes_are_usage_errors_before_any_work(tmp_path, capsys, option, value, bound):
    """Issue 30: `--fit-samples 1e9` asked for 22-24 GiB per BRDF and `--lobes 1000` silently dropped
    the fit with exit 0; each is now a usage error (exit 2) naming the option and its range, and no
    output folder is made."""
    out = tmp_path / "rep"
    with pytest.raises(SystemExit) as stop:
        main(["report", "lambert:albedo=0.5", option, value, "--out", str(out)])
    err = capsys.readouterr().err
    assert stop.value.code == 2 and f"argument {option}: must be in {bound}" in err and "Traceback" not in err
    assert not out.exists()
