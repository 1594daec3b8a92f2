"""Start-up time of the command line (issue 26): ``shrm --help``, ``shrm --version`` and usage
errors should cost at most 0.3 s CPU on a quiet core (the parser is built without importing the
verbs; only the chosen verb's module is imported, ``cli/main.py``).

Each command runs in a fresh process, ``--rounds`` times, the commands interleaved round by
round so that a change of machine load hits them alike. The time is the child's CPU time (user +
sys, from ``os.wait4``), which on a shared machine moves far less than the wall time (also
given). Two references bracket the figures: the interpreter alone (``python -c pass``) and
``python -c "import numpy"`` (the issue measured the old start-up as 12× that).

To compare with an older checkout, run this script with ``PYTHONPATH`` pointing at a folder that
holds it as ``shrmkit`` (the commands run ``shrmkit.cli.main`` through ``sys.executable``, as the
``shrm`` console script does).

Usage::

    python benchmarks/startup.py --rounds 7
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import time

#: what the ``shrm`` console script runs (pyproject ``[project.scripts]``)
SHRM = [sys.executable, "-c", "import sys; from shrmkit.cli.main import main; sys.exit(main())"]

#: (label, argv, expected exit status, held to the target)
COMMANDS = [
    ("python -c pass", [sys.executable, "-c", "pass"], 0, False),
    ("python -c 'import numpy'", [sys.executable, "-c", "import numpy"], 0, False),
    ("shrm --version", [*SHRM, "--version"], 0, True),
    ("shrm --help", [*SHRM, "--help"], 0, True),
    ("shrm ordres (misspelt verb)", [*SHRM, "ordres", "phong:s=4"], 2, True),
    ("shrm orders (no BRDF)", [*SHRM, "orders"], 2, True),
    ("shrm orders --epss 0.1 (bad option)", [*SHRM, "orders", "phong:s=4", "--epss", "0.1"], 2, True),
    ("shrm report --help", [*SHRM, "report", "--help"], 0, False),
]


def run_once(argv: list[str]) -> tuple[float, float, int]:
    """(CPU seconds user + sys of the child, wall seconds, exit status) of one fresh process."""
    t0 = time.perf_counter()
    proc = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - t0
    proc.returncode = os.waitstatus_to_exitcode(status)
    return usage.ru_utime + usage.ru_stime, wall, proc.returncode


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=7, help="runs of each command (default 7)")
    parser.add_argument("--target", type=float, default=0.3, help="CPU seconds a start-up may cost (default 0.3)")
    args = parser.parse_args()
    if args.rounds < 1:
        parser.error("--rounds must be at least 1")
    cpu: dict[str, list[float]] = {label: [] for label, *_ in COMMANDS}
    wall: dict[str, list[float]] = {label: [] for label, *_ in COMMANDS}
    for label, argv, expected, _ in COMMANDS:  # one warm-up run each (the OS file cache, .pyc files)
        code = run_once(argv)[2]
        if code != expected:
            print(f"error: {label} exited {code}, expected {expected}", file=sys.stderr)
            return 1
    for _ in range(args.rounds):
        for label, argv, _, _ in COMMANDS:
            c, w, _ = run_once(argv)
            cpu[label].append(c)
            wall[label].append(w)
    load = os.getloadavg()[0]
    print(f"start-up, {args.rounds} rounds interleaved, {os.cpu_count()} CPUs, load average {load:.1f}; "
          f"CPU = user + sys of the process")
    print()
    print(f"| command | CPU median (s) | CPU min (s) | wall median (s) | target {args.target:g} s CPU |")
    print("|---|---|---|---|---|")
    failed = 0
    for label, _, _, held in COMMANDS:
        median = statistics.median(cpu[label])
        verdict = ("met" if median <= args.target else "NOT met") if held else "(reference)"
        failed += held and median > args.target
        print(f"| `{label}` | {median:.3f} | {min(cpu[label]):.3f} | {statistics.median(wall[label]):.3f} | "
              f"{verdict} |")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
