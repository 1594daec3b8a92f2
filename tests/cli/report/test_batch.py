"""Batch reports: a corrupt file among good ones, atomic folders, summary files, and the
same results from the serial, process-pool and Dask engines.

Threaded workers: matplotlib's text layout and the offscreen GL context are
process-global, so a Dask worker with several threads must not lose reports
(``cli/report/shared_state.py``). Before the locks were added,
``test_figures_drawn_from_four_threads_at_once`` failed in 3 of 3 runs and
``test_dask_worker_with_four_threads_loses_no_report`` in 2 of 2 (``ParseException`` from
mathtext on log-axis tick labels, matplotlib issue #26289); with the locks both passed in
every run."""

from __future__ import annotations

import csv
import json
import sys
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

from shrmkit.cli.report.batch import report_names, run_batch
from shrmkit.cli.report.collect import collect_report, strip_timings
from shrmkit.cli.report.options import profile
from shrmkit.cli.report.plots import make_plots
from shrmkit.cli.report.writer import write_folder

GOOD = ["lafortune:kd=0.2,n=30,ks=2", "lambert:albedo=0.5"]


def tiny_options(plots: bool = False):
    """The cheapest reports; without plots (most of a quick report's time) unless a test checks the
    plots or matplotlib's lock (the serial batch's pages, the threaded Dask worker)."""
    return profile("quick", preview="none", models=("lafortune",), tolerances=(0.1,), eps=0.1, n_pairs=30,
                   fit_samples=1024, albedo_nodes=16, plots=plots)


def reports(out):
    return {d.name: strip_timings(json.loads((d / "report.json").read_text())) for d in sorted(out.iterdir())
            if d.is_dir()}


@pytest.fixture(scope="module")
def serial_batch(tmp_path_factory):
    root = tmp_path_factory.mktemp("batch")
    corrupt = root / "broken.binary"
    corrupt.write_bytes(np.array([90, 90, 180], "<i4").tobytes() + b"\x00" * 1000)  # truncated MERL file
    sources = [GOOD[0], str(corrupt), GOOD[1]]
    events = []
    result = run_batch(sources, root / "serial", tiny_options(), progress=lambda *e: events.append(e))
    return root, sources, result, events


class TestSerialBatch:
    """The tests of the serial_batch fixture: one unit of work under xdist (tests/conftest.py), one serial run."""

    def test_corrupt_file_is_reported_and_does_not_stop_the_batch(self, serial_batch):
        root, sources, result, events = serial_batch
        out = root / "serial"
        assert result.n_failed == 1 and not result.ok
        assert [r["status"] for r in result.rows] == ["ok", "failed", "ok"]
        assert "truncated" in result.rows[1]["error"] and "broken.binary" in result.rows[1]["error"]
        failed = json.loads((out / "broken" / "report.json").read_text())
        assert failed["status"] == "failed" and "truncated" in failed["error"]
        for name in ("lafortune_kd_0.2_n_30_ks_2", "lambert_albedo_0.5"):
            doc = json.loads((out / name / "report.json").read_text())
            assert doc["status"] == "ok"
            assert "Plots not drawn" in (out / name / "report.html").read_text()  # tiny_options: no plots
            assert (out / name / "report.md").read_text().startswith("# BRDF report")
        # the summary: one row per BRDF in input order, failure with its error
        with open(out / "summary.csv", newline="") as f:
            rows = list(csv.DictReader(f))
        assert [r["status"] for r in rows] == ["ok", "failed", "ok"]
        assert rows[1]["error"].startswith(str(sources[1]))
        assert rows[0]["F@0.1"] and rows[0]["fit_rel_rms_lafortune"]
        index = (out / "index.html").read_text()
        assert "broken" in index and 'class="sortable"' in index and "<script>" in index
        # no temporary folders left behind (atomic writes)
        assert not [p.name for p in out.iterdir() if p.name.startswith(".")]
        # progress: every BRDF started and finished, stages reported
        done = [e[1] for e in events if e[0] == "done"]
        assert done == ["lafortune_kd_0.2_n_30_ks_2", "broken", "lambert_albedo_0.5"]
        assert any(e[0] == "stage" and e[2] == "orders" for e in events)

    def test_lambert_albedo_in_batch_report(self, serial_batch):
        """Lambert: directional albedo = albedo at every view (closed form), no warnings."""
        root, _, _, _ = serial_batch
        doc = json.loads((root / "serial" / "lambert_albedo_0.5" / "report.json").read_text())
        np.testing.assert_allclose(doc["data_checks"]["albedo"]["rgb"], 0.5, rtol=1e-9)
        assert doc["warnings"] == []

    @pytest.mark.slow
    def test_workers_match_serial(self, serial_batch):
        """--workers 2 (spawned processes) gives the same reports as the serial run."""
        root, sources, _, _ = serial_batch
        result = run_batch(sources, root / "workers", tiny_options(), workers=2)
        assert result.engine.startswith("2 processes") and result.n_failed == 1
        assert reports(root / "workers") == reports(root / "serial")

    def test_dask_matches_serial(self, serial_batch):
        """The same tasks on a Dask LocalCluster (in-process workers) give the same reports."""
        distributed = pytest.importorskip("distributed")
        root, sources, _, _ = serial_batch
        # ":0": the scheduler's HTTP server on a free port (None still takes 8787, and a second
        # cluster on the machine then warns, an error here)
        with distributed.LocalCluster(
            n_workers=1, threads_per_worker=2, processes=False, dashboard_address=":0"
        ) as cluster:
            result = run_batch(sources, root / "dask", tiny_options(), scheduler=cluster.scheduler_address)
        assert result.engine.startswith("dask") and result.n_failed == 1
        assert [r["name"] for r in result.rows] == [r["name"] for r in run_rows(root / "serial")]
        assert reports(root / "dask") == reports(root / "serial")


def run_rows(out):
    with open(out / "summary.csv", newline="") as f:
        return list(csv.DictReader(f))


def test_report_names_are_unique_and_safe(tmp_path):
    names = report_names(["a/b/gold.binary", "c/gold.binary", "phong:s=8", "x.npz"])
    assert names == ["gold", "gold-2", "phong_s_8", "x"]


def test_write_folder_replaces_atomically(tmp_path):
    write_folder(tmp_path, "r", {"a.txt": b"one", "b.txt": b"two"})
    write_folder(tmp_path, "r", {"a.txt": b"new"})
    assert sorted(p.name for p in (tmp_path / "r").iterdir()) == ["a.txt"]
    assert (tmp_path / "r" / "a.txt").read_bytes() == b"new"
    assert [p.name for p in tmp_path.iterdir()] == ["r"]


#: 4 cheap BRDFs, one of each kind (the log-axis speed/error plot is drawn for each): four tasks
#: at once on four threads. Without the matplotlib lock a Dask worker with 4 threads lost 2-3 of
#: these reports in 4 of 6 runs, as often as with the 8 or 12 BRDFs this list had before (6 of 9
#: and 2 of 3 runs); test_figures_drawn_from_four_threads_at_once fails every time.
MANY = ["phong:s=16", "lambert:albedo=0.5", "lafortune:kd=0.2,n=30,ks=2", "microfacet:sigma=0.4"]


@pytest.fixture(scope="module")
def serial_many(tmp_path_factory):
    root = tmp_path_factory.mktemp("threads")
    result = run_batch(MANY, root / "serial", tiny_options(plots=True))
    assert result.n_failed == 0
    return root


def test_figures_drawn_from_four_threads_at_once():
    """4 figure sets drawn by 4 threads at once, with the interpreter switching threads every
    10 µs (as a loaded machine does): every set is complete. Without the lock this failed in
    every round (2 to 4 of the 4 sets, 22 of 22 rounds, cold or warm caches; before, two rounds
    of 8 sets: 2 to 8 of them a round; see the module docstring)."""
    docs = [collect_report(s, tiny_options())[0] for s in ("lafortune:kd=0.2,n=30,ks=2", "phong:s=40",
                                                           "microfacet:sigma=0.3")]
    expected = {"energy", "accuracy_by_p", "speed_error", "fit_slices", "fit_bands", "explorer_slice",
                "explorer_polar", "explorer_albedo"}
    interval = sys.getswitchinterval()
    sys.setswitchinterval(1e-5)
    try:
        with ThreadPoolExecutor(4) as pool:
            drawn = list(pool.map(make_plots, [docs[i % 3] for i in range(4)]))
        for plots in drawn:
            assert set(plots) == expected
            assert all(len(v) > 1000 and v[:8] == b"\x89PNG\r\n\x1a\n" for v in plots.values())
    finally:
        sys.setswitchinterval(interval)


class TestManyBrdfs:
    """The tests of the serial_many fixture: one unit of work under xdist (tests/conftest.py), one serial run.

    Spawned worker processes hold their own copies of the global state (no threads share it):
    that they match the serial run is checked by TestSerialBatch.test_workers_match_serial (with a
    corrupt file) and test_scaling (largest first), not a third time here."""

    def test_dask_worker_with_four_threads_loses_no_report(self, serial_many):
        """One in-process Dask worker with 4 threads runs all 4 reports; the reports equal the serial ones."""
        distributed = pytest.importorskip("distributed")
        interval = sys.getswitchinterval()
        sys.setswitchinterval(1e-5)  # switch threads often, as a loaded machine does
        try:
            with distributed.LocalCluster(n_workers=1, threads_per_worker=4, processes=False,
                                          dashboard_address=":0") as cluster:
                result = run_batch(MANY, serial_many / "dask", tiny_options(plots=True),
                                   scheduler=cluster.scheduler_address)
        finally:
            sys.setswitchinterval(interval)
        assert result.n_failed == 0, [r.get("error") for r in result.rows]
        assert reports(serial_many / "dask") == reports(serial_many / "serial")


def test_two_environments_with_one_name_get_two_columns(tmp_path):
    """Two maps both named 'constant' (different radiance) keep their own summary columns."""
    options = profile("quick", preview="none", models=("lafortune",), tolerances=(0.1,), eps=0.1, n_pairs=30,
                      fit_samples=1024, albedo_nodes=16,
                      envs=("builtin:constant,height=16", "builtin:constant,height=16,value=2"))
    result = run_batch(["lambert:albedo=0.5"], tmp_path / "r", options)
    doc = json.loads((tmp_path / "r" / "lambert_albedo_0.5" / "report.json").read_text())
    assert [e["name"] for e in doc["environments"]] == ["constant", "constant-2"]
    row = result.rows[0]
    assert {"shrm_rel_rms_constant", "shrm_rel_rms_constant-2"} <= set(row)


def test_summary_csv_cells_are_never_formulas(tmp_path):
    """Names and errors that a spreadsheet would run as formulas (issue 28: a file named
    `=HYPERLINK(...)`) are written with a leading `'`; numbers, negative ones included, are not."""
    from shrmkit.cli.report.writer import write_summary

    rows = [{"name": "=HYPERLINK(\"http://x\")", "status": "failed", "value": -0.5, "text": "-0.25",
             "error": "@SUM(A1:A2) +1 -cmd"},
            {"name": "plain", "status": "ok", "value": 1.5, "text": "+3", "error": None}]
    csv_path, _ = write_summary(tmp_path, rows)
    with open(csv_path, newline="") as f:
        got = list(csv.DictReader(f))
    assert got[0]["name"] == "'=HYPERLINK(\"http://x\")" and got[0]["error"] == "'@SUM(A1:A2) +1 -cmd"
    assert got[0]["value"] == "-0.5" and got[0]["text"] == "-0.25" and got[1]["text"] == "+3"
    assert got[1]["name"] == "plain" and got[1]["error"] == ""
    assert all(not cell.startswith(("=", "@")) for row in got for cell in row.values())


def test_two_runs_into_one_folder_keep_every_row(tmp_path):
    """Two batches writing into the same --out at once (issue 28: both exit 0 and the index listed 2
    of the 3 reports in the folder): the index and summary.csv hold every report folder, this run's
    rows first, each run's rows rebuilt from report.json under a lock on the folder."""
    out = tmp_path / "out"
    batches = [["lambert:albedo=0.5", "phong:s=16"], ["lafortune:kd=0.2,n=30,ks=2"]]
    with ThreadPoolExecutor(2) as pool:
        results = list(pool.map(lambda sources: run_batch(sources, out, tiny_options()), batches))
    assert all(r.n_failed == 0 for r in results)
    with open(out / "summary.csv", newline="") as f:
        names = sorted(row["name"] for row in csv.DictReader(f))
    assert names == sorted(["lambert_albedo_0.5", "phong_s_16", "lafortune_kd_0.2_n_30_ks_2"])
    index = (out / "index.html").read_text()
    assert all(name in index for name in names)
