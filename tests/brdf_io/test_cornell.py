"""Cornell .brdf scattered measurements (brdf_io/cornell.py) and the spectral -> sRGB
pipeline (brdf_io/colour.py)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import shrmkit
from shrmkit.brdf_io.colour import (
    CIE1931_CMF,
    D65_SPD,
    WAVELENGTHS_NM,
    XYZ_TO_LINEAR_SRGB,
    spectral_to_linear_srgb,
    spectral_to_xyz,
    white_balance,
)
from shrmkit.brdf_io.cornell import ScatteredBRDF, read_cornell
from shrmkit.brdf_io.errors import BadInputError, ScatteredEvalError

MATERIALS = ("acryl_blue", "cayman", "garnet_red", "krylon_blue", "mystique")

# ------------------------------------------------------------------------------ colour


def test_flat_spectrum_is_grey() -> None:
    """A spectrally flat rho = c maps to (c, c, c) within 1e-3 (the pipeline's normalization)."""
    for c in (0.0, 0.05, 1.0, 37.5):
        np.testing.assert_allclose(spectral_to_linear_srgb(np.full(31, c)), [c, c, c], atol=1e-3 * max(c, 1))


def test_white_balance_is_small() -> None:
    """Without the final diagonal, D65-weighted flat white through the IEC matrix is already
    within 0.5 % of (1, 1, 1): the CMF table, the D65 table and the matrix agree."""
    np.testing.assert_allclose(white_balance(), 1.0, atol=5e-3)


def test_d65_white_chromaticity() -> None:
    """x, y of D65 from the tabulated SPD and CMFs vs CIE 015:2004's (0.3127, 0.3290)."""
    X, Y, Z = spectral_to_xyz(np.ones(31))
    assert Y == pytest.approx(1.0, abs=1e-15)
    assert X / (X + Y + Z) == pytest.approx(0.3127, abs=5e-4)
    assert Y / (X + Y + Z) == pytest.approx(0.3290, abs=5e-4)


def test_cmf_sum_normalization() -> None:
    """Equal-energy white: Σx̄ ≈ Σȳ ≈ Σz̄, and Σȳ Δλ ≈ ∫ȳ dλ = 106.857 (CIE 015:2004), up to
    the part of the curves outside 400–700 nm (< 0.5 %)."""
    sums = CIE1931_CMF.sum(axis=0) * 10.0
    np.testing.assert_allclose(sums, 106.857, rtol=5e-3)
    assert CIE1931_CMF[:, 1].max() == pytest.approx(0.99500)  # ȳ peaks at 1 at 555 nm, not sampled


@pytest.mark.parametrize(
    ("wavelength", "x", "y"),
    # CIE 1931 spectral-locus chromaticities (CIE 015:2004 Table T.4 x(λ), y(λ) columns)
    [(450, 0.1566, 0.0177), (520, 0.0743, 0.8338), (550, 0.3016, 0.6923), (600, 0.6270, 0.3725)],
)
def test_spectral_locus(wavelength: int, x: float, y: float) -> None:
    spectrum = np.where(WAVELENGTHS_NM == wavelength, 1.0, 0.0)
    X, Y, Z = spectral_to_xyz(spectrum)
    assert X / (X + Y + Z) == pytest.approx(x, abs=2e-4)
    assert Y / (X + Y + Z) == pytest.approx(y, abs=2e-4)


def test_srgb_matrix_maps_d65_to_white() -> None:
    """IEC 61966-2-1: the D65 white XYZ = (0.9505, 1, 1.0890) maps to RGB (1, 1, 1)."""
    np.testing.assert_allclose(XYZ_TO_LINEAR_SRGB @ [0.9505, 1.0, 1.0890], 1.0, atol=1e-3)
    assert D65_SPD[WAVELENGTHS_NM == 560][0] == 100.0  # D65 normalized to 100 at 560 nm


def test_colour_rejects_other_wavelengths() -> None:
    with pytest.raises(ValueError, match="400, 410"):
        spectral_to_linear_srgb(np.ones(31), wavelengths=np.arange(380, 690, 10.0))
    with pytest.raises(ValueError, match="31 samples"):
        spectral_to_xyz(np.ones(30))


# ------------------------------------------------------------------------------ real files


@pytest.fixture(scope="module")
def cornell(shared_data: Path) -> dict[str, ScatteredBRDF]:
    return {m: read_cornell(shared_data / "brdf" / "cornell" / f"{m}.brdf") for m in MATERIALS}


def test_real_files(cornell: dict[str, ScatteredBRDF]) -> None:
    """All five files: 1439 rows, θ_i in {10, ..., 80}°, φ_i = 0, θ_s ≤ 79.05°, unit
    directions above the surface, finite non-negative spectral values."""
    for name, brdf in cornell.items():
        assert brdf.kind == "scattered" and brdf.name == name
        assert len(brdf) == 1439
        assert brdf.L.shape == brdf.V.shape == brdf.rgb.shape == (1439, 3)
        assert brdf.spectral.shape == (1439, 31)
        np.testing.assert_array_equal(brdf.wavelengths, np.arange(400, 701, 10))
        theta_i = np.degrees(np.arccos(brdf.L[:, 2]))
        np.testing.assert_allclose(np.unique(np.round(theta_i)), np.arange(10, 81, 10))
        np.testing.assert_allclose(theta_i, np.round(theta_i), atol=1e-4)
        assert np.all(brdf.L[:, 1] == 0.0) and np.all(brdf.L[:, 0] > 0)  # φ_i = 0
        assert np.degrees(np.arccos(brdf.V[:, 2])).max() == pytest.approx(79.05, abs=0.01)
        np.testing.assert_allclose(np.linalg.norm(brdf.L, axis=1), 1.0, atol=1e-12)
        np.testing.assert_allclose(np.linalg.norm(brdf.V, axis=1), 1.0, atol=1e-12)
        assert np.all(brdf.V[:, 2] > 0)
        assert np.all(np.isfinite(brdf.spectral)) and np.all(brdf.spectral >= 0)
        assert np.all(np.isfinite(brdf.rgb)) and np.all(brdf.rgb >= 0)
        # out-of-gamut components are clipped, and only those
        unclipped = spectral_to_linear_srgb(brdf.spectral)
        assert brdf.n_clipped == int(np.sum(unclipped < 0))
        np.testing.assert_array_equal(brdf.rgb, np.maximum(unclipped, 0.0))


def test_specular_peak_is_at_the_mirror_direction(cornell: dict[str, ScatteredBRDF]) -> None:
    """Sign convention: the brightest sample at each θ_i lies in the plane of incidence on
    the far side (φ_s = π) and within 5° of the mirror direction (−L_x, −L_y, L_z) — except
    garnet_red at θ_i = 50°–70°, whose brightest sample is a more grazing one (still φ_s = π)."""
    for name, brdf in cornell.items():
        theta_i = np.round(np.degrees(np.arccos(brdf.L[:, 2])))
        brightness = brdf.spectral.mean(axis=1)
        for t in np.arange(10, 81, 10):
            rows = np.flatnonzero(theta_i == t)
            k = rows[np.argmax(brightness[rows])]
            assert abs(brdf.V[k, 1]) < 1e-6 and brdf.V[k, 0] < 0  # φ_s = π
            if name == "garnet_red" and 50 <= t <= 70:
                continue
            mirror = brdf.L[k] * np.array([-1.0, -1.0, 1.0])
            assert np.degrees(np.arccos(np.clip(brdf.V[k] @ mirror, -1, 1))) < 5.0


def test_colours_match_material_names(cornell: dict[str, ScatteredBRDF]) -> None:
    """Diffuse-ish samples (far from the mirror direction) of the blue paints are blue and
    of garnet red are red, in linear sRGB."""
    for name, brdf in cornell.items():
        mirror = brdf.L * np.array([-1.0, -1.0, 1.0])
        off_specular = np.einsum("ij,ij->i", brdf.V, mirror) < np.cos(np.radians(30))
        r, _, b = np.median(brdf.rgb[off_specular], axis=0)
        if name in ("krylon_blue", "acryl_blue"):
            assert b > 2 * r
        if name == "garnet_red":
            assert r > 2 * b


def test_eval_raises(cornell: dict[str, ScatteredBRDF], shared_data: Path) -> None:
    brdf = shrmkit.load_brdf(str(shared_data / "brdf" / "cornell" / "cayman.brdf"))
    assert isinstance(brdf, ScatteredBRDF)
    with pytest.raises(ScatteredEvalError, match=r"fit a model \(shrm fit / shrmkit.fit_brdf\) first"):
        brdf.eval(brdf.L, brdf.V)
    with pytest.raises(ScatteredEvalError):
        brdf.eval_counted(brdf.L, brdf.V)
    with pytest.raises(ScatteredEvalError):
        brdf.rho_hat(brdf.L, brdf.V)


# ------------------------------------------------------------------------------ bad input

_HEADER = "# test file\n\n# num wls\n31\n\n# wls\n" + " ".join(str(w) for w in range(400, 590, 10)) + "\n" + " ".join(
    str(w) for w in range(590, 701, 10)
) + "\n\n"


def _row(theta_i: float = 0.5, phi_i: float = 0.0, theta_s: float = 0.4, phi_s: float = 3.0, n: int = 31) -> str:
    return " ".join(f"{v:.6f}" for v in (theta_i, phi_i, theta_s, phi_s, *np.linspace(0.1, 0.4, n))) + "\n"


def test_synthetic_file_reads(tmp_path: Path) -> None:
    """A hand-written file: directions from the spherical convention, flat spectrum -> grey."""
    path = tmp_path / "ok.brdf"
    flat = " ".join(["0.5", "0.0", "0.3", "3.14159265"] + ["0.2"] * 31) + "\n"
    path.write_text(_HEADER + _row() + flat)
    brdf = read_cornell(path)
    assert len(brdf) == 2
    np.testing.assert_allclose(brdf.L[1], [np.sin(0.5), 0.0, np.cos(0.5)], atol=1e-15)
    np.testing.assert_allclose(brdf.V[1], [-np.sin(0.3), np.sin(0.3) * np.sin(3.14159265), np.cos(0.3)], atol=1e-12)
    np.testing.assert_allclose(brdf.rgb[1], 0.2, atol=1e-3 * 0.2)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        (_HEADER + _row() + _row()[:-20] + "\n", r"line 11: 33 numbers"),  # truncated last row
        (_HEADER + _row(n=32), "36 numbers, expected 4 angles"),
        (_HEADER + _row(n=30), "34 numbers"),
        (_HEADER + _row().replace("0.400000", "abc"), "'abc' is not a number"),
        (_HEADER.replace("\n31\n", "\n30\n"), "31 wavelengths listed, the header says 30"),
        (_HEADER.replace("\n31\n", "\n3.5\n"), "not a positive integer"),
        (_HEADER.replace("400 410", "405 410") + _row(), "not the 31 values"),
        (_HEADER, "no measurement rows"),
        ("# nothing\n", "no wavelength header"),
        (_HEADER + _row(theta_s=1.7), "outside"),
        (_HEADER + _row().replace("0.400000", "-0.4"), "negative"),
        (_HEADER + _row().replace("0.400000", "nan"), "non-finite"),
    ],
)
def test_bad_files(tmp_path: Path, text: str, message: str) -> None:
    path = tmp_path / "bad.brdf"
    path.write_text(text)
    with pytest.raises(BadInputError, match=message) as info:
        read_cornell(path)
    assert str(path) in str(info.value)


def test_unreadable(tmp_path: Path) -> None:
    with pytest.raises(BadInputError, match="no such file"):
        read_cornell(tmp_path / "absent.brdf")
    path = tmp_path / "binary.brdf"
    path.write_bytes(b"\xff\xfe\x00garbage")
    with pytest.raises(BadInputError, match="cannot read"):
        read_cornell(path)
