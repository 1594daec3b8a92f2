"""An SHRM file's light descriptions (``meta.lights``, ``data_specs/shrm_file.md``) hold a direction
and an RGB power of three numbers each: a description with another count is refused naming the file
(found by mypy: the reader built ``Light`` with as many numbers as the file gave)."""

from __future__ import annotations

import json

import numpy as np
import pytest

import shrmkit
from shrmkit.brdf_io.errors import BadInputError


@pytest.fixture(scope="module")
def lit_arrays(tmp_path_factory):
    path = tmp_path_factory.mktemp("lit") / "lit.shrm.npz"
    shrm = shrmkit.prefilter(shrmkit.load_env("builtin:sky,height=32"), "microfacet:sigma=0.2", eps=0.1)
    assert shrm.has_lights and shrm.meta["lights"]
    shrm.save(path)
    with np.load(path) as npz:
        return {key: npz[key] for key in npz.files}


def _write(path, arrays, header):
    np.savez(path, **{**arrays, "header": np.array(json.dumps(header))})
    return path


def test_light_descriptions_read_back_as_three_numbers(lit_arrays, tmp_path):
    header = json.loads(str(lit_arrays["header"]))
    light = shrmkit.load_shrm(_write(tmp_path / "good.shrm.npz", lit_arrays, header)).lights.lights[0]
    assert len(light.direction) == 3 and len(light.power) == 3
    assert light.direction == pytest.approx(header["meta"]["lights"][0]["direction"])


@pytest.mark.parametrize("key, value", [("direction", [0.0, 1.0]), ("power", [1.0, 2.0, 3.0, 4.0])])
def test_light_description_with_another_count_of_numbers_is_refused(lit_arrays, tmp_path, key, value):
    header = json.loads(str(lit_arrays["header"]))
    header["meta"]["lights"][0][key] = value
    path = _write(tmp_path / "bad.shrm.npz", lit_arrays, header)
    with pytest.raises(BadInputError, match=r"bad\.shrm\.npz.*light description"):
        shrmkit.load_shrm(path)
