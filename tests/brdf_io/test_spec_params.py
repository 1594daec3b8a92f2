"""The one spec-parameter parser (brdf_io/spec_params.py) behind BRDF specs and built-in environments."""

from __future__ import annotations

import numpy as np
import pytest

from shrmkit.brdf_io.envmap import load_env
from shrmkit.brdf_io.errors import BadInputError
from shrmkit.brdf_io.spec_params import SpecParams, parse_params
from shrmkit.brdf_io.specs import load_brdf


def test_typed_access_and_defaults():
    spec = "x:a=1.5,rgb=0.1/0.2/0.3,n=7,w=GGX"
    p = SpecParams(spec, parse_params(spec, ["a=1.5", " rgb = 0.1/0.2/0.3 ", "n=7", "w=GGX"]), owner="x")
    assert p.scalar("a", None, 0.0, 2.0) == 1.5
    np.testing.assert_array_equal(p.color("rgb", None), [0.1, 0.2, 0.3])
    np.testing.assert_array_equal(p.color("absent", (1.0, 2.0, 3.0)), [1.0, 2.0, 3.0])
    np.testing.assert_array_equal(p.color("absent2", 0.5), [0.5, 0.5, 0.5])
    assert p.integer("n", 1, 1, 10) == 7
    assert p.choice("w", "beckmann", ("beckmann", "ggx"), fold_case=True) == "ggx"
    assert p.has("a") and not p.has("zzz")
    p.finish()


@pytest.mark.parametrize(
    ("items", "call", "fragments"),
    [
        (["a=abc"], lambda p: p.scalar("a", 1.0), ["a='abc'", "not a number"]),
        (["a=nan"], lambda p: p.scalar("a", 1.0), ["a='nan'", "not finite"]),
        (["a=1/2"], lambda p: p.color("a", 1.0), ["a='1/2'", "one value or r/g/b"]),
        (["a=1/2/3"], lambda p: p.scalar("a", 1.0), ["parameter a", "not r/g/b"]),
        (["a=3"], lambda p: p.scalar("a", 1.0, 0.0, 2.0), ["a=3", "outside [0, 2]"]),
        (["a=0"], lambda p: p.scalar("a", 1.0, 0.0, 2.0, lo_open=True), ["a=0", "outside (0, 2]"]),
        (["a=2.5"], lambda p: p.integer("a", 1), ["a=2.5", "not an integer"]),
        ([], lambda p: p.scalar("a", None), ["missing parameter 'a'"]),
        (["w=phong"], lambda p: p.choice("w", "ggx", ("beckmann", "ggx")), ["w='phong'", "beckmann, ggx"]),
        (["a=1", "b=2"], lambda p: (p.scalar("a", 0.0), p.finish()), ["unknown parameter(s) b for m", "valid: a"]),
    ],
)
def test_errors_name_spec_key_and_value(items, call, fragments):
    spec = "m:" + ",".join(items)
    with pytest.raises(BadInputError) as info:
        call(SpecParams(spec, parse_params(spec, items), owner="m"))
    assert info.value.source == spec
    for fragment in fragments:
        assert fragment in str(info.value)


@pytest.mark.parametrize(
    ("items", "allowed", "fragment"),
    [
        (["a"], None, "parameter 'a' is not of the form key=value"),
        (["a="], None, "'a=' is not of the form key=value"),
        (["=1"], None, "not of the form key=value"),
        (["a=1", "a=2"], None, "parameter 'a' given twice"),
        (["c=1"], ("a", "b"), "unknown parameter 'c' for owner; valid: a, b"),
    ],
)
def test_parse_errors(items, allowed, fragment):
    with pytest.raises(BadInputError, match=fragment.replace("(", r"\(")):
        parse_params("the-spec", items, allowed=allowed, owner="owner")


@pytest.mark.parametrize(
    ("brdf_spec", "env_spec", "message"),
    [
        ("lambert:albedo=abc", "builtin:constant,value=abc", "parameter {}='abc' is not a number"),
        ("lambert:albedo=inf", "builtin:constant,value=inf", "parameter {}='inf' is not finite"),
        ("lambert:albedo=1/2", "builtin:constant,value=1/2", "parameter {}='1/2': give one value or r/g/b"),
        ("lambert:albedo", "builtin:constant,value", "parameter '{}' is not of the form key=value"),
        ("lambert:albedo=1,albedo=1", "builtin:constant,value=1,value=1", "parameter '{}' given twice"),
    ],
)
def test_brdf_specs_and_builtin_envs_share_the_parser(brdf_spec, env_spec, message):
    for spec, key, load in ((brdf_spec, "albedo", load_brdf), (env_spec, "value", load_env)):
        with pytest.raises(BadInputError) as info:
            load(spec)
        assert str(info.value) == f"{spec}: " + message.format(key)


def test_unknown_keys_are_listed_with_the_valid_ones():
    with pytest.raises(BadInputError, match=r"unknown parameter\(s\) q for phong; valid: s, ks"):
        load_brdf("phong:s=8,q=2")
    with pytest.raises(BadInputError, match="unknown parameter 'q' for builtin:sun; valid: height, sky, ratio"):
        load_env("builtin:sun,q=2")
