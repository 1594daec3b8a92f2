"""Start-up time of the command line (issue 26): ``shrm --help``, ``shrm --version``, a misspelt
verb, and every verb's ``--help`` and usage errors should cost at most 0.3 s CPU on a quiet core.
The top-level parser is built without importing the verbs (``cli/main.py``); a verb's parser is
built from numpy-free modules (``cli/options*.py`` over ``brdf_io.names``, ``analysis.defaults``,
``render.defaults``), and its work (``cli/cmd_<verb>.py``, the numerical stack) is imported only
when it runs. A bad *value* (``--eps 2``) is held to the target as well.

Each command runs in a fresh process, ``--rounds`` times, the commands interleaved round by
round so that a change of machine load hits them alike. The time is the child's CPU time (user +
sys, from ``os.wait4``), which on a shared machine moves far less than the wall time (also
given). Two references bracket the figures: the interpreter alone (``python -c pass``) and
``python -c "import numpy"`` (the issue measured the old start-up as 12× that).

``--old DIR``: also run every ``shrm`` command with ``PYTHONPATH=DIR``, where ``DIR`` holds an
older checkout as ``shrmkit`` (e.g. ``git worktree add /tmp/old REV; mkdir /tmp/oldpkg; ln -s
/tmp/old /tmp/oldpkg/shrmkit``), interleaved with the current ones, and print its median beside.
The commands run ``shrmkit.cli.main`` through ``sys.executable``, as the ``shrm`` console script
does.

Usage::

    python benchmarks/startup.py --rounds 7 [--old /tmp/oldpkg]
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

#: what the ``shrm`` console script runs (pyproject ``[project.scripts]``)
#: the console script's code (``console_main``; an older checkout without it: ``main``)
SHRM = [sys.executable, "-c", "import sys; from shrmkit.cli import main as m; "
        "sys.exit(m.console_main() if hasattr(m, 'console_main') else m.main())"]

#: (label, argv, expected exit status, held to the target)
COMMANDS = [
    ("python -c pass", [sys.executable, "-c", "pass"], 0, False),
    ("python -c 'import numpy'", [sys.executable, "-c", "import numpy"], 0, False),
    ("shrm --version", [*SHRM, "--version"], 0, True),
    ("shrm --help", [*SHRM, "--help"], 0, True),
    ("shrm ordres (misspelt verb)", [*SHRM, "ordres", "phong:s=4"], 2, True),
    ("shrm orders --help", [*SHRM, "orders", "--help"], 0, True),
    ("shrm orders (no BRDF)", [*SHRM, "orders"], 2, True),
    ("shrm orders --epss 0.1 (bad option)", [*SHRM, "orders", "phong:s=4", "--epss", "0.1"], 2, True),
    ("shrm prefilter --eps 2 (bad value)",
     [*SHRM, "prefilter", "--env", "builtin:sky", "--brdf", "phong:s=4", "-o", "x.shrm.npz", "--eps", "2"], 2, True),
    ("shrm render --help", [*SHRM, "render", "--help"], 0, True),
    ("shrm render (no MESH)", [*SHRM, "render", "-o", "x.png"], 2, True),
    ("shrm report --help", [*SHRM, "report", "--help"], 0, True),
    ("shrm report --bogus (bad option)", [*SHRM, "report", "phong:s=4", "--bogus"], 2, True),
    ("shrm view --help", [*SHRM, "view", "--help"], 0, True),
    ("shrm export --to nope (bad choice)", [*SHRM, "export", "phong:s=4", "-o", "x.xml", "--to", "nope"], 2, True),
    ("shrm fit --help", [*SHRM, "fit", "--help"], 0, True),
    ("shrm census --help", [*SHRM, "census", "--help"], 0, True),
    ("shrm compare --help", [*SHRM, "compare", "--help"], 0, True),
]


def run_once(argv: list[str], env: dict[str, str] | None = None) -> tuple[float, float, int]:
    """(CPU seconds user + sys of the child, wall seconds, exit status) of one fresh process."""
    t0 = time.perf_counter()
    proc = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env)
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - t0
    proc.returncode = os.waitstatus_to_exitcode(status)
    return usage.ru_utime + usage.ru_stime, wall, proc.returncode


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=7, help="runs of each command (default 7)")
    parser.add_argument("--target", type=float, default=0.3, help="CPU seconds a start-up may cost (default 0.3)")
    parser.add_argument("--old", default=None, metavar="DIR",
                        help="also run the shrm commands with PYTHONPATH=DIR (a folder holding an older checkout "
                        "as shrmkit), interleaved, and print its median beside")
    args = parser.parse_args()
    if args.rounds < 1:
        parser.error("--rounds must be at least 1")
    if args.old is not None and not (Path(args.old) / "shrmkit" / "cli" / "main.py").is_file():
        parser.error(f"--old {args.old}: no shrmkit/cli/main.py in it")
    old_env = None if args.old is None else {**os.environ, "PYTHONPATH": args.old}
    # (label, argv, expected status, held, env, which) for every run: the current code and, with --old, the old
    runs = [(label, argv, expected, held, None, "new") for label, argv, expected, held in COMMANDS]
    if old_env is not None:
        runs += [(label, argv, expected, held, old_env, "old") for label, argv, expected, held in COMMANDS
                 if argv[:len(SHRM)] == SHRM]
    cpu: dict[tuple[str, str], list[float]] = {(label, which): [] for label, *_, which in runs}
    wall: dict[tuple[str, str], list[float]] = {(label, which): [] for label, *_, which in runs}
    with tempfile.TemporaryDirectory() as folder:  # outputs a command might name are never written here
        cwd = os.getcwd()
        os.chdir(folder)
        try:
            for label, argv, expected, _, env, which in runs:  # one warm-up run each (file cache, .pyc files)
                code = run_once(argv, env)[2]
                if code != expected:
                    print(f"error: {label} ({which}) exited {code}, expected {expected}", file=sys.stderr)
                    return 1
            for _ in range(args.rounds):
                for label, argv, _, _, env, which in runs:
                    c, w, _ = run_once(argv, env)
                    cpu[label, which].append(c)
                    wall[label, which].append(w)
        finally:
            os.chdir(cwd)
    load = os.getloadavg()[0]
    print(f"start-up, {args.rounds} rounds interleaved, {os.cpu_count()} CPUs, load average {load:.1f}; "
          f"CPU = user + sys of the process")
    print()
    old_head = " old CPU median (s) |" if old_env is not None else ""
    print(f"| command | CPU median (s) | CPU min (s) | wall median (s) |{old_head} target {args.target:g} s CPU |")
    print("|---|---|---|---|" + ("---|" if old_env is not None else "") + "---|")
    failed = 0
    for label, _, _, held in COMMANDS:
        median = statistics.median(cpu[label, "new"])
        verdict = ("met" if median <= args.target else "NOT met") if held else "(reference)"
        failed += held and median > args.target
        old = ""
        if old_env is not None:
            old = f" {statistics.median(cpu[label, 'old']):.3f} |" if (label, "old") in cpu else " |"
        print(f"| `{label}` | {median:.3f} | {min(cpu[label, 'new']):.3f} | "
              f"{statistics.median(wall[label, 'new']):.3f} |{old} {verdict} |")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
