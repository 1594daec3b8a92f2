"""The `shrm` entry point across verbs: version, help, one-line errors with exit 2, and a lazy
command line (a verb's module, and the stack under it, is imported only when that verb runs)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from shrmkit.cli.main import _verbs, build_parser

#: imported by no `shrm --version` / `shrm --help`; VTK and friends by no `shrm VERB --help` either
STACK = ("scipy", "ducc0", "rich", "shrmkit.analysis", "shrmkit.render", "shrmkit.cli.report")
HEAVY = ("vtk", "vtkmodules", "pyvista", "matplotlib", "distributed")

#: runs main(argv) and prints, after its own output, the modules the process imported
_PROBE = (
    "import json, sys\n"
    "from shrmkit.cli.main import main\n"
    "try:\n"
    "    code = main(sys.argv[1:])\n"
    "except SystemExit as stop:\n"
    "    code = stop.code\n"
    "sys.stdout.flush()\n"
    "print('\\nMODULES ' + json.dumps([code, sorted(sys.modules)]))\n"
)


def run_cli(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "shrmkit.cli.main", *args], capture_output=True, text=True)


def imports_of(*args: str) -> tuple[int, str, set[str]]:
    """(exit code, stdout, modules imported) of `shrm ARGS` in a fresh interpreter."""
    proc = subprocess.run([sys.executable, "-c", _PROBE, *args], capture_output=True, text=True,
                          env={**os.environ, "COLUMNS": "200"})
    out, _, last = proc.stdout.rpartition("\nMODULES ")
    assert last, proc.stderr[-2000:]
    code, modules = json.loads(last)
    return code, out, set(modules)


def _loaded(modules: set[str], names: tuple[str, ...]) -> list[str]:
    return sorted(m for m in modules if any(m == n or m.startswith(n + ".") for n in names))


def _verb_modules(modules: set[str]) -> list[str]:
    """The verbs' modules imported: their parsers (``options_<verb>``) and their work (``cmd_<verb>``)."""
    return sorted(m for m in modules if m.startswith(("shrmkit.cli.cmd_", "shrmkit.cli.options_")))


def test_version_and_help(monkeypatch):
    """`--version` and `--help` import no verb and nothing of the analysis/render stack; the
    help lists every verb with its HELP line, exactly as the parser with every verb imported."""
    code, out, modules = imports_of("--version")
    assert code == 0 and out.startswith("shrm ")
    assert not _verb_modules(modules) and not _loaded(modules, STACK + HEAVY), _loaded(modules, STACK + HEAVY)
    code, out, modules = imports_of("--help")
    assert code == 0 and "orders" in out and "prefilter" in out
    assert not _verb_modules(modules) and not _loaded(modules, STACK + HEAVY), _loaded(modules, STACK + HEAVY)
    monkeypatch.setenv("COLUMNS", "200")
    assert out.strip() == build_parser().format_help().strip()
    assert all(f"    {verb} " in out for verb in _verbs())


def test_verb_help_imports_that_verb_only():
    """`shrm VERB --help` imports VERB's parser module only (not its work, nor the other verbs'), prints
    VERB's own options, and imports no VTK/matplotlib: `orders` not the render stack either."""
    code, out, modules = imports_of("orders", "--help")
    assert code == 0 and "--max-view-angle" in out and out.startswith("usage: shrm orders")
    assert _verb_modules(modules) == ["shrmkit.cli.options_orders"]
    assert not _loaded(modules, HEAVY + ("shrmkit.render", "shrmkit.cli.report")), _loaded(modules, HEAVY)
    code, out, modules = imports_of("render", "--help")
    assert code == 0 and "--turntable" in out and out.startswith("usage: shrm render")
    assert _verb_modules(modules) == ["shrmkit.cli.options_render"]
    assert not _loaded(modules, HEAVY), _loaded(modules, HEAVY)


def test_unknown_verb_is_a_usage_error():
    code, _, modules = imports_of("nosuch")
    assert code == 2 and not _verb_modules(modules)
    proc = run_cli("nosuch")
    assert proc.returncode == 2 and "invalid choice: 'nosuch'" in proc.stderr
    assert all(f"'{verb}'" in proc.stderr for verb in _verbs())


@pytest.mark.slow
def test_unwritable_outputs_exit_2_without_traceback(tmp_path, run_each):
    """Each command exits 2 with a one-line error, no traceback. They run in one fresh
    interpreter (conftest's ``run_each``: main(argv), what the ``shrm`` script calls), not five: 2 s of
    start-up and imports each."""
    cases = [
        ["prefilter", "--env", "builtin:sky,height=16", "--brdf", "phong:s=8", "-o", "/proc/x.shrm.npz"],
        ["fit", "phong:s=32", "--samples", "256", "--starts", "1", "-o", "/proc/x.json"],
        ["prefilter", "--env", "builtin:sky,height=16", "--brdf", "phong:s=8", "--cube-size", "8", "-o",
         str(tmp_path / "a.shrm.npz")],
        ["report", "phong:s=32", "--quick", "--env", str(tmp_path / "missing.exr"), "--out", str(tmp_path / "r")],
        ["orders", "phong:s=8", "--env", "builtin:sky", "--env-flip"],
    ]
    done = run_each(cases, timeout=600)
    for args, (code, stderr) in zip(cases, done, strict=True):
        assert code == 2, (args, stderr)
        assert "Traceback" not in stderr and stderr.startswith("shrm "), stderr
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize("argv, hint", [
    (["ordres", "phong:s=4"], "did you mean 'orders'?"),
    (["orders", "phong:s=4", "--epss", "0.1"], "did you mean '--epss' → '--eps'?"),
    (["report", "--env", "builtin:sky", "builtin:studio", "--quick"], "--env takes every value after it"),
    (["render", "--env", "builtin:sky", "builtin:sphere", "--brdf", "phong:s=3", "-o", "x.png"],
     "required: MESH (--env takes every value after it"),
])
def test_usage_errors_suggest_the_fix(argv, hint, capsys):
    from shrmkit.cli.main import main

    with pytest.raises(SystemExit) as stop:
        main(argv)
    err = capsys.readouterr().err
    assert stop.value.code == 2 and hint in err and "Traceback" not in err


@pytest.mark.parametrize("argv", [
    ["view", "phong:s=32"],  # -o missing, no --env given (issue 26: the hint named --env all the same)
    ["render", "builtin:sphere", "--brdf", "phong:s=32"],
    ["report", "--env=builtin:sky"],  # one value: nothing swallowed
    ["report", "--env", "builtin:sky", "--"],  # the list ended by --
])
def test_the_greedy_option_hint_only_when_it_could_have_swallowed_a_positional(argv, capsys):
    from shrmkit.cli.main import main

    with pytest.raises(SystemExit) as stop:
        main(argv)
    err = capsys.readouterr().err
    assert stop.value.code == 2 and "arguments are required" in err
    assert "takes every value" not in err and "--env" not in err.splitlines()[-1]


def test_end_of_a_greedy_list_keeps_the_positionals():
    from shrmkit.cli.main import build_parser

    args = build_parser().parse_args(["report", "--env", "builtin:sky", "builtin:studio", "--", "phong:s=4"])
    assert args.env == ["builtin:sky", "builtin:studio"] and args.brdfs == ["phong:s=4"]


def test_library_warnings_reach_the_user_as_one_line(capsys, monkeypatch):
    import warnings as warnings_module

    from shrmkit.cli import main as cli_main

    monkeypatch.setattr(warnings_module, "showwarning", warnings_module.showwarning)
    cli_main._one_line_warnings("orders")
    with warnings_module.catch_warnings():
        warnings_module.simplefilter("always")
        warnings_module.warn("a library's message\nover two lines", UserWarning, stacklevel=1)
    err = capsys.readouterr().err
    assert err == "shrm orders: warning: a library's message over two lines\n"


def test_quiet_prints_nothing_but_json_and_errors(capsys):
    from shrmkit.cli.main import main

    assert main(["orders", "phong:s=5", "--eps", "0.1", "--quiet"]) == 0
    assert capsys.readouterr().out == ""
    assert main(["orders", "phong:s=5", "--eps", "0.1", "-q", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["F"] >= 0
    assert main(["orders", "no-such-file.binary", "-q"]) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and "no-such-file.binary" in captured.err


def test_default_orientation_of_a_lat_long_file_is_never_silent(tmp_path, capsys):
    """A lat-long file read with the default (y-up, as panoramas in the wild) says so and how to
    change it (--env-up z reads it as stored); an explicit --env-up, built-ins and --json print no
    such line."""
    from shrmkit.cli.main import main

    hdr = str(Path(__file__).parents[1] / "resources" / "tiny_4x8.hdr")
    assert main(["prefilter", "--env", hdr, "--brdf", "phong:s=8", "--eps", "0.1", "-o", str(tmp_path / "a.npz")]) == 0
    out = capsys.readouterr().out
    assert out.startswith("environment tiny_4x8: a lat-long file read y-up") and "--env-up z" in out
    assert main(["prefilter", "--env", hdr, "--env-up", "z", "--brdf", "phong:s=8", "--eps", "0.1",
                 "-o", str(tmp_path / "b.npz")]) == 0
    assert "read y-up" not in capsys.readouterr().out
    assert main(["prefilter", "--env", hdr, "--brdf", "phong:s=8", "--eps", "0.1", "--json",
                 "-o", str(tmp_path / "c.npz")]) == 0
    json.loads(capsys.readouterr().out)  # the JSON alone


def test_the_orientation_note_offers_only_the_options_not_given_and_one_line_per_sequence(tmp_path, capsys):
    """--env-flip given: the note says the rows were flipped and does not offer --env-flip again
    (issue 26); a folder of maps (a sequence) gets one note naming how many files, not one per map."""
    import argparse
    import shutil

    from shrmkit.cli.common import load_env_sequence, orientation_note
    from shrmkit.cli.main import build_parser

    hdr = Path(__file__).parents[1] / "resources" / "tiny_4x8.hdr"
    for k in range(3):
        shutil.copy(hdr, tmp_path / f"frame_{k}.hdr")
    args = build_parser().parse_args(["render", "builtin:sphere", "--env", str(tmp_path), "--env-flip",
                                      "--brdf", "phong:s=8", "-o", "x.png"])
    assert load_env_sequence([str(p) for p in sorted(tmp_path.iterdir())], args)
    out = capsys.readouterr().out.splitlines()
    assert len(out) == 1 and out[0].startswith("environments: 3 lat-long files (frame_0 … frame_2) read y-up, "
                                               "rows flipped (--env-flip)")
    assert "--env-up z reads them" in out[0] and "--env-flip turns" not in out[0]
    env = load_env_sequence([str(hdr)], args)[0]
    single = capsys.readouterr().out.splitlines()
    assert single == [orientation_note(env, args)] and "--env-flip turns" not in single[0]
    turned = argparse.Namespace(env_up=None, env_flip=False, env_azimuth=30.0)
    note = orientation_note(env, turned)
    assert "turned 30 deg" in note and "--env-flip turns it upside down" in note and "--env-azimuth DEG" not in note


def test_report_states_the_default_orientation_of_its_map_files(capsys):
    """shrm report checks its maps once before the batch and, like every verb, names the y-up
    reading of a lat-long file (not with --json, nor for an explicit --env-up)."""
    from shrmkit.cli.cmd_report import _check_shared_inputs
    from shrmkit.cli.report.options import profile

    hdr = str(Path(__file__).parents[1] / "resources" / "tiny_4x8.hdr")
    _check_shared_inputs(profile("quick", envs=(hdr, "builtin:sky")), show=True)
    out = capsys.readouterr().out.splitlines()
    assert len(out) == 1 and out[0].startswith("environment tiny_4x8: a lat-long file read y-up")
    _check_shared_inputs(profile("quick", envs=(hdr, "builtin:sky", hdr)), show=True)
    out = capsys.readouterr().out.splitlines()
    assert len(out) == 1 and out[0].startswith("environments: 2 of 3 lat-long files (tiny_4x8, tiny_4x8) read y-up")
    _check_shared_inputs(profile("quick", envs=(hdr,)), show=False)
    _check_shared_inputs(profile("quick", envs=(hdr,), env_up="z"), show=True)
    assert capsys.readouterr().out == ""


@pytest.mark.parametrize("argv", [
    ["prefilter", "--env", "builtin:sky,height=16", "--brdf", "phong:s=8", "--eps", "0.1", "-o", "{tmp}/a.shrm.npz"],
    ["orders", "phong:s=8", "--eps", "0.1"],
])
def test_quiet_silences_progress_too(argv, tmp_path, capsys, monkeypatch):
    """-q: no spinner frame on stderr (issue 26: shrm prefilter … -q 2>log wrote "⠦ prefiltering …");
    the same command without -q draws one on a terminal (the check can fail)."""
    import io

    from shrmkit.cli.common import stderr
    from shrmkit.cli.main import main

    argv = [a.replace("{tmp}", str(tmp_path)) for a in argv]
    terminal = io.StringIO()
    monkeypatch.setattr(stderr, "_force_terminal", True)
    monkeypatch.setattr(stderr, "_file", terminal)
    assert main(argv) == 0
    assert terminal.getvalue().strip(), "the spinner is drawn without -q"
    terminal.seek(0)
    terminal.truncate()
    assert main([*argv, "-q"]) == 0
    assert terminal.getvalue() == "" and capsys.readouterr().err == ""
