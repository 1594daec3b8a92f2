"""`shrm prefilter`: a loadable SHRM file, bad input exits 2 with no file left behind."""

from __future__ import annotations

import subprocess
import sys

import shrmkit
from shrmkit.cli.main import main


def run_cli(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "shrmkit.cli.main", *args], capture_output=True, text=True)


def test_prefilter_writes_loadable_file(tmp_path, capsys):


    out = tmp_path / "m.shrm.npz"
    assert main(["prefilter", "--env", "builtin:sky,height=32", "--brdf", "phong:s=16", "-o", str(out)]) == 0
    m = shrmkit.load_shrm(out)
    assert m.P == 0 and m.F > 0
    assert "wrote" in capsys.readouterr().out


def test_prefilter_bad_input_leaves_no_file(tmp_path):
    out = tmp_path / "bad.shrm.npz"
    proc = run_cli("prefilter", "--env", str(tmp_path / "missing.exr"), "--brdf", "phong:s=8", "-o", str(out))
    assert proc.returncode == 2 and "missing.exr" in proc.stderr
    proc = run_cli("prefilter", "--env", "builtin:sky", "--brdf", "lambert:albedo=0", "-o", str(out))
    assert proc.returncode == 2 and "zero everywhere" in proc.stderr
    assert not out.exists() and not list(tmp_path.iterdir())


def test_prefilter_eps_is_validated_by_the_one_rule(tmp_path, capsys):
    """--eps outside (0, 1) is a usage error (exit 2) with check_eps's message; no file is written."""
    out = tmp_path / "m.shrm.npz"
    proc = run_cli("prefilter", "--env", "builtin:sky,height=16", "--brdf", "phong:s=8", "--eps", "1.5", "-o", str(out))
    assert proc.returncode == 2 and "eps must be in (0, 1), got 1.5" in proc.stderr
    assert not out.exists()
