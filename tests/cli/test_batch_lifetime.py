"""Lifetime of `shrm report --workers N` (issues 28 and 30): a worker process that dies loses
only its task, which is retried once on a new worker (and fails alone when that worker dies
too); SIGTERM, Ctrl-C (SIGINT to the process group) and SIGKILL of the driver leave no worker,
no resource tracker and no open pipe behind, and no traceback; the temporaries a killed run
leaves in the output folder are removed by the next run, unless another run into it is alive.

The command runs as a subprocess (its own session, so that a test can signal its process
group); its processes are found in /proc (Linux). Every wait polls its condition with a
generous deadline for a loaded machine and ends as soon as the condition holds.
"""

from __future__ import annotations

import csv
import fcntl
import importlib
import json
import os
import re
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import pytest

from shrmkit.cli.report import _dask_engine, _pool, batch
from shrmkit.cli.report.batch import run_batch
from shrmkit.cli.report.options import profile

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")

#: the cheapest reports: no preview, one fit on few samples, one tolerance, 16-row environments
FAST = ["--quick", "--preview", "none", "--models", "lafortune", "--tolerances", "0.1", "--eps", "0.1",
        "--pairs", "30", "--fit-samples", "1024", "--env-height", "16", "--no-progress", "--no-plots"]
SPECS = ["phong:s=8", "lambert:albedo=0.5", "phong:s=20"]
NAMES = ["phong_s_8", "lambert_albedo_0.5", "phong_s_20"]
#: seconds: a whole batch, a stop, the end of every process (a loaded 2-core machine)
RUN_TIMEOUT, STOP_TIMEOUT = 240.0, 60.0


# ------------------------------------------------------------------------------ processes in /proc


def _stat(pid: int) -> tuple[str, int, int] | None:
    """(state, parent pid, start time) of a process, or None when there is none."""
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rpartition(")")[2].split()
    except OSError:
        return None
    return fields[0], int(fields[1]), int(fields[19])


def _cmdline(pid: int) -> str:
    try:
        return Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
    except OSError:
        return ""


def _descendants(pid: int) -> dict[int, int]:
    """{pid: start time} of every process below ``pid``."""
    table = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit() and (st := _stat(int(entry.name))) is not None:
            table[int(entry.name)] = st
    found, todo = {}, [pid]
    while todo:
        parent = todo.pop()
        for child, (_, ppid, start) in table.items():
            if ppid == parent and child not in found:
                found[child] = start
                todo.append(child)
    return found


def _alive(pid: int, start: int) -> bool:
    st = _stat(pid)
    return st is not None and st[2] == start and st[0] not in "ZX"  # a zombie has exited


def _workers(pid: int) -> list[int]:
    """The report worker processes of the driver ``pid`` (its spawned children, not the
    multiprocessing resource tracker)."""
    return sorted(p for p, start in _descendants(pid).items()
                  if _stat(p) is not None and _stat(p)[1] == pid and "spawn_main" in _cmdline(p)
                  and _alive(p, start))


def _sigint_held_off(pid: int) -> bool:
    """Whether SIGINT is blocked or ignored in process ``pid`` (/proc/PID/status SigBlk, SigIgn)."""
    fields = dict(line.split(":\t", 1) for line in Path(f"/proc/{pid}/status").read_text().splitlines()
                  if ":\t" in line)
    bit = 1 << (signal.SIGINT - 1)
    return bool((int(fields["SigBlk"], 16) | int(fields["SigIgn"], 16)) & bit)


def _watching(pid: int) -> bool:
    """Whether worker ``pid`` started its driver watch (past its start-up imports, in its own code)."""
    try:
        return any((task / "comm").read_text().strip() == _pool.WATCH_THREAD_NAME
                   for task in Path(f"/proc/{pid}/task").iterdir())
    except OSError:
        return False


def _wait_for(condition: Callable[[], object], timeout: float, what: str) -> object:
    deadline = time.monotonic() + timeout
    while True:
        value = condition()
        if value:
            return value
        if time.monotonic() > deadline:
            pytest.fail(f"timed out after {timeout:.0f} s waiting for {what}")
        time.sleep(0.05)


class Run:
    """`shrm report --workers 2 … SPECS` in its own session; ``end()`` kills whatever is left."""

    def __init__(self, out: Path, specs: list[str] = SPECS) -> None:
        self.out = out
        self.proc = subprocess.Popen([sys.executable, "-m", "shrmkit.cli.main", "report", "--workers", "2", *FAST,
                                      "--out", str(out), *specs],
                                     stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True)
        self.seen: dict[int, int] = {}

    def workers(self, count: int = 2, watching: bool = False) -> list[int]:
        """Wait until ``count`` workers run (``watching``: past their start, watching the driver); their pids."""
        def found():
            pids = [p for p in _workers(self.proc.pid) if not watching or _watching(p)]
            return pids if len(pids) >= count else None
        pids = _wait_for(found, STOP_TIMEOUT, f"{count} worker processes{' watching the driver' * watching}")
        self.remember()
        return pids

    def remember(self) -> dict[int, int]:
        """Every process below the driver now (workers and the resource tracker)."""
        self.seen.update(_descendants(self.proc.pid))
        return self.seen

    def finish(self, timeout: float) -> tuple[int, str, str]:
        """Exit status, stdout and stderr: returns only once every holder of the pipes closed them."""
        out, err = self.proc.communicate(timeout=timeout)
        return self.proc.returncode, out, err

    def assert_all_gone(self) -> None:
        """Every process the driver ever had ends (polled: the resource tracker ends after the driver)."""
        assert self.seen, "no process of the driver was recorded"
        _wait_for(lambda: not [p for p, s in self.seen.items() if _alive(p, s)], STOP_TIMEOUT,
                  f"the end of {[(p, _cmdline(p)[-70:]) for p, s in self.seen.items() if _alive(p, s)]}")

    def end(self) -> None:
        for pid, start in [(self.proc.pid, None), *self.remember().items()]:
            if start is None or _alive(pid, start):
                try:
                    os.kill(pid, signal.SIGKILL)
                except (ProcessLookupError, PermissionError):
                    pass
        try:
            self.proc.communicate(timeout=STOP_TIMEOUT)
        except (subprocess.TimeoutExpired, ValueError):
            pass


@pytest.fixture
def start(tmp_path):
    runs = []

    def start_run(specs: list[str] = SPECS) -> Run:
        runs.append(Run(tmp_path / f"out{len(runs)}", specs))
        return runs[-1]

    yield start_run
    for run in runs:
        run.end()


def _statuses(out: Path) -> dict[str, str]:
    with open(out / "summary.csv", newline="") as f:
        return {row["name"]: row["status"] for row in csv.DictReader(f)}


def _one_interrupted_line(err: str, signame: str) -> re.Match:
    assert "Traceback" not in err, err[-3000:]
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1, err[-3000:]
    found = re.fullmatch(rf"shrm report: interrupted \({signame}\): (\d) of 3 reports written to .*; rerun to make "
                         r"the rest", lines[0])
    assert found, lines[0]
    return found


# ------------------------------------------------------------------------------ a worker dies


def test_killed_worker_task_is_retried_and_every_report_written(start):
    """SIGKILL to a worker while it holds its task (it gets one as it starts): one line says its
    BRDF was retried, the other worker goes on, both reports are written (exit 0), no
    traceback, no temporaries left."""
    run = start(SPECS[:2])
    victim = run.workers()[0]
    os.kill(victim, signal.SIGKILL)
    code, out, err = run.finish(RUN_TIMEOUT)
    assert "Traceback" not in err, err[-3000:]
    assert code == 0, (out, err[-3000:])
    retried = re.findall(r"^worker died on (\S+) \(killed by SIGKILL\); retried$", err, re.M)
    assert len(retried) == 1 and retried[0] in NAMES[:2], err
    assert "2 of 2 reports made" in out
    assert _statuses(run.out) == dict.fromkeys(NAMES[:2], "ok")
    for name in NAMES[:2]:
        assert json.loads((run.out / name / "report.json").read_text())["status"] == "ok"
    assert "retried" in (run.out / "index.html").read_text()
    assert not [p.name for p in run.out.iterdir() if p.name.startswith(".")]
    run.assert_all_gone()


def test_task_whose_retry_dies_too_is_one_failed_report(start):
    """The worker of a BRDF and the new worker of its retry both killed: that BRDF is one
    failed report (its report.json says why), the other is written, exit 1, no traceback."""
    run = start(SPECS[:2])
    first = run.workers()
    os.kill(first[0], signal.SIGKILL)
    second = _wait_for(lambda: [p for p in _workers(run.proc.pid) if p not in first], STOP_TIMEOUT,
                       "the worker of the retry")
    run.remember()
    os.kill(second[0], signal.SIGKILL)
    code, out, err = run.finish(RUN_TIMEOUT)
    assert "Traceback" not in err, err[-3000:]
    assert code == 1, (out, err[-3000:])
    retried = re.findall(r"^worker died on (\S+) \(killed by SIGKILL\); retried$", err, re.M)
    assert len(retried) == 1, err
    victim = retried[0]
    other = next(n for n in NAMES[:2] if n != victim)
    assert _statuses(run.out) == {victim: "failed", other: "ok"}
    doc = json.loads((run.out / victim / "report.json").read_text())
    assert doc["status"] == "failed" and "worker process died 2 times" in doc["error"], doc["error"]
    assert f"{victim}: FAILED: its worker process died 2 times (last: killed by SIGKILL)" in out
    run.assert_all_gone()


# ------------------------------------------------------------------------------ the driver is stopped


def test_sigterm_stops_the_batch_with_one_line_and_no_process_left(start):
    """SIGTERM to the driver while its workers run their code: exit 143 at once, one line saying
    how many reports were written (as many folders as that, and a summary listing them), every
    worker and the resource tracker gone, and the pipes closed (communicate returns)."""
    run = start()
    run.workers(watching=True)
    run.proc.send_signal(signal.SIGTERM)
    code, out, err = run.finish(STOP_TIMEOUT)
    assert code == 143, (out, err[-3000:])
    written = int(_one_interrupted_line(err, "SIGTERM").group(1))
    folders = [n for n in NAMES if (run.out / n / "report.json").is_file()]
    assert written == len(folders)
    assert sorted(_statuses(run.out)) == sorted(folders)
    assert not [p.name for p in run.out.iterdir() if p.name.startswith(".")]
    run.assert_all_gone()


def test_ctrl_c_while_workers_start_leaves_no_traceback(start):
    """SIGINT to the whole process group (what Ctrl-C in a terminal does) while the workers are
    still starting (importing): exit 130, one line, no traceback of any worker, nothing left.
    Every worker holds SIGINT off from its first instruction (blocked, then ignored): the first
    one once inherited the mask that multiprocessing's resource tracker unblocks after its own
    start, and a Ctrl-C during its imports printed "Fatal Python error: init_import_site"."""
    run = start()
    workers = run.workers()
    assert all(_sigint_held_off(pid) for pid in workers), [Path(f"/proc/{p}/status").read_text() for p in workers]
    os.killpg(run.proc.pid, signal.SIGINT)
    code, out, err = run.finish(STOP_TIMEOUT)
    assert code == 130, (out, err[-3000:])
    assert _one_interrupted_line(err, "SIGINT").group(1) == "0"
    run.assert_all_gone()


def test_workers_end_when_the_driver_is_killed(start):
    """SIGKILL to the driver (no chance to stop anything) while its workers run their code: they
    end by themselves, so the caller's pipes close (communicate returns) and no process is left."""
    run = start()
    run.workers(watching=True)
    run.proc.kill()
    code, _, err = run.finish(STOP_TIMEOUT)
    assert code == -signal.SIGKILL and "Traceback" not in err, err[-3000:]
    run.assert_all_gone()


# ------------------------------------------------------------------------------ temporaries of a killed run


def _fake_task(task, progress=None):
    row = {"name": task.name, "status": "ok", "source": task.source, "total_seconds": 0.0, "error": None}
    return batch.ReportOutcome(task.name, True, row, {"report.json": b"{}\n"})


def _leftovers(out: Path) -> None:
    """What a run killed while writing leaves: a report folder being assembled, a report moved
    aside and not yet replaced, the summary's temporary files, its lock file."""
    (out / ".phong_s_8.k2x9_a0q.tmp").mkdir(parents=True)
    (out / ".phong_s_8.k2x9_a0q.tmp" / "report.json").write_text("{}")
    (out / ".gold.ab12cd34.old" / "gold").mkdir(parents=True)
    (out / ".gold.ab12cd34.old" / "gold" / "report.json").write_text('{"kept": 1}')
    (out / ".summary.csv.zz99yy88.csv").write_text("name\n")
    (out / ".index.html.q1w2e3r4.html").write_text("<html>")
    (out / ".summary.csv.0123456789abcdef.csv").write_text("name\n")  # secrets.token_hex(8)
    (out / ".shrm-report-run.deadbeef.lock").write_text("")


def test_next_run_removes_the_temporaries_of_a_killed_run(tmp_path, monkeypatch):
    """Our temporary names only: a hidden file of the user's stays; the report a killed run had
    moved aside comes back."""
    monkeypatch.setattr(batch, "run_task", _fake_task)
    out = tmp_path / "rep"
    _leftovers(out)
    (out / ".keep").write_text("mine")
    (out / ".notes.tmp").write_text("mine")
    result = run_batch(["lambert:albedo=0.5"], out, profile("quick", preview="none", plots=False))
    assert result.n_failed == 0
    assert sorted(p.name for p in out.iterdir() if p.name.startswith(".")) == [".keep", ".notes.tmp"]
    assert json.loads((out / "gold" / "report.json").read_text()) == {"kept": 1}


def test_temporaries_of_a_live_run_are_left_alone(tmp_path, monkeypatch):
    """Another run into the same folder holds its lock: its temporaries are not touched (the
    run after it removes them), and this run leaves nothing of its own."""
    monkeypatch.setattr(batch, "run_task", _fake_task)
    out = tmp_path / "rep"
    _leftovers(out)
    before = sorted(p.name for p in out.iterdir())
    fd = os.open(out / ".shrm-report-run.deadbeef.lock", os.O_RDONLY)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)  # the other run is alive
        run_batch(["lambert:albedo=0.5"], out, profile("quick", preview="none", plots=False))
        assert sorted(p.name for p in out.iterdir() if p.name.startswith(".")) == before
    finally:
        os.close(fd)
    run_batch(["lambert:albedo=0.5"], out, profile("quick", preview="none", plots=False))
    assert not [p.name for p in out.iterdir() if p.name.startswith(".")]


# ------------------------------------------------------------------------------ Dask


@pytest.mark.slow
def test_dask_worker_death_costs_one_retry_and_the_rest_of_the_batch_goes_on(tmp_path):
    """A LocalCluster of 2 worker processes (under nannies). The task "victim" SIGKILLs its worker
    process the first time it runs: the scheduler's remove-worker event (and the task's start event)
    make the batch report one retry, and its second run, on the other worker, gives its outcome; the
    other task's outcome comes back and is not counted as a victim. Tasks are stand-ins (no report
    is computed): what is tested is the engine. Slow: a cluster of processes, ~14 s of CPU."""
    distributed = pytest.importorskip("distributed")
    marks = tmp_path / "marks"
    marks.mkdir()

    def task_function(task, threads, driver):  # pickled by value (a closure): runs on the workers
        if task.name == "victim" and not (marks / "victim").exists():
            (marks / task.name).write_text(str(os.getpid()))
            time.sleep(0.5)  # dies while computing: its start event has reached the scheduler
            os.kill(os.getpid(), signal.SIGKILL)
        return batch.ReportOutcome(task.name, True, {"name": task.name, "pid": os.getpid()}, {})

    options = profile("quick", preview="none", plots=False)
    tasks = [batch.ReportTask("lambert:albedo=0.5", "victim", options, "none"),
             batch.ReportTask("phong:s=8", "plain", options, "none")]
    events: list[tuple[str, str, str]] = []
    retried: list[str] = []
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                                  silence_logs=50) as cluster:
        outcomes = list(_dask_engine._dask(tasks, cluster.scheduler_address,
                                    lambda *e: events.append(e), retried, task_function))
    assert sorted(o.name for o in outcomes) == ["plain", "victim"] and all(o.ok for o in outcomes)
    victim = next(o for o in outcomes if o.name == "victim")
    assert str(victim.row["pid"]) != (marks / "victim").read_text()  # its second run, elsewhere
    retries = [e for e in events if e[0] == "retry"]
    assert [e[1] for e in retries] == ["victim"] and "was lost" in retries[0][2]
    assert len(retried) == 1 and retried[0].startswith("the Dask worker of victim died") and "\n" not in retried[0]


class _StubFuture:
    def __init__(self, key, result=None):
        self.key, self.status, self._result = key, "pending", result
        self.cancelled = False

    def result(self):
        return self._result

    def cancel(self):
        self.cancelled = True


def _stub_dask(monkeypatch, plan):
    """A stand-in distributed Client: ``plan(client, futures)`` runs at every look of the batch and
    returns (finished futures, events of topic "all", start events); no cluster is started."""
    import distributed

    class Completed:
        def __init__(self, client):
            self.client = client

        def next_batch(self, block):
            done, self.client.all_events, self.client.start_events = plan(self.client, self.client.futures)
            for future in done:
                future.status = "finished"
            return done

    class Client:
        status = "running"
        loop = None

        def __init__(self, address, **kw):
            self.futures, self.all_events, self.start_events = [], [], []

        def scheduler_info(self, **kw):
            return {"workers": {}}

        def submit(self, function, *args, key, **kw):
            task = args[1]
            self.futures.append(_StubFuture(key, batch.ReportOutcome(task.name, True, {"name": task.name}, {})))
            return self.futures[-1]

        def get_events(self, topic):
            return self.start_events if topic == _dask_engine.DASK_START_TOPIC else self.all_events

        def close(self, timeout=None):
            pass

    client = None

    def make(address, **kw):
        nonlocal client
        client = Client(address, **kw)
        return client

    monkeypatch.setattr(distributed, "Client", make)
    monkeypatch.setattr(distributed, "as_completed", lambda futures, loop=None: Completed(client))
    monkeypatch.setattr(_dask_engine, "DASK_POLL_SECONDS", 0.0)


def test_dask_task_whose_worker_dies_twice_is_one_failed_report(monkeypatch):
    """Stand-in scheduler events: "doomed" starts on worker A, A is removed (one retry, one line),
    it starts on B, B is removed too: one failed report naming the second death, its future
    cancelled; "queued" was listed on A's processing set without starting there (not a victim),
    and it and "fine" finish. The reference is the rule itself: TASK_TRIES = 2 runs."""
    looks = []

    def plan(client, futures):
        looks.append(len(looks))
        key = {f.key.removeprefix("shrm-report-"): f for f in futures}
        start_a = (1.0e12, {"key": "shrm-report-doomed", "worker": "tcp://a"})
        start_b = (1.0e12 + 2, {"key": "shrm-report-doomed", "worker": "tcp://b"})
        lost_a = (1.0e12 + 1, {"action": "remove-worker", "worker": "tcp://a",
                               "processing-tasks": {"shrm-report-doomed", "shrm-report-queued"}})
        lost_b = (1.0e12 + 3, {"action": "remove-worker", "worker": "tcp://b",
                               "processing-tasks": {"shrm-report-doomed"}})
        if len(looks) == 1:
            return [], [lost_a], [start_a]
        if len(looks) == 2:
            return [], [lost_a, lost_b], [start_a, start_b]
        return [key["queued"], key["fine"]] if len(looks) == 3 else [], [lost_a, lost_b], [start_a, start_b]

    _stub_dask(monkeypatch, plan)
    options = profile("quick", preview="none", plots=False)
    tasks = [batch.ReportTask("phong:s=8", n, options, "none") for n in ("doomed", "queued", "fine")]
    events, retried = [], []
    outcomes = list(_dask_engine._dask(tasks, "tcp://stub:1", lambda *e: events.append(e), retried))
    by_name = {o.name: o for o in outcomes}
    assert sorted(by_name) == ["doomed", "fine", "queued"]
    assert by_name["fine"].ok and by_name["queued"].ok and not by_name["doomed"].ok
    assert "its Dask worker died 2 times (last: tcp://b)" in by_name["doomed"].row["error"]
    assert [e[:2] for e in events if e[0] == "retry"] == [("retry", "doomed")]
    assert retried == ["the Dask worker of doomed died (tcp://a); retried on another worker"]


def test_lost_dask_scheduler_is_one_line(tmp_path, monkeypatch):
    """The scheduler goes away during a batch: the client's calls fail. The batch stops with one line
    ("lost the Dask scheduler …"), the reports without a result are failed rows, the summary is
    written, and nothing of distributed's logging reaches stderr. Stand-in client: no cluster."""
    class Future:
        def __init__(self, key):
            self.key, self.status = key, "pending"

    class Completed:
        def next_batch(self, block):
            return []

    class Client:
        status = "running"
        loop = None

        def __init__(self, address, **kw):
            pass

        def scheduler_info(self, **kw):
            return {"workers": {}}

        def submit(self, function, task, *args, key, **kw):
            return Future(key)

        def get_events(self, topic):
            self.status = "closed"
            raise OSError("Timed out trying to connect to tcp://127.0.0.1:1: connection refused\nmore")

        def close(self, timeout=None):
            pass

    import distributed

    monkeypatch.setattr(distributed, "Client", Client)
    monkeypatch.setattr(distributed, "as_completed", lambda futures, loop=None: Completed())
    out = tmp_path / "rep"
    result = run_batch(["phong:s=8", "lambert:albedo=0.5"], out, profile("quick", preview="none", plots=False),
                       scheduler="tcp://127.0.0.1:1")
    assert result.n_failed == 2
    errors = [r["error"] for r in result.rows]
    assert all("lost the Dask scheduler tcp://127.0.0.1:1 (OSError: Timed out" in e for e in errors), errors
    assert all("\n" not in e and "more" not in e for e in errors)
    assert (out / "summary.csv").exists()


def test_worker_target_module_sets_the_parent_death_signal_before_heavy_imports():
    """A spawned worker imports its target's module first: worker_boot.py must load no numpy, scipy or
    matplotlib, so that PR_SET_PDEATHSIG is set before the report modules' seconds of imports (a driver
    killed then left its workers running 3-14 s: benchmarks in the closing note)."""
    heavy = "('numpy', 'scipy', 'matplotlib', 'shrmkit.cli.report.batch', 'shrmkit.cli.report._pool')"
    code = f"import sys, shrmkit.cli.report.worker_boot; print(sorted(m for m in {heavy} if m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert out.returncode == 0 and out.stdout.strip() == "[]", out.stderr[-2000:]
    assert _pool._Pool.start_worker.__code__.co_names.count("worker_boot") >= 1  # the target the driver starts


def test_worker_target_names_the_process_engines_worker_loop():
    """The worker loop is started by name (``worker_boot.boot`` imports it): the name must stay that
    of the process engine's loop wherever it lives (a moved module left the name behind)."""
    module, _, name = _pool.WORKER_TARGET.partition(":")
    assert getattr(importlib.import_module(module), name) is _pool._worker_main
