"""The command line's start-up (issue 26: <= 0.3 s CPU, benchmarks/startup.py; numpy alone costs about that):
``--help``, ``--version``, a misspelt verb, and every verb's ``--help`` and usage errors import no numpy, scipy,
matplotlib or VTK. The verbs' parsers are built from numpy-free modules (``cli/options*.py`` over
``brdf_io.names``, ``analysis.defaults``, ``render.defaults``), whose names and defaults must be the registries'."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from shrmkit.brdf_io.errors import BadInputError
from shrmkit.cli.main import _verbs

HEAVY = ("numpy", "scipy", "matplotlib", "vtkmodules", "vtk", "pyvista")

#: runs main(argv) for each argv of sys.argv[1] (a repr'd list) in this one interpreter, prints each exit
#: status, then the heavy modules imported by all of them together
_PROBE = (
    "import ast, contextlib, io, sys\n"
    "from shrmkit.cli.main import main\n"
    "codes = []\n"
    "for argv in ast.literal_eval(sys.argv[1]):\n"
    "    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):\n"
    "        try:\n"
    "            codes.append(main(argv))\n"
    "        except SystemExit as stop:\n"
    "            codes.append(stop.code)\n"
    f"print(codes, sorted(m for m in {HEAVY!r} if m in sys.modules))\n"
)


def _imports(cases: list[list[str]]) -> tuple[list[int], list[str]]:
    out = subprocess.run([sys.executable, "-c", _PROBE, repr(cases)], capture_output=True, text=True, check=True)
    codes, heavy = out.stdout.strip().split("] [")
    return [int(c) for c in codes.strip("[]").split(",")], [h.strip(" '") for h in heavy.strip("[]").split(",") if h]


@pytest.mark.parametrize("argv", [["--version"], ["--help"], ["ordres"]])
def test_startup_imports_no_numpy(argv):
    codes, heavy = _imports([argv])
    assert heavy == [] and codes == [2 if argv == ["ordres"] else 0]


def test_every_verbs_help_and_usage_errors_import_no_numpy():
    """Each verb's ``--help`` (exit 0), an unknown option, a missing argument and bad values (exit 2), all in
    one interpreter: none of them imports the numerical stack (before: every verb's module imported it to
    build its parser, ~1.4 s CPU)."""
    verbs = _verbs()
    assert len(verbs) >= 11
    cases = [[verb, "--help"] for verb in verbs] + [[verb, "--no-such-option"] for verb in verbs]
    cases += [["orders"], ["prefilter", "--env", "builtin:sky"], ["orders", "x", "--eps", "2"],
              ["render", "x", "--lights", "99", "-o", "a.png"], ["report", "x", "--window", "nope"],
              ["fit", "x", "--model", "nope"], ["export", "x", "-o", "y", "--to", "nope"],
              ["census", "x", "--candidates", "nope"], ["compare", "x", "--env", "e", "--elevations", "999"],
              ["view", "x", "-o", "y.html", "--zoom", "99"]]
    codes, heavy = _imports(cases)
    assert heavy == []
    assert codes == [0] * len(verbs) + [2] * (len(cases) - len(verbs))


def test_the_light_names_are_the_registries():
    """What the parsers show (``brdf_io.names``, ``analysis.defaults``, ``render.defaults``) is what the
    registries and the option records hold."""
    from shrmkit.analysis import census, defaults, lights, orders, view_bands, window
    from shrmkit.analysis.baselines.methods import GAUSSIAN_ELEVATIONS, GAUSSIAN_LOBES, RSIBR_REFERENCE_HEIGHT
    from shrmkit.analysis.compare import CompareOptions
    from shrmkit.analysis.fit import crossval, metrics, models_param, representation, zernike
    from shrmkit.analysis.prefiltered_cube import MAX_FACE_SIZE
    from shrmkit.brdf_io import display, names
    from shrmkit.brdf_io.dds import DDS_FORMATS
    from shrmkit.brdf_io.export_formats import EXPORT_FORMATS
    from shrmkit.brdf_io.rgl import RGL_INCIDENT
    from shrmkit.brdf_io.specs import BRDF_FILE_TYPES
    from shrmkit.render import defaults as render_defaults
    from shrmkit.render import error_image, modes, pipeline, webgl_page

    assert names.BRDF_FILE_SUFFIXES == tuple(BRDF_FILE_TYPES)
    assert names.BRDF_SELECTOR_SUFFIXES == tuple(s for s, kind in BRDF_FILE_TYPES.items() if kind.selector)
    assert names.BRDF_MEMBER_SUFFIXES == tuple(s for s, kind in BRDF_FILE_TYPES.items() if kind.members)
    assert names.RGL_INCIDENT_NAMES == tuple(RGL_INCIDENT)
    assert names.EXPORT_FORMAT_SUFFIXES == {name: f.suffix for name, f in EXPORT_FORMATS.items()}
    assert list(names.EXPORT_FORMAT_SUFFIXES) == list(EXPORT_FORMATS)
    assert names.DDS_FORMAT_NAMES == tuple(DDS_FORMATS)
    assert names.TONE_MAP_NAMES == display.TONE_MAPS

    assert (defaults.DEFAULT_MAX_F, defaults.DEFAULT_MAX_P) == (orders.DEFAULT_MAX_F, orders.DEFAULT_MAX_P)
    assert (defaults.WINDOWS, defaults.DEFAULT_WINDOW, defaults.WINDOW_THRESHOLD, defaults.WINDOW_BUDGET_EPS) == (
        window.WINDOWS, window.DEFAULT_WINDOW, window.WINDOW_THRESHOLD, window.WINDOW_BUDGET_EPS)
    assert (defaults.LIGHT_MODES, defaults.DEFAULT_LIGHTS, defaults.LIGHT_CONTRAST, defaults.MAX_LIGHT_RADIUS_DEG,
            defaults.MAX_LIGHTS) == (lights.LIGHT_MODES, lights.DEFAULT_LIGHTS, lights.LIGHT_CONTRAST,
                                     lights.MAX_LIGHT_RADIUS_DEG, lights.MAX_LIGHTS)
    # the one validator, numpy-free (numbers.Integral where it tested int | np.integer): what it accepted before
    assert lights.check_lights is defaults.check_lights
    accepted = {"auto": "auto", " None ": "none", "3": 3, "0": "none", "8": 8, 2: 2, 0: "none", np.int64(4): 4}
    assert {value: defaults.check_lights(value) for value in accepted} == accepted
    for value in ("9", "-1", "x", "", 9, -1, True, np.int64(9), 2.0, None):
        with pytest.raises(BadInputError, match="choose auto, none or a number of lights 0..8"):
            defaults.check_lights(value)
    assert (defaults.CRITERIA, defaults.DEFAULT_CRITERION, defaults.DEFAULT_MAX_VIEW_DEG) == (
        view_bands.CRITERIA, view_bands.DEFAULT_CRITERION, view_bands.DEFAULT_MAX_VIEW_DEG)
    assert names.ZERNIKE_MAX_ORDER == zernike.MAX_ORDER
    assert (defaults.FIT_MODELS, defaults.FIT_METRICS, defaults.DEFAULT_FOLDS, defaults.REPRESENTATION_CANDIDATES) == (
        models_param.MODELS, metrics.METRICS, crossval.DEFAULT_FOLDS, representation.CANDIDATES)
    assert (defaults.CENSUS_F, defaults.CENSUS_P, defaults.CENSUS_THRESHOLD, defaults.CENSUS_MAX_F_LIMIT,
            defaults.CENSUS_MAX_P_LIMIT, defaults.CENSUS_MAX_WORKERS) == (
        census.DEFAULT_F, census.DEFAULT_P, census.DEFAULT_THRESHOLD, census.MAX_F_LIMIT, census.MAX_P_LIMIT,
        census.MAX_WORKERS)
    compare = CompareOptions()
    assert defaults.COMPARE_DEFAULTS == {key: getattr(compare, key) for key in defaults.COMPARE_DEFAULTS}
    for limits, setting in ((defaults.GAUSSIAN_LOBES_LIMITS, GAUSSIAN_LOBES),
                            (defaults.GAUSSIAN_ELEVATIONS_LIMITS, GAUSSIAN_ELEVATIONS),
                            (defaults.RSIBR_REFERENCE_HEIGHT_LIMITS, RSIBR_REFERENCE_HEIGHT)):
        assert limits == (setting.default, setting.lo, setting.hi)
    assert defaults.MAX_CUBE_FACE_SIZE == MAX_FACE_SIZE

    rd = render_defaults
    assert rd.RENDER_MODE_HELP == {m.name: m.help for m in modes.RENDER_MODES.values()}
    assert (rd.DEFAULT_MODE, rd.SELF_SHADOW_MODES) == (modes.DEFAULT_MODE, modes.self_shadow_modes())
    assert rd.LOBE_OPTION_MODES == tuple(
        m.name for m in modes.RENDER_MODES.values() if m.published is not None
        and {s.name for s in m.published.settings} >= {"lobes", "elevations"})
    options = modes.RenderOptions()
    assert (options.lobes, options.elevations) == (GAUSSIAN_LOBES.default, GAUSSIAN_ELEVATIONS.default)
    assert (rd.BACKGROUNDS, rd.ERROR_IMAGE_HELP) == (pipeline.BACKGROUNDS, error_image.ERROR_IMAGE_HELP)
    assert (rd.VIEW_MODES, rd.DEFAULT_VIEW_MESH, rd.DEFAULT_VIEW, rd.STILL_RENDERERS, rd.DEFAULT_PAGE_BYTES) == (
        webgl_page.VIEW_MODES, webgl_page.DEFAULT_MESH, webgl_page.DEFAULT_VIEW, webgl_page.STILL_RENDERERS,
        webgl_page.ViewBudget().page_bytes)



def test_env_up_help_names_the_default_load_env_applies():
    """``--env-up``'s help names the orientation a lat-long file is read with when it is not given."""
    from pathlib import Path

    from shrmkit.brdf_io.envmap import load_env
    from shrmkit.cli.main import build_parser

    env = load_env(Path(__file__).parents[1] / "resources" / "tiny_4x8.hdr")
    default = "y" if "[latlong, up=y" in env.source else "z"
    orders = build_parser()._subparsers._group_actions[0].choices["orders"]
    up = next(a for a in orders._actions if "--env-up" in a.option_strings)
    assert up.default is None and up.help.startswith(f"lat-long file convention: {default} (default")
