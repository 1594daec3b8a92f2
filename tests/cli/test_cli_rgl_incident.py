"""``--rgl-incident camera|light`` on every verb that loads a BRDF (cli/common.py; issue 29)."""

from __future__ import annotations

import argparse
import json

import pytest

from shrmkit.brdf_io.errors import BadInputError
from shrmkit.cli.common import rgl_brdf_arg
from shrmkit.cli.main import build_parser, main

#: the verbs that take a user's BRDF (bench and demo use their own)
BRDF_VERBS = ("orders", "report", "prefilter", "render", "view", "compare", "fit")


def _verb_parsers() -> dict[str, argparse.ArgumentParser]:
    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    return dict(sub.choices)


def test_every_brdf_verb_has_the_option() -> None:
    parsers = _verb_parsers()
    for verb in BRDF_VERBS:
        action = next((a for a in parsers[verb]._actions if "--rgl-incident" in a.option_strings), None)
        assert action is not None, verb
        assert action.default == "camera" and tuple(action.choices) == ("camera", "light"), verb


def test_rgl_brdf_arg() -> None:
    light, camera = argparse.Namespace(rgl_incident="light"), argparse.Namespace(rgl_incident="camera")
    assert rgl_brdf_arg("a/x.bsdf", light) == "a/x.bsdf#light"
    assert rgl_brdf_arg("a/x.BSDF", camera) == "a/x.BSDF"
    assert rgl_brdf_arg("a/x.bsdf#light", camera) == "a/x.bsdf#light"  # the file's own choice is kept
    assert rgl_brdf_arg("a/x.bsdf#light", light) == "a/x.bsdf#light"
    assert rgl_brdf_arg("phong:s=8", light) == "phong:s=8"
    assert rgl_brdf_arg("m.binary", light) == "m.binary"
    with pytest.raises(BadInputError, match="--rgl-incident says 'light'"):
        rgl_brdf_arg("a/x.bsdf#camera", light)


def test_orders_reads_the_light_convention(shared_data, capsys) -> None:
    path = str(shared_data / "brdf" / "rgl" / "paper_white_rgb.bsdf")
    assert main(["orders", path, "--eps", "0.05", "--json", "--rgl-incident", "light"]) == 0
    assert json.loads(capsys.readouterr().out)["brdf"] == "paper_white_rgb#light"
    assert main(["orders", path, "--eps", "0.05", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["brdf"] == "paper_white_rgb"
