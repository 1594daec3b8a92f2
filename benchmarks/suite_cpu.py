"""CPU seconds per test (user + sys of the test process and of the children it waited for), so that
the suite's cost can be compared old vs new on a loaded machine where wall times are noise.

Usage::

    python benchmarks/suite_cpu.py [--top 30] [--json out.json] -- [pytest args]
    python benchmarks/suite_cpu.py --top 20 -- -p no:xdist -q tests/analysis/test_view_bands.py
    python benchmarks/suite_cpu.py --compare old.json new.json --top 30
    python benchmarks/suite_cpu.py --durations-out tests/resources/test_durations.json -- -n 2 -q

``--durations-out``: the tests' wall seconds (setup + call + teardown) of at least ``--min-seconds``
(default 1.0), ``{node id: seconds}`` sorted longest first, the file from which tests/conftest.py
hands the tests out to the xdist workers longest first (from a whole run on the project machine).

Runs pytest in this process with a small plugin: for each test, setup + call + teardown, the
process CPU time (``os.times``: user + sys, all threads) plus the CPU time of children reaped
meanwhile (``os.times`` children fields: subprocesses the test waited for, e.g. the CLI run in a
fresh interpreter). Children that outlive the test (daemons, xdist) are not counted. Prints the
top tests by CPU, the wall time beside it, and the sum. Under xdist (``-n 2``) the plugin runs in
each worker and the numbers are collected through a JSON file per worker (``SHRM_SUITE_CPU_DIR``).
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

import pytest


def _cpu() -> float:
    t = os.times()
    return t.user + t.system + t.children_user + t.children_system


class CpuPlugin:
    """pytest plugin: per-test CPU and wall seconds (setup + call + teardown), written at the end of
    the session to ``SHRM_SUITE_CPU_DIR/<worker>.json`` when that variable is set."""

    def __init__(self) -> None:
        self.rows: dict[str, list[float]] = {}

    @pytest.hookimpl(hookwrapper=True)
    def pytest_runtest_protocol(self, item, nextitem):  # noqa: ARG002 - pytest hook signature
        cpu0, wall0 = _cpu(), time.perf_counter()
        self.first = getattr(self, "first", time.time())
        yield
        self.rows[item.nodeid] = [_cpu() - cpu0, time.perf_counter() - wall0]
        self.last = time.time()

    def pytest_sessionfinish(self, session):  # noqa: ARG002
        folder = os.environ.get("SHRM_SUITE_CPU_DIR")
        if folder:
            worker = os.environ.get("PYTEST_XDIST_WORKER", "main")
            Path(folder, f"{worker}.json").write_text(json.dumps(self.rows))
            if self.rows:
                Path(folder, f"{worker}.span").write_text(json.dumps([self.first, self.last, _cpu()]))


def table(rows: dict[str, list[float]], top: int) -> str:
    lines = [f"{'cpu s':>7} {'wall s':>7}  test"]
    for nodeid, (cpu, wall) in sorted(rows.items(), key=lambda kv: -kv[1][0])[:top]:
        lines.append(f"{cpu:7.2f} {wall:7.2f}  {nodeid}")
    cpu_sum = sum(v[0] for v in rows.values())
    wall_sum = sum(v[1] for v in rows.values())
    lines.append(f"{cpu_sum:7.1f} {wall_sum:7.1f}  sum over {len(rows)} tests")
    return "\n".join(lines)


def durations_json(rows: dict[str, list[float]], min_seconds: float = 1.0) -> str:
    """``{node id: wall seconds}`` of the tests of at least ``min_seconds``, longest first, one a
    line (the expected durations tests/conftest.py orders the work by)."""
    long = sorted(((n, round(v[1], 1)) for n, v in rows.items() if v[1] >= min_seconds), key=lambda kv: -kv[1])
    return "{\n" + ",\n".join(f"{json.dumps(n)}: {s}" for n, s in long) + "\n}\n"


def compare(old: dict[str, list[float]], new: dict[str, list[float]], top: int) -> str:
    names = sorted(set(old) | set(new), key=lambda n: -max(old.get(n, [0])[0], new.get(n, [0])[0]))
    lines = [f"{'old cpu':>8} {'new cpu':>8}  test"]
    for n in names[:top]:
        o, w = old.get(n, [float("nan")])[0], new.get(n, [float("nan")])[0]
        lines.append(f"{o:8.2f} {w:8.2f}  {n}")
    lines.append(f"{sum(v[0] for v in old.values()):8.1f} {sum(v[0] for v in new.values()):8.1f}  sum "
                 f"({len(old)} / {len(new)} tests)")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if "--" in argv:
        cut = argv.index("--")
        own, pytest_args = argv[:cut], argv[cut + 1:]
    else:
        own, pytest_args = argv, []
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--top", type=int, default=30)
    parser.add_argument("--json", help="write {nodeid: [cpu s, wall s]} here")
    parser.add_argument("--durations-out", help="write {nodeid: wall s} of the tests of at least --min-seconds here")
    parser.add_argument("--min-seconds", type=float, default=1.0)
    parser.add_argument("--compare", nargs=2, metavar=("OLD", "NEW"), help="compare two --json files")
    args = parser.parse_args(own)
    if args.compare:
        old, new = (json.loads(Path(p).read_text()) for p in args.compare)
        print(compare(old, new, args.top))
        return 0
    with tempfile.TemporaryDirectory(prefix="suite_cpu_") as folder:
        os.environ["SHRM_SUITE_CPU_DIR"] = folder
        # the plugin alone on the path (not every benchmark script), importable by name in xdist
        # workers too (they inherit the environment)
        shim = Path(folder, "plugin")
        shim.mkdir()
        shutil.copy(__file__, shim / "suite_cpu.py")
        sys.path.insert(0, str(shim))
        os.environ["PYTHONPATH"] = os.pathsep.join([str(shim), os.environ.get("PYTHONPATH", "")]).rstrip(os.pathsep)
        wall0 = time.perf_counter()
        code = pytest.main(["-p", "suite_cpu", *pytest_args])
        wall = time.perf_counter() - wall0
        rows: dict[str, list[float]] = {}
        for path in Path(folder).glob("*.json"):  # one file per process that ran tests
            rows.update(json.loads(path.read_text()))
        spans = {p.stem: json.loads(p.read_text()) for p in Path(folder).glob("*.span")}
    print(table(rows, args.top))
    print(f"wall of the whole run: {wall:.1f} s; load average now: {os.getloadavg()}")
    if spans:
        start = min(v[0] for v in spans.values())
        for name, (first, last, cpu) in sorted(spans.items()):
            print(f"  {name}: first test at +{first - start:.1f} s, last test ended at +{last - start:.1f} s, "
                  f"process CPU {cpu:.1f} s (collection included)")
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=0))
    if args.durations_out:
        Path(args.durations_out).write_text(durations_json(rows, args.min_seconds))
    return int(code)


_PLUGIN = CpuPlugin()


def pytest_configure(config):
    config.pluginmanager.register(_PLUGIN, "suite_cpu_rows")


if __name__ == "__main__":
    sys.exit(main())
