"""CURET (brdf_io/curet.py) and gonioreflectometer CSV (brdf_io/gonio.py) readers."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from shrmkit.brdf_io.cornell import ScatteredBRDF
from shrmkit.brdf_io.curet import (
    CURET_SAMPLE_NAMES,
    curet_files,
    curet_sample_name,
    curet_samples,
    read_curet,
    read_curet_all,
)
from shrmkit.brdf_io.errors import BadInputError, ScatteredEvalError
from shrmkit.brdf_io.gonio import gonio_wavelengths, read_gonio_csv

SEPARATIONS_DEG = 22.5 * np.arange(1, 8)  # CURET's seven source–camera separations


def _angle_deg(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.degrees(np.arccos(np.clip(np.sum(a * b, axis=-1), -1.0, 1.0)))


def _mirror(d: np.ndarray) -> np.ndarray:
    return d * np.array([-1.0, -1.0, 1.0])


# ------------------------------------------------------------------------------ CURET, real data


@pytest.fixture(scope="module")
def curet_dir(shared_data: Path) -> Path:
    return shared_data / "brdf" / "curet"


def test_curet_samples_and_names(curet_dir: Path) -> None:
    assert curet_samples(curet_dir) == list(range(1, 62))
    assert len(CURET_SAMPLE_NAMES) == 61
    assert curet_sample_name(15) == "Aluminum Foil" and curet_sample_name(61) == "Moss"
    with pytest.raises(BadInputError, match="1..61"):
        curet_sample_name(62)


def test_read_curet_sample(curet_dir: Path) -> None:
    foil = read_curet(curet_dir, 15)
    assert isinstance(foil, ScatteredBRDF) and foil.kind == "scattered" and len(foil) == 205
    assert foil.name == "curet-15-aluminum-foil" and foil.source.endswith("abrdf.dat#15")
    assert foil.L.shape == foil.V.shape == foil.rgb.shape == (205, 3)
    np.testing.assert_allclose(np.linalg.norm(foil.L, axis=1), 1.0, atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(foil.V, axis=1), 1.0, atol=1e-12)
    assert foil.L[:, 2].min() > 0.1 and foil.V[:, 2].min() > 0.1  # θ <= 83.9°
    assert np.degrees(np.arccos(min(foil.L[:, 2].min(), foil.V[:, 2].min()))) == pytest.approx(83.88, abs=0.01)
    np.testing.assert_array_equal(foil.rgb[:, 0], foil.rgb[:, 1])
    np.testing.assert_array_equal(foil.rgb[:, 0], foil.rgb[:, 2])
    assert foil.spectral is None and foil.n_clipped == 0
    # source–camera separations are CURET's seven angles
    sep = _angle_deg(foil.L, foil.V)
    assert np.all(np.min(np.abs(sep[:, None] - SEPARATIONS_DEG[None, :]), axis=1) < 0.05)
    # the foil's brightest measurement is at the mirror direction (standard convention, both away)
    k = int(np.argmax(foil.rgb[:, 0]))
    assert _angle_deg(_mirror(foil.L[k]), foil.V[k]) < 1e-3
    with pytest.raises(ScatteredEvalError):
        foil.eval(foil.L, foil.V)


def test_curet_file_arguments_and_selection(curet_dir: Path) -> None:
    by_folder = read_curet(curet_dir, 15)
    for path, sample in ((curet_dir / "abrdf.dat", "15"), (curet_dir / "table.txt", "aluminum-foil"),
                         (curet_dir, "Aluminum Foil"), (curet_dir, np.int64(15))):
        other = read_curet(path, sample)
        np.testing.assert_array_equal(other.rgb, by_folder.rgb)
        np.testing.assert_array_equal(other.L, by_folder.L)
    assert curet_files(curet_dir) == (curet_dir / "abrdf.dat", curet_dir / "table.txt")
    with pytest.raises(BadInputError, match="#15"):
        read_curet(curet_dir)
    with pytest.raises(BadInputError, match="no sample 62"):
        read_curet(curet_dir, 62)
    with pytest.raises(BadInputError, match="no CURET sample named"):
        read_curet(curet_dir, "granite")
    with pytest.raises(BadInputError, match="number 1..61"):
        read_curet(curet_dir, 1.5)  # type: ignore[arg-type]
    # 5,000 digits (issue 30): int() refuses > 4300 digits with a ValueError traceback; one line, shortened
    with pytest.raises(BadInputError, match=r"no sample 999999999999… \(5000 digits\)") as raised:
        read_curet(curet_dir, "9" * 5000)
    assert len(str(raised.value)) < 300


def test_curet_negative_values_are_clamped_and_counted(curet_dir: Path) -> None:
    """29 of the 12,505 values are negative: 28 on sample 61 (moss), 1 on sample 4."""
    every = read_curet_all(curet_dir)
    assert [b.name.split("-")[1] for b in every] == [f"{k:02d}" for k in range(1, 62)]
    counts = {int(b.name.split("-")[1]): b.n_clipped // 3 for b in every if b.n_clipped}
    assert counts == {4: 1, 61: 28}
    assert sum(b.n_clipped for b in every) == 3 * 29
    assert min(b.rgb.min() for b in every) == 0.0
    moss = read_curet(curet_dir, 61)
    np.testing.assert_array_equal(moss.rgb, every[60].rgb)


# ------------------------------------------------------------------------------ CURET, synthetic files


def _write_curet(folder: Path, samples: dict[int, np.ndarray] | None = None, n: int = 205) -> None:
    rng = np.random.default_rng(0)
    folder.mkdir(parents=True, exist_ok=True)
    rows = [f"{k}  {rng.uniform(0, 1.4):.6f} {rng.uniform(-3, 3):.6f} {rng.uniform(0, 1.4):.6f} "
            f"{rng.uniform(-3, 3):.6f}" for k in range(1, n + 1)]
    (folder / "table.txt").write_text("\n".join(rows) + "\n")
    samples = samples if samples is not None else {1: np.full(n, 0.1), 2: np.linspace(-0.01, 0.5, n)}
    lines = [f"{k} " + " ".join(f"{v:.4f}" for v in values) for k, values in samples.items()]
    (folder / "abrdf.dat").write_text("\n".join(lines) + "\n")


def _replace_line(path: Path, line_no: int, new: str) -> None:
    lines = path.read_text().splitlines()
    lines[line_no - 1] = new
    path.write_text("\n".join(lines) + "\n")


def test_curet_synthetic_roundtrip(tmp_path: Path) -> None:
    _write_curet(tmp_path)
    assert curet_samples(tmp_path) == [1, 2]
    b = read_curet(tmp_path / "abrdf.dat", 2)
    assert b.rgb.min() == 0.0 and b.n_clipped == 3 * 4  # −0.01, −0.0075, −0.005, −0.0025
    assert b.rgb[-1, 0] == pytest.approx(0.5)


@pytest.mark.parametrize(
    ("file", "line", "text", "match"),
    [
        ("abrdf.dat", 1, "1 0.1 x" + " 0.1" * 203, "line 1: 'x' is not a number"),
        ("abrdf.dat", 1, "1 0.1 1_0" + " 0.1" * 203, "line 1: '1_0' is not a number"),
        ("abrdf.dat", 1, "1 0.1 1e999" + " 0.1" * 203, "line 1: non-finite number '1e999'"),
        ("abrdf.dat", 2, "2 " + " ".join(["0.1"] * 204), "line 2: 205 numbers, expected 206 \\(the sample"),
        ("abrdf.dat", 2, "1 " + " ".join(["0.1"] * 205), "line 2: sample 1 listed twice"),
        ("abrdf.dat", 2, "62 " + " ".join(["0.1"] * 205), "line 2: sample number 62"),
        ("table.txt", 7, "7 0.1 0.2 0.3", "line 7: 4 numbers, expected 5"),
        ("table.txt", 7, "7 0.1 0.2 0.3 -Infinity", "line 7: non-finite number '-Infinity'"),
        ("table.txt", 7, "8 0.1 0.2 0.3 0.4", "line 7: measurement index 8, expected 7"),
        ("table.txt", 9, "9 1.7 0.2 0.3 0.4", "line 9: θ_v = 1.7 rad outside"),
        ("table.txt", 9, "9 0.5 0.2 0.3 90", "line 9: azimuth outside"),
    ],
)
def test_curet_bad_files(tmp_path: Path, file: str, line: int, text: str, match: str) -> None:
    _write_curet(tmp_path)
    _replace_line(tmp_path / file, line, text)
    with pytest.raises(BadInputError, match=match) as info:
        read_curet(tmp_path, 1)
    assert info.value.source == str(tmp_path / file)


def test_curet_sample_with_a_nan_fails_alone(tmp_path: Path) -> None:
    """A non-finite value on sample 2's line (issue 28: one `nan` made `shrm report abrdf.dat` exit 2
    with no report of the 61): sample 2 fails with the line's message, sample 1 reads, both are
    listed (the batch makes one failed report and the rest)."""
    from shrmkit.brdf_io.curet import curet_samples
    from shrmkit.brdf_io.specs import brdf_sources

    _write_curet(tmp_path)
    _replace_line(tmp_path / "abrdf.dat", 2, "2 nan " + " ".join(["0.1"] * 204))
    with pytest.raises(BadInputError, match="sample 2: line 2: non-finite number 'nan'") as info:
        read_curet(tmp_path, 2)
    assert info.value.source == str(tmp_path / "abrdf.dat")
    assert np.all(np.isfinite(read_curet(tmp_path, 1).rgb))
    assert curet_samples(tmp_path) == [1, 2]
    assert brdf_sources(tmp_path / "abrdf.dat") == [f"{tmp_path / 'abrdf.dat'}#1", f"{tmp_path / 'abrdf.dat'}#2"]


def test_curet_missing_and_short_files(tmp_path: Path) -> None:
    _write_curet(tmp_path / "short", n=204)
    with pytest.raises(BadInputError, match="204 measurement rows, expected 205"):
        read_curet(tmp_path / "short", 1)
    _write_curet(tmp_path / "long")
    with (tmp_path / "long" / "table.txt").open("a") as handle:
        handle.write("206 0.1 0.2 0.3 0.4\n")
    with pytest.raises(BadInputError, match="line 206: more than 205 rows"):
        read_curet(tmp_path / "long", 1)
    _write_curet(tmp_path / "lonely")
    (tmp_path / "lonely" / "table.txt").unlink()
    with pytest.raises(BadInputError, match="table.txt"):
        read_curet(tmp_path / "lonely" / "abrdf.dat", 1)
    with pytest.raises(BadInputError, match="no such file"):
        read_curet(tmp_path / "nowhere", 1)
    _write_curet(tmp_path / "empty")
    (tmp_path / "empty" / "abrdf.dat").write_text("\n\n")
    with pytest.raises(BadInputError, match="empty CURET values file"):
        read_curet(tmp_path / "empty", 1)
    (tmp_path / "empty" / "abrdf.dat").write_bytes(b"1 \xff\n")
    with pytest.raises(BadInputError, match="not an ASCII"):
        read_curet(tmp_path / "empty", 1)


# ------------------------------------------------------------------------------ gonio CSV, real data


@pytest.fixture(scope="module")
def ptfe_dir(shared_data: Path) -> Path:
    return shared_data / "brdf" / "nist_ptfe"


def test_ptfe_regular_set(ptfe_dir: Path) -> None:
    path = ptfe_dir / "PTFE.data.csv"
    assert gonio_wavelengths(path) == [351.0, 532.0, 633.0, 1064.0]
    with pytest.raises(BadInputError, match="351, 532, 633, 1064 nm"):
        read_gonio_csv(path)
    with pytest.raises(BadInputError, match="no rows at 500 nm"):
        read_gonio_csv(path, 500)
    b = read_gonio_csv(path, "532nm")
    assert b.name == "PTFE.data@532nm" and len(b) == 1824 and b.n_clipped == 0
    assert b.spectral.shape == (1824, 1) and b.wavelengths.tolist() == [532.0]
    np.testing.assert_array_equal(b.rgb[:, 0], b.spectral[:, 0])
    assert 0.2 < b.rgb.min() and b.rgb.max() < 0.75
    np.testing.assert_allclose(np.linalg.norm(b.L, axis=1), 1.0, atol=1e-12)
    assert b.L[:, 2].min() > 0 and b.V[:, 2].min() >= 0
    # negative θ_i: the source sits at azimuth 180°; the detector never on the source
    assert np.all(b.L[:, 0] <= 1e-12) and np.all(np.abs(b.L[:, 1]) < 1e-12)
    assert _angle_deg(b.L, b.V).min() > 5.0
    # the forward-scattering peak at θ_i = −75° lies near the mirror direction
    grazing = np.abs(np.degrees(np.arccos(b.L[:, 2])) - 75.0) < 0.5
    k = int(np.argmax(np.where(grazing, b.rgb[:, 0], -1.0)))
    assert _angle_deg(_mirror(b.L[k]), b.V[k]) < 30.0
    assert _angle_deg(b.L[k], b.V[k]) > 120.0
    np.testing.assert_array_equal(read_gonio_csv(path, "0.532um").rgb, b.rgb)


def test_ptfe_random_set(ptfe_dir: Path) -> None:
    b = read_gonio_csv(ptfe_dir / "PTFE.data.random.csv")  # one wavelength: no choice needed
    assert len(b) == 1760 and b.wavelengths.tolist() == [532.0]
    assert _angle_deg(b.L, b.V).min() > 4.5  # the detector never sits on the source
    # PTFE's forward scattering: brighter towards the mirror direction at grazing incidence
    grazing = b.L[:, 2] < np.cos(np.radians(50.0))
    cos_mirror = np.sum(_mirror(b.L) * b.V, axis=1)
    assert np.corrcoef(cos_mirror[grazing], b.rgb[grazing, 0])[0, 1] > 0.5


# ------------------------------------------------------------------------------ gonio CSV, synthetic


HEADER = "lambda,thetai,phi,thetar,phir,f_r11,f_r12/f_r11"


def _csv(tmp_path: Path, *rows: str, header: str = HEADER) -> Path:
    path = tmp_path / "g.csv"
    path.write_text("\n".join([header, *rows]) + "\n")
    return path


def test_gonio_sign_convention_and_clamping(tmp_path: Path) -> None:
    path = _csv(tmp_path, "0.6328,-30,0,30,0,0.31,0.01", "0.6328,30,90,45,180,-0.002,0.0", "")
    b = read_gonio_csv(path)
    s, c = np.sin(np.radians(30.0)), np.cos(np.radians(30.0))
    np.testing.assert_allclose(b.L[0], [-s, 0.0, c], atol=1e-15)  # θ_i = −30°: source at azimuth 180°
    np.testing.assert_allclose(b.V[0], [s, 0.0, c], atol=1e-15)  # the mirror direction
    np.testing.assert_allclose(b.L[1], [0.0, s, c], atol=1e-15)
    assert b.rgb[1].tolist() == [0.0, 0.0, 0.0] and b.n_clipped == 3
    assert b.wavelengths.tolist() == [632.8]
    # column order and case do not matter; other names accepted
    other = _csv(tmp_path, "0.31, 30 ,-30,0,0,0.6328", header="F_R11,ThetaR,ThetaI,Phi_i,PhiR,Wavelength")
    np.testing.assert_allclose(read_gonio_csv(other).L[0], [-s, 0.0, c], atol=1e-15)


@pytest.mark.parametrize(
    ("rows", "header", "match"),
    [
        (("0.5,0,0,10,0,0.3,0",), "lambda,thetai,thetar,phir,f_r11,x,y", "missing column\\(s\\) phi/phii/phi_i"),
        (("0.5,0,0,10,0,0.3,0",), "lambda,thetai,phi,thetar,phir,f_r11,brdf", "column 'f_r11' appears 2 times"),
        (("0.5,0,0,10,0,0.3,0", "0.5,0,0,abc,0,0.3,0"), HEADER, "line 3: column thetar: 'abc' is not a number"),
        (("0.5,0,0,10,0,nan,0",), HEADER, "line 2: column f_r11: 'nan' is not finite"),
        (("0.5,0,0,10,0,1e999,0",), HEADER, "line 2: column f_r11: '1e999' is not finite"),
        (("0.5,0,0,1_0,0,0.3,0",), HEADER, "line 2: column thetar: '1_0' is not a number"),
        (("0.5,0,,10,0,0.3,0",), HEADER, "line 2: column phii: '' is not a number"),
        (("0.5,0,0,10,0,0.3,0", "0.5,0,0,10"), HEADER, "line 3: 4 fields, the header has 7"),
        (("0.5,0,0,95,0,0.3,0",), HEADER, "line 2: thetar = 95° outside"),
        ((), HEADER, "no measurement rows"),
    ],
)
def test_gonio_bad_files(tmp_path: Path, rows: tuple[str, ...], header: str, match: str) -> None:
    path = _csv(tmp_path, *rows, header=header)
    with pytest.raises(BadInputError, match=match) as info:
        read_gonio_csv(path)
    assert info.value.source == str(path)


def test_gonio_row_limit(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The arrays are sized from the line count and checked against SHRM_MAX_ELEMENTS first."""
    path = _csv(tmp_path, *["0.5,0,0,10,0,0.3,0"] * 5)
    assert len(read_gonio_csv(path)) == 5
    monkeypatch.setenv("SHRM_MAX_ELEMENTS", "20")
    with pytest.raises(BadInputError, match="SHRM_MAX_ELEMENTS"):
        read_gonio_csv(path)


def test_gonio_other_errors(tmp_path: Path) -> None:
    path = tmp_path / "empty.csv"
    path.write_text("")
    with pytest.raises(BadInputError, match="empty file"):
        read_gonio_csv(path)
    path.write_bytes(b"lambda\xff\n")
    with pytest.raises(BadInputError, match="not a UTF-8"):
        read_gonio_csv(path)
    good = _csv(tmp_path, "0.5,0,0,10,0,0.3,0")
    for bad in ("green", "-5", "0"):
        with pytest.raises(BadInputError, match="wavelength"):
            read_gonio_csv(good, bad)
    with pytest.raises(BadInputError, match="no such file"):
        read_gonio_csv(tmp_path / "missing.csv")
