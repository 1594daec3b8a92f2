"""How long `shrm report --workers 2`'s worker processes outlive a driver killed during their
imports (issue 30): the driver is SIGKILLed as soon as both worker processes exist (they are then
importing the report modules); the table gives the seconds until every worker has exited.

Workers set the parent-death signal first (``cli/report/worker_boot.py``), before the heavy
imports; before that change they set it only once the report modules were loaded. To compare with
an older checkout, run this script with ``PYTHONPATH`` pointing at a folder that holds it as
``shrmkit`` (the workers inherit the environment).

Usage::

    python benchmarks/worker_parent_death.py --rounds 3
"""

from __future__ import annotations

import argparse
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

#: the cheapest reports (as tests/cli/test_batch_lifetime.py)
FAST = ["--quick", "--preview", "none", "--models", "lafortune", "--tolerances", "0.1", "--eps", "0.1",
        "--pairs", "30", "--fit-samples", "1024", "--env-height", "16", "--no-progress", "--no-plots"]


def _workers(driver: int) -> list[int]:
    """Live spawned children of ``driver`` (their command line runs multiprocessing's spawn_main)."""
    found = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            fields = (entry / "stat").read_text().rpartition(")")[2].split()
            command = (entry / "cmdline").read_bytes()
        except OSError:
            continue
        if int(fields[1]) == driver and b"spawn_main" in command and fields[0] != "Z":
            found.append(int(entry.name))
    return found


def _alive(pid: int) -> bool:
    try:
        return Path(f"/proc/{pid}/stat").read_text().rpartition(")")[2].split()[0] != "Z"
    except OSError:
        return False


def one_round(timeout: float = 60.0) -> tuple[float, int]:
    """(seconds from the driver's SIGKILL until no worker is left, workers seen)."""
    out = tempfile.mkdtemp(prefix="shrm_parent_death_")
    shrm = Path(sys.executable).with_name("shrm")
    driver = subprocess.Popen([str(shrm), "report", "phong:s=8", "lambert:albedo=0.5", "--workers", "2",
                               "--out", out, *FAST], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                              start_new_session=True)
    deadline = time.monotonic() + timeout
    workers: list[int] = []
    while time.monotonic() < deadline and len(workers) < 2:
        workers = _workers(driver.pid)
        time.sleep(0.005)
    os.kill(driver.pid, signal.SIGKILL)
    killed = time.monotonic()
    driver.wait()
    while any(_alive(w) for w in workers) and time.monotonic() - killed < timeout:
        time.sleep(0.01)
    return time.monotonic() - killed, len(workers)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args(argv)
    if not sys.platform.startswith("linux"):
        print("reads /proc: Linux only")
        return 0
    rows = [one_round() for _ in range(args.rounds)]
    print("round  workers  seconds until no worker is left")
    for i, (seconds, n) in enumerate(rows, start=1):
        print(f"{i:>5}  {n:>7}  {seconds:8.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
