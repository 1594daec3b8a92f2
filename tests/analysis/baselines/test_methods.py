"""The table of published methods (analysis.baselines.methods) and the two layers that wrap it.

References: the bibliography page (every cite key is defined there); the render-mode table and the
comparison's registry, whose builders must give the same model as the table's function for the same
settings (bitwise: Kautz–McCool's coefficients, the Gaussian lobes); an independent ``prefilter`` call
on the SHRM's (F, P) and rows for Kautz–McCool; the earlier names (each must resolve, with a warning).
"""

from __future__ import annotations

import dataclasses
import re
import warnings
from pathlib import Path

import numpy as np
import pytest

from shrmkit.analysis.baselines import methods
from shrmkit.analysis.baselines.methods import (
    GAUSSIAN_ELEVATIONS,
    GAUSSIAN_LOBES,
    METHODS,
    get_method,
    method_key,
)
from shrmkit.analysis.compare import REGISTRY, BuildContext, CompareOptions
from shrmkit.analysis.compare.green_lobes import build_green_lobes
from shrmkit.analysis.compare.registry import deprecated_row_key
from shrmkit.analysis.compare.shrm_kinds import build_kautz_mccool
from shrmkit.analysis.shrm import prefilter
from shrmkit.analysis.tolerance import DEFAULT_EPS
from shrmkit.brdf_io.envmap import load_env
from shrmkit.brdf_io.errors import BadInputError
from shrmkit.brdf_io.specs import load_brdf
from shrmkit.cli import cmd_compare
from shrmkit.cli.cmd_render import LOBE_OPTION_MODES
from shrmkit.cli.main import build_parser
from shrmkit.render.modes import RENDER_MODES, RenderOptions

ROOT = Path(__file__).resolve().parents[3]
ENV = "builtin:studio,height=16"


def test_table_rows_cite_the_bibliography_and_hold_their_defaults() -> None:
    bibliography = (ROOT / "data_specs" / "bibliography.md").read_text(encoding="utf-8")
    defined = set(re.findall(r"^\| \[([A-Za-z0-9]+)\] \|", bibliography, flags=re.M))
    assert list(METHODS) == ["shrm", "kautz_mccool", "rsibr", "gaussian_lobes"]
    for key, method in METHODS.items():
        assert method.key == key and method.key.isidentifier() and method.name and method.summary
        assert method.cite in defined, method.cite
        assert method.label() == f"{method.name} [{method.cite}]"
        for setting in method.settings:
            assert setting.lo <= setting.default <= setting.hi and method.setting(setting.name) is setting
            assert setting.check(setting.lo) == setting.lo and setting.check(setting.hi) == setting.hi
            for bad in (setting.lo - 1, setting.hi + 1, float(setting.default), True):
                with pytest.raises(BadInputError, match=f"{setting.name} must be an integer in"):
                    setting.check(bad)


def test_names_spellings_and_earlier_names() -> None:
    """A key, its CLI spelling and case resolve silently; each earlier name resolves with one
    DeprecationWarning naming the key; anything else is refused naming the keys."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert method_key("kautz-mccool") == "kautz_mccool" and get_method("Gaussian-Lobes").key == "gaussian_lobes"
    for old, new in (("cabral", "rsibr"), ("cabral_shrm", "rsibr"), ("gaussian", "gaussian_lobes"),
                     ("green", "gaussian_lobes")):
        with pytest.warns(DeprecationWarning, match=f"'{old}' is deprecated: use '{new}'"):
            assert get_method(old) is METHODS[new]
    with pytest.raises(BadInputError, match="unknown method 'phong'; known: shrm, kautz_mccool, rsibr"):
        get_method("phong")


def test_render_and_compare_take_names_and_limits_from_the_table() -> None:
    """Every render mode draws a method of the table; the lobe options belong to the modes whose
    method has them; RenderOptions, CompareOptions and both CLIs use the table's limits (the
    elevations' limits were 1-90 in render and 2-64 in compare before the table)."""
    assert {m.name: m.method for m in RENDER_MODES.values()} == {
        "distant": "shrm", "perpixel": "shrm", "rsibr": "rsibr", "kautz-mccool": "kautz_mccool",
        "gaussian-lobes": "gaussian_lobes"}
    assert LOBE_OPTION_MODES == ("gaussian-lobes",)
    assert set(REGISTRY) >= {"shrm", "kautz_mccool", "rsibr", "gaussian_lobes"}
    defaults = RenderOptions()
    assert (defaults.lobes, defaults.elevations) == (GAUSSIAN_LOBES.default, GAUSSIAN_ELEVATIONS.default)
    assert CompareOptions().elevations == GAUSSIAN_ELEVATIONS.default
    for build in (lambda n: RenderOptions(elevations=n), lambda n: CompareOptions(elevations=n)):
        for bad in (GAUSSIAN_ELEVATIONS.lo - 1, GAUSSIAN_ELEVATIONS.hi + 1):
            with pytest.raises(BadInputError, match=r"elevations must be an integer in \[1, 64\]"):
                build(bad)
        assert build(1).elevations == 1 and build(64).elevations == 64
    parser = build_parser()
    assert parser.parse_args(["render", "builtin:sphere", "-o", "x.png", "--elevations", "64"]).elevations == 64
    assert parser.parse_args(["compare", "phong:s=8", "--env", ENV, "--elevations", "1"]).elevations == 1
    with pytest.raises(SystemExit):
        parser.parse_args(["compare", "phong:s=8", "--env", ENV, "--elevations", "65"])


def test_earlier_compare_names_still_work() -> None:
    """CompareOptions(n_elevations=, cabral_reference_height=), REGISTRY["cabral_shrm"] and
    ``--cabral-reference-height`` keep working with one deprecation note each; rows whose key
    changed carry the earlier key."""
    with pytest.warns(DeprecationWarning, match="n_elevations"):
        options = CompareOptions(n_elevations=4)
    assert options.elevations == 4 and dataclasses.replace(options, lobes=(2,)).elevations == 4
    with pytest.warns(DeprecationWarning, match="cabral_reference_height"):
        assert CompareOptions(cabral_reference_height=8).rsibr_reference_height == 8
    with pytest.warns(DeprecationWarning, match="use elevations"):
        assert options.n_elevations == 4
    with pytest.raises(TypeError, match="not both"), warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        CompareOptions(elevations=3, n_elevations=4)
    with pytest.raises(TypeError, match="unexpected keyword argument"):
        CompareOptions(bogus=1)
    with pytest.warns(DeprecationWarning, match="'cabral_shrm' is deprecated: use 'rsibr'"):
        assert REGISTRY["cabral_shrm"] is REGISTRY["rsibr"]
    assert deprecated_row_key("rsibr") == {"deprecated_key": "cabral_shrm"}
    assert deprecated_row_key("gaussian_lobes_k3") == {"deprecated_key": "gaussian_k3"}
    assert deprecated_row_key("shrm") == {} and deprecated_row_key("kautz_mccool") == {}
    args = build_parser().parse_args(["compare", "phong:s=8", "--env", ENV, "--cabral-reference-height", "0"])
    assert args.rsibr_reference_height == 0
    assert args.deprecation_notes == ["--cabral-reference-height is deprecated: use --rsibr-reference-height"]
    assert cmd_compare._options(args).rsibr_reference_height is None


def test_kautz_mccool_is_one_model_in_render_and_compare() -> None:
    """[KM00] on the SHRM's (F, P) and map rows, the table's setting: render's build (SHRM and
    Kautz–McCool made in one call) and compare's row (``prefilter`` on the grid of an SHRM made
    here) give the same coefficients. Before the table, render chose its own orders and rows: here
    F 15 on 54 rows against the SHRM's 13 on 48."""
    env, brdf = load_env(ENV), load_brdf("microfacet:sigma=0.3")
    shrm = prefilter(env, brdf, eps=DEFAULT_EPS, lights="none")
    ctx = BuildContext(env, brdf, CompareOptions(lobes=(), lights="none"))
    ctx._base = (shrm, 0.0)  # the comparison's SHRM, made above
    row = build_kautz_mccool(ctx)[0].model
    built = RENDER_MODES["kautz-mccool"].build(env, brdf, None, eps=DEFAULT_EPS, options=RenderOptions(lights="none"))
    km = built.model
    assert (km.F, km.P, km.height, km.width) == (shrm.F, shrm.P, shrm.height, shrm.width)
    assert built.info["azimuth_free"] is True and (shrm.F, shrm.height) == (13, 48)
    np.testing.assert_array_equal(km.coeffs, row.coeffs)


def test_gaussian_lobes_are_one_model_in_render_and_compare() -> None:
    """[Green07] with the same K and elevations: render's build, compare's row and the table's
    function fit the same lobes on the same elevations (bitwise), θ_v evenly on [0, 89°]."""
    env, brdf = load_env(ENV), load_brdf("phong:s=8")
    options = RenderOptions(lobes=1, elevations=2)
    built = RENDER_MODES["gaussian-lobes"].build(env, brdf, None, eps=DEFAULT_EPS, options=options)
    row = build_green_lobes(BuildContext(env, brdf, CompareOptions(lobes=(1,), elevations=2)))[0]
    direct = methods.gaussian_lobes_model(env, brdf, lobes=1, elevations=2)
    assert row.key == "gaussian_lobes_k1" and row.params["elevations"] == 2
    np.testing.assert_allclose(built.model.lobes.theta_v, np.radians([0.0, 89.0]), rtol=1e-15)
    for other in (row.model.model.lobes, direct.lobes):
        for name in ("theta_v", "mu", "sigma", "weight", "residual"):
            np.testing.assert_array_equal(getattr(built.model.lobes, name), getattr(other, name))
