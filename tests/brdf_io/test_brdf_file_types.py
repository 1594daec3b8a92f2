"""The BRDF file-type registry (brdf_io.specs.BRDF_FILE_TYPES): every suffix reaches its
reader through load_brdf, ``FILE#selector`` picks one member of a multi-BRDF file, and
brdf_sources expands a whole file into its members."""

from __future__ import annotations

import numpy as np
import pytest

from shrmkit.brdf_io.curet import read_curet
from shrmkit.brdf_io.errors import BadInputError
from shrmkit.brdf_io.gonio import read_gonio_csv
from shrmkit.brdf_io.rgl import read_rgl
from shrmkit.brdf_io.specs import BRDF_FILE_TYPES, brdf_sources, load_brdf


def test_registry_lists_every_reader():
    assert set(BRDF_FILE_TYPES) == {".binary", ".npz", ".brdf", ".bsdf", ".dat", ".csv", ".json"}
    assert {s for s, t in BRDF_FILE_TYPES.items() if t.selector} == {".dat", ".csv", ".bsdf"}


def test_curet_selector_and_expansion(shared_data):
    path = shared_data / "brdf" / "curet" / "abrdf.dat"
    by_number = load_brdf(f"{path}#12")
    direct = read_curet(path, 12)
    np.testing.assert_array_equal(by_number.rgb, direct.rgb)
    assert by_number.name == direct.name
    sources = brdf_sources(path)
    assert len(sources) == 61 and sources[0] == f"{path}#1" and sources[-1] == f"{path}#61"
    assert brdf_sources(f"{path}#5") == [f"{path}#5"]
    with pytest.raises(BadInputError, match="choose one"):
        load_brdf(path)
    with pytest.raises(BadInputError, match="no sample 99"):
        load_brdf(f"{path}#99")


def test_gonio_selector_and_expansion(shared_data):
    path = shared_data / "brdf" / "nist_ptfe" / "PTFE.data.csv"
    brdf = load_brdf(f"{path}#532")
    np.testing.assert_array_equal(brdf.rgb, read_gonio_csv(path, 532).rgb)
    assert brdf_sources(path) == [f"{path}#{w}" for w in ("351", "532", "633", "1064")]


def test_rgl_through_load_brdf(shared_data):
    path = shared_data / "brdf" / "rgl" / "paper_white_rgb.bsdf"
    rng = np.random.default_rng(1)
    L, V = rng.normal(size=(2, 50, 3))
    L[:, 2], V[:, 2] = np.abs(L[:, 2]), np.abs(V[:, 2])
    L /= np.linalg.norm(L, axis=1, keepdims=True)
    V /= np.linalg.norm(V, axis=1, keepdims=True)
    np.testing.assert_array_equal(load_brdf(path).eval(L, V), read_rgl(path).eval(L, V))


def test_selector_on_a_missing_file_names_the_file(tmp_path):
    with pytest.raises(BadInputError, match="no such file") as err:
        load_brdf(f"{tmp_path / 'none.dat'}#3")
    assert "none.dat" in str(err.value) and "#3" not in str(err.value)
    assert brdf_sources("phong:s=8") == ["phong:s=8"]


def test_rgl_incident_selector(shared_data):
    """``file.bsdf#light`` / ``#camera`` pick the RGL table direction (default camera, as Mitsuba
    renders: data_specs/rgl_bsdf.md); anything else is refused naming the choices."""
    path = shared_data / "brdf" / "rgl" / "paper_white_rgb.bsdf"
    assert load_brdf(path).table_direction == "view" and load_brdf(f"{path}#camera").table_direction == "view"
    light = load_brdf(f"{path}#light")
    assert light.table_direction == "light" and light.name == "paper_white_rgb#light"
    assert brdf_sources(f"{path}#light") == [f"{path}#light"]
    with pytest.raises(BadInputError, match="unknown RGL incident direction 'sun'.*camera, light"):
        load_brdf(f"{path}#sun")
