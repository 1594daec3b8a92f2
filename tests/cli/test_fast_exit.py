"""The ``shrm`` console script ends without the interpreter's teardown only when that is safe
(``cli/main.py``: ``fast_exit``): its output, exit code and ``atexit`` handlers are kept, and a
live thread or child process gets the ordinary exit."""

from __future__ import annotations

import os
import subprocess
import sys

#: wraps os._exit so that a run says whether it took the fast exit, then runs console_main
_HARNESS = """
import atexit, os, sys, threading, time
real = os._exit
def marked(code):
    out = sys.stderr or sys.stdout
    out.write("FAST-EXIT\\n"); out.flush(); real(code)
os._exit = marked
atexit.register(lambda: print("atexit ran", file=sys.stderr))
{setup}
sys.argv = ["shrm", *{argv!r}]
from shrmkit.cli.main import console_main
console_main()
"""


def _run(argv: list[str], setup: str = "") -> subprocess.CompletedProcess[str]:
    code = _HARNESS.format(setup=setup, argv=argv)
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)


def test_help_through_a_pipe_is_whole_and_atexit_handlers_run() -> None:
    proc = _run([])
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.startswith("usage: shrm") and "report" in proc.stdout
    assert proc.stdout.rstrip().splitlines()[-1].strip(), "the help's last line was lost"
    assert "atexit ran" in proc.stderr and "FAST-EXIT" in proc.stderr


def test_an_error_keeps_its_line_and_exit_code_2() -> None:
    proc = _run(["orders", "no-such-model:x=1"])
    assert proc.returncode == 2
    assert "shrm orders: error:" in proc.stderr and "no-such-model" in proc.stderr
    assert "atexit ran" in proc.stderr and "FAST-EXIT" in proc.stderr


def test_a_live_thread_gets_the_ordinary_exit() -> None:
    # a non-daemon thread still running when main returns: os._exit would kill it mid-work
    setup = ("threading.Thread(target=lambda: (time.sleep(0.5), print('thread finished', file=sys.stderr)))"
             ".start()")
    proc = _run([], setup=setup)
    assert proc.returncode == 0
    assert "thread finished" in proc.stderr and "atexit ran" in proc.stderr
    assert "FAST-EXIT" not in proc.stderr


def test_closed_stderr_keeps_the_exit_code() -> None:
    """stderr closed when the process started (``2>&-``: sys.stderr is None): an error still exits 2
    and a success 0 (flushing None raised AttributeError, and the exit code became 1)."""
    proc = _run(["orders", "no-such-model:x=1"], setup="sys.stderr = None")
    assert proc.returncode == 2 and "no-such-model" in proc.stdout and "FAST-EXIT" in proc.stdout
    assert _run([], setup="sys.stderr = None").returncode == 0



_BLAS = """
import os, sys
{env}
sys.argv = ["shrm", "orders", "lambert", "--json"]
from shrmkit.cli.main import console_main
import shrmkit.cli.main as m
real = m.main
def main():
    from threadpoolctl import threadpool_info
    code = real()
    blas = [p["num_threads"] for p in threadpool_info() if p["user_api"] == "blas"]
    print("BLAS", os.environ.get("OPENBLAS_NUM_THREADS"), blas, file=sys.stderr)
    return code
m.main = main
console_main()
"""


def test_console_script_gives_blas_one_thread_unless_the_user_set_it() -> None:
    def blas(env: str) -> str:
        proc = subprocess.run([sys.executable, "-c", _BLAS.format(env=env)], capture_output=True, text=True,
                              timeout=120, env={k: v for k, v in os.environ.items() if k != "OPENBLAS_NUM_THREADS"})
        assert proc.returncode == 0, proc.stderr
        return next(line for line in proc.stderr.splitlines() if line.startswith("BLAS"))

    assert blas("") == "BLAS 1 [1]"
    assert blas("os.environ['OPENBLAS_NUM_THREADS'] = '2'") == "BLAS 2 [2]"
