"""The `shrm` entry point across verbs: version, help, one-line errors with exit 2."""

from __future__ import annotations

import subprocess
import sys


def run_cli(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "shrmkit.cli.main", *args], capture_output=True, text=True)


def test_version_and_help(capsys):
    proc = run_cli("--version")
    assert proc.returncode == 0 and proc.stdout.startswith("shrm ")
    proc = run_cli("--help")
    assert proc.returncode == 0 and "orders" in proc.stdout and "prefilter" in proc.stdout


def test_unwritable_outputs_exit_2_without_traceback(tmp_path):
    for args in (
        ["prefilter", "--env", "builtin:sky,height=16", "--brdf", "phong:s=8", "-o", "/proc/x.shrm.npz"],
        ["fit", "phong:s=32", "--samples", "256", "--starts", "1", "-o", "/proc/x.json"],
        ["prefilter", "--env", "builtin:sky,height=16", "--brdf", "phong:s=8", "--cube-size", "8", "-o",
         str(tmp_path / "a.shrm.npz")],
        ["report", "phong:s=32", "--quick", "--env", str(tmp_path / "missing.exr"), "--out", str(tmp_path / "r")],
        ["orders", "phong:s=8", "--env", "builtin:sky", "--env-flip"],
    ):
        proc = run_cli(*args)
        assert proc.returncode == 2, (args, proc.stderr)
        assert "Traceback" not in proc.stderr and proc.stderr.startswith("shrm "), proc.stderr
    assert not list(tmp_path.iterdir())
