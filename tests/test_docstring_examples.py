"""The ``Examples`` sections of the main readers' and ``prefilter``'s docstrings run as tests (doctest).

The examples name their input files as ``tests/resources/...``, relative to the
repository root, so each module's examples run with the root as the working directory.
The tiny files there are checked here against the values they were made with
(tests/resources/README.md), so that a wrong reader cannot hide behind a wrong file.
"""

from __future__ import annotations

import doctest
import json
from pathlib import Path

import numpy as np
import pytest

from shrmkit.analysis import shrm
from shrmkit.brdf_io import envmap, hdr_codecs, merl, pfm, rgbe, specs

ROOT = Path(__file__).resolve().parents[1]
RESOURCES = ROOT / "tests" / "resources"
OPTIONS = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE

# module -> the functions whose docstrings must show examples
DOCUMENTED = {
    specs: ("load_brdf",),
    envmap: ("load_env",),
    merl: ("read_merl", "write_merl"),
    rgbe: ("read_hdr",),
    pfm: ("read_pfm",),
    shrm: ("prefilter",),
}


@pytest.mark.parametrize("module", list(DOCUMENTED), ids=lambda m: m.__name__.rsplit(".", 1)[-1])
def test_docstring_examples_pass(module, monkeypatch):
    monkeypatch.chdir(ROOT)
    found = doctest.DocTestFinder().find(module)
    with_examples = {test.name.rsplit(".", 1)[-1] for test in found if test.examples}
    missing = sorted(set(DOCUMENTED[module]) - with_examples)
    assert not missing, f"{module.__name__}: no docstring examples in {', '.join(missing)}"
    result = doctest.testmod(module, optionflags=OPTIONS, report=False)
    assert result.attempted >= len(DOCUMENTED[module])
    assert result.failed == 0, f"{result.failed} of {result.attempted} examples failed in {module.__name__} (above)"


def test_tiny_hdr_holds_the_known_pixels():
    """tiny_4x8.hdr: pixel (i, j) = ((j + 1)/8, (i + 1)/4, (i + j + 1)/16), exact in RGBE."""
    path = RESOURCES / "tiny_4x8.hdr"
    data = path.read_bytes()
    assert len(data) < 1024
    assert data.startswith(b"#?RADIANCE") and b"\n-Y 4 +X 8\n" in data
    assert data[data.index(b"+X 8\n") + 5 :][:4] == bytes((2, 2, 0, 8))  # run-length encoded scanlines
    i, j = np.mgrid[0:4, 0:8]
    expected = np.stack([(j + 1) / 8, (i + 1) / 4, (i + j + 1) / 16], axis=-1)
    np.testing.assert_allclose(hdr_codecs.read_hdr(path), expected, rtol=0, atol=1e-7)
    # first pixel by hand from its RGBE bytes: exponent byte e gives 2^(e - 136)
    image = hdr_codecs.read_hdr(path)
    assert image[0, 0].tolist() == [0.125, 0.25, 0.0625]


def test_tiny_table_holds_the_known_values():
    """tiny_table.npz: ρ = (0.1 + 0.2 t_i, 0.3 + 0.1 t_o, 0.2 + 0.1 t_φ) at the grid corners,
    t = θ_i/(π/2), θ_o/(π/2), φ_d/π."""
    path = RESOURCES / "tiny_table.npz"
    assert path.stat().st_size < 4096
    with np.load(path) as npz:
        np.testing.assert_array_equal(npz["theta_i"], [0.0, np.pi / 2])
        np.testing.assert_array_equal(npz["theta_o"], [0.0, np.pi / 2])
        np.testing.assert_array_equal(npz["phi_d"], [0.0, np.pi])
        t_i, t_o, t_p = np.meshgrid([0.0, 1.0], [0.0, 1.0], [0.0, 1.0], indexing="ij")
        expected = np.stack([0.1 + 0.2 * t_i, 0.3 + 0.1 * t_o, 0.2 + 0.1 * t_p], axis=-1)
        np.testing.assert_allclose(npz["values"], expected, rtol=1e-15)
        assert json.loads(str(npz["metadata"]))["format"] == "shrmkit-brdf-table"


def test_resources_stay_tiny():
    for path in RESOURCES.iterdir():
        assert path.stat().st_size < 50_000, path
