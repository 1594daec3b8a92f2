"""MERL .binary reader/writer and index-space interpolation (brdf_io/merl.py)."""

from __future__ import annotations

import math
import struct
from pathlib import Path

import numpy as np
import pytest

import shrmkit
from shrmkit.brdf_io.errors import BadInputError
from shrmkit.brdf_io.halfdiff import directions_to_halfdiff, halfdiff_to_directions
from shrmkit.brdf_io.merl import (
    MerlBRDF,
    merl_index_coordinates,
    merl_sample_angles,
    read_merl,
    tabulate_merl,
    write_merl,
)

N = 90 * 90 * 180
SCALES = (1.0 / 1500.0, 1.15 / 1500.0, 1.66 / 1500.0)  # BRDFRead.cpp RED/GREEN/BLUE_SCALE
SMOOTH_SPEC = "lafortune:kd=0.2/0.3/0.4,cxy=-1,cz=1,n=6,ks=0.5/0.6/0.7"


def _offset(c: int, i: int, j: int, k: int) -> int:
    """Byte offset of sample (channel c, θ_h i, θ_d j, φ_d k), written out by hand from
    BRDFRead.cpp: ind = k + j·180 + i·180·90, channel planes of 90·90·180 doubles after a
    12-byte header."""
    return 12 + 8 * (c * N + i * 90 * 180 + j * 180 + k)


def _random_hemisphere(rng: np.random.Generator, n: int, max_theta: float = np.pi / 2) -> np.ndarray:
    cos_t = rng.uniform(np.cos(max_theta), 1.0, n)
    phi = rng.uniform(-np.pi, np.pi, n)
    sin_t = np.sqrt(1.0 - cos_t**2)
    return np.stack((sin_t * np.cos(phi), sin_t * np.sin(phi), cos_t), axis=-1)


@pytest.fixture(scope="module")
def smooth_merl(tmp_path_factory: pytest.TempPathFactory) -> tuple[object, MerlBRDF, Path]:
    """A smooth Lafortune model written to MERL and read back."""
    model = shrmkit.load_brdf(SMOOTH_SPEC)
    path = tmp_path_factory.mktemp("merl") / "smooth.binary"
    write_merl(path, model)
    return model, read_merl(path), path


# ---------------------------------------------------------------------------------- layout


def test_reader_byte_layout_against_hand_built_file(tmp_path: Path) -> None:
    """A file built with struct at hand-computed offsets (independent of the reader's
    reshape) reads back with the right channel order, index order, scales and missing."""
    data = bytearray(12 + 3 * 8 * N)
    struct.pack_into("<3i", data, 0, 90, 90, 180)
    rng = np.random.default_rng(7)
    picks = [(c, int(rng.integers(90)), int(rng.integers(90)), int(rng.integers(180))) for c in range(3)] * 8
    picks += [(0, 0, 0, 0), (2, 89, 89, 179), (1, 0, 0, 179), (1, 89, 0, 0)]
    stored = {}
    for n, (c, i, j, k) in enumerate(picks):
        stored[(c, i, j, k)] = 1.0 + n + 0.25 * c
        struct.pack_into("<d", data, _offset(c, i, j, k), stored[(c, i, j, k)])
    struct.pack_into("<d", data, _offset(1, 5, 6, 7), -1.0)  # one missing green sample
    path = tmp_path / "hand.binary"
    path.write_bytes(bytes(data))
    brdf = read_merl(path)
    assert brdf.values.shape == (3, 90, 90, 180)
    for (c, i, j, k), v in stored.items():
        assert brdf.values[c, i, j, k] == pytest.approx(v * SCALES[c], rel=1e-15)
    assert np.isnan(brdf.values[1, 5, 6, 7])
    assert brdf.n_missing == 1
    assert np.nansum(brdf.values) == pytest.approx(sum(v * SCALES[c] for (c, *_), v in stored.items()))
    assert brdf.name == "hand" and brdf.kind == "tabulated" and brdf.source == str(path)


def test_writer_byte_layout(tmp_path: Path) -> None:
    """write_merl's bytes, read back with struct at hand-computed offsets."""
    rng = np.random.default_rng(8)
    values = rng.uniform(0.0, 5.0, (3, 90, 90, 180))
    values[2, 10, 20, 30] = np.nan
    path = write_merl(tmp_path / "w.binary", values)
    data = path.read_bytes()
    assert len(data) == 12 + 24 * N
    assert struct.unpack_from("<3i", data, 0) == (90, 90, 180)
    for c, i, j, k in [(0, 0, 0, 0), (0, 3, 4, 5), (1, 89, 1, 179), (2, 45, 88, 90), (1, 0, 89, 17)]:
        (got,) = struct.unpack_from("<d", data, _offset(c, i, j, k))
        assert got == pytest.approx(values[c, i, j, k] / SCALES[c], rel=1e-15)
    (missing,) = struct.unpack_from("<d", data, _offset(2, 10, 20, 30))
    assert missing < 0


# ------------------------------------------------------------------------ index convention


def test_sample_positions_formulas() -> None:
    """θ_h = (i/90)² π/2, θ_d = j π/180, φ_d = k π/180 (data_specs/merl_binary.md)."""
    th, td, pd = merl_sample_angles()
    assert th.shape == (90,) and td.shape == (90,) and pd.shape == (180,)
    assert th[30] == pytest.approx((30 / 90) ** 2 * math.pi / 2, rel=1e-15)
    assert td[45] == pytest.approx(math.pi / 4, rel=1e-15)
    assert pd[90] == pytest.approx(math.pi / 2, rel=1e-15)
    u, v, w = merl_index_coordinates(th, td, pd)
    np.testing.assert_allclose(u, np.arange(90), atol=1e-12)
    np.testing.assert_allclose(v, np.arange(90), atol=1e-12)
    np.testing.assert_allclose(w, np.arange(180), atol=1e-12)


def _reference_lookup(theta_half: float, theta_diff: float, phi_diff: float) -> tuple[int, int, int]:
    """BRDFRead.cpp's theta_half_index / theta_diff_index / phi_diff_index, transcribed."""
    if theta_half <= 0.0:
        i = 0
    else:
        i = int(math.sqrt(theta_half / (math.pi / 2.0) * 90 * 90))
    i = min(max(i, 0), 89)
    j = min(max(int(theta_diff / (math.pi * 0.5) * 90), 0), 89)
    if phi_diff < 0.0:
        phi_diff += math.pi
    k = min(max(int(phi_diff / math.pi * 360 / 2), 0), 179)
    return i, j, k


def test_reference_lookup_round_trip() -> None:
    """The reference reader's floor lookup maps our sample positions back to (i, j, k).

    Sample positions are the lower bin edges, where floor is ill-conditioned in floating
    point (e.g. 12 of the 90 exact θ_h edges land a rounding error below the integer), so
    each position is moved 1e-6 of a bin into its bin — through directions too (φ_h ≠ 0).
    """
    rng = np.random.default_rng(9)
    nudge = 1e-6
    for _ in range(400):
        i, j, k = int(rng.integers(90)), int(rng.integers(90)), int(rng.integers(180))
        th = ((i + nudge) / 90) ** 2 * math.pi / 2
        td = (j + nudge) * math.pi / 180
        pd = (k + nudge) * math.pi / 180
        assert _reference_lookup(th, td, pd) == (i, j, k)
        # the reference folds φ_d < 0 by +π: the same bin from the reciprocal side
        assert _reference_lookup(th, td, pd - math.pi) == (i, j, k)
        L, V = halfdiff_to_directions(th, td, pd, rng.uniform(-math.pi, math.pi))
        got = _reference_lookup(*(float(a) for a in directions_to_halfdiff(L, V)))
        # at θ_h → 0 the half vector's azimuth, hence φ_d, is undefined (any k is right)
        assert got[:2] == (i, j) and (i == 0 or got[2] == k)


# -------------------------------------------------------------------- model round trip


def test_model_round_trip_random_directions(smooth_merl) -> None:
    """Tabulate a smooth analytic model, read it back, compare at random directions
    (θ ≤ 80°) with the model itself: the error is the trilinear interpolation error."""
    model, brdf, _ = smooth_merl
    rng = np.random.default_rng(10)
    L, V = _random_hemisphere(rng, 200_000, np.radians(80)), _random_hemisphere(rng, 200_000, np.radians(80))
    got, without = brdf.eval_counted(L, V)
    want = model.eval(L, V)
    rel = (got - want) / want
    rms = float(np.sqrt(np.mean(rel**2)))
    assert without == 0
    assert rms < 0.02
    assert np.abs(rel).max() < 0.2


def test_model_exact_at_sample_positions(smooth_merl) -> None:
    """At the sample positions (any φ_h) the table reproduces the model to rounding."""
    model, brdf, _ = smooth_merl
    th, td, pd = merl_sample_angles()
    rng = np.random.default_rng(11)
    i, j, k = rng.integers(0, 90, 3000), rng.integers(0, 90, 3000), rng.integers(0, 180, 3000)
    L, V = halfdiff_to_directions(th[i], td[j], pd[k], rng.uniform(-np.pi, np.pi, 3000))
    above = (L[:, 2] > 1e-3) & (V[:, 2] > 1e-3)
    got, without = brdf.eval_counted(L[above], V[above])
    assert without == 0
    np.testing.assert_allclose(got, model.eval(L[above], V[above]), rtol=1e-9)
    assert above.sum() > 1500


def test_tabulate_marks_below_surface_missing() -> None:
    """Samples with tan θ_h tan θ_d |cos φ_d| ≥ 1 put L or V below the surface: missing."""
    values = tabulate_merl(shrmkit.load_brdf("lambert:albedo=0.5"))
    th, td, pd = merl_sample_angles()
    TH, TD, PD = np.meshgrid(th, td, pd, indexing="ij")
    below = np.tan(TH) * np.tan(TD) * np.abs(np.cos(PD)) >= 1.0
    missing = np.isnan(values[0])
    # exact except for samples within rounding of the horizon
    assert np.sum(missing != below) < 10
    np.testing.assert_allclose(values[:, ~missing], 0.5 / np.pi, rtol=1e-15)


def test_reciprocity_and_below_surface(smooth_merl) -> None:
    """eval(L, V) = eval(V, L) (φ_d folded by reciprocity); below the surface is 0, not counted."""
    _, brdf, _ = smooth_merl
    rng = np.random.default_rng(12)
    L, V = _random_hemisphere(rng, 5000), _random_hemisphere(rng, 5000)
    np.testing.assert_allclose(brdf.eval(L, V), brdf.eval(V, L), rtol=1e-12)
    below = V * np.array([1.0, 1.0, -1.0])
    rho, without = brdf.eval_counted(L, below)
    assert without == 0
    assert np.all(rho == 0.0)


def test_load_brdf_dispatch(smooth_merl) -> None:
    _, _, path = smooth_merl
    brdf = shrmkit.load_brdf(str(path))
    assert isinstance(brdf, MerlBRDF) and brdf.name == "smooth"


# ---------------------------------------------------------------------- missing samples


def _slow_interpolation(values: np.ndarray, u: float, v: float, w: float) -> np.ndarray:
    """Direct per-corner loop: weights over present corners, renormalized (the spec in
    data_specs/merl_binary.md written out one point at a time)."""
    u, v = min(max(u, 0.0), 89.0), min(max(v, 0.0), 89.0)
    w = w % 180.0
    i0, j0, k0 = min(int(u), 88), min(int(v), 88), int(w)
    out = np.zeros(3)
    for c in range(3):
        num = den = 0.0
        for di in (0, 1):
            for dj in (0, 1):
                for dk in (0, 1):
                    weight = (
                        (u - i0 if di else 1 - (u - i0))
                        * (v - j0 if dj else 1 - (v - j0))
                        * (w - k0 if dk else 1 - (w - k0))
                    )
                    sample = values[c, i0 + di, j0 + dj, (k0 + dk) % 180]
                    if not math.isnan(sample):
                        num += weight * sample
                        den += weight
        out[c] = num / den if den > 0 else 0.0
    return out


def test_missing_block_is_excluded_and_counted(tmp_path: Path) -> None:
    """A block of negative (missing) samples: points inside it are counted and return 0;
    points near it interpolate from present samples only (slow direct loop as reference);
    a constant table stays exactly constant next to the hole (no dilution by zeros)."""
    rng = np.random.default_rng(13)
    values = rng.uniform(0.5, 1.5, (3, 90, 90, 180))
    values[:, 20:30, 30:40, :] = np.nan
    path = write_merl(tmp_path / "hole.binary", values)
    brdf = read_merl(path)
    assert brdf.n_missing == 10 * 10 * 180

    # inside the hole: continuous indices with all 8 corners missing
    n_in = 500
    u = rng.uniform(20.01, 28.99, n_in)
    v = rng.uniform(30.01, 38.99, n_in)
    w = rng.uniform(0, 180, n_in)
    # around it: cells that straddle the hole's edge
    u2 = np.concatenate((rng.uniform(19.0, 20.0, 300), rng.uniform(29.0, 30.0, 300)))
    v2 = rng.uniform(29.5, 40.5, 600)
    w2 = rng.uniform(0, 180, 600)
    uu, vv, ww = np.concatenate((u, u2)), np.concatenate((v, v2)), np.concatenate((w, w2))
    L, V = halfdiff_to_directions((uu / 90) ** 2 * np.pi / 2, vv * np.pi / 180, ww * np.pi / 180, 0.3)
    assert np.all(L[:, 2] > 0) and np.all(V[:, 2] > 0)
    rho, without = brdf.eval_counted(L, V)
    assert without == n_in
    assert np.all(rho[:n_in] == 0.0)
    # recompute the index coordinates from the directions, as the reader does
    cu, cv, cw = merl_index_coordinates(*directions_to_halfdiff(L[n_in:], V[n_in:]))
    for n in range(0, 600, 7):
        np.testing.assert_allclose(rho[n_in + n], _slow_interpolation(brdf.values, cu[n], cv[n], cw[n]), rtol=1e-12)

    constant = np.full((3, 90, 90, 180), 0.25)
    constant[:, 20:30, 30:40, :] = np.nan
    brdf_c = MerlBRDF(constant, name="const")
    rho_c, without_c = brdf_c.eval_counted(L, V)
    assert without_c == n_in
    np.testing.assert_allclose(rho_c[n_in:], 0.25, rtol=1e-14)


def test_blocked_evaluation_matches_small_batches() -> None:
    """Queries spanning several evaluation blocks give the same values as small batches
    (the speed of 1e6 queries is measured in benchmarks/io_speed.py, not asserted here)."""
    rng = np.random.default_rng(14)
    brdf = MerlBRDF(rng.uniform(size=(3, 90, 90, 180)), name="random")
    L, V = _random_hemisphere(rng, 100_000), _random_hemisphere(rng, 100_000)
    whole = brdf.eval(L.reshape(10, -1, 3), V.reshape(10, -1, 3))
    assert whole.shape == (10, 10_000, 3)
    parts = np.concatenate([brdf.eval(L[k : k + 997], V[k : k + 997]) for k in range(0, 100_000, 997)])
    np.testing.assert_array_equal(whole.reshape(-1, 3), parts)


# ----------------------------------------------------------------------------- bad input


def _good_bytes() -> bytearray:
    data = bytearray(12 + 24 * N)
    struct.pack_into("<3i", data, 0, 90, 90, 180)
    return data


@pytest.mark.parametrize(
    ("mutate", "message"),
    [
        (lambda d: d[:-8], "truncated"),
        (lambda d: d[: 12 + 8 * 1000], "truncated"),
        (lambda d: d + b"\0" * 8, "trailing bytes"),
        (lambda d: d[:7], "shorter than the 12-byte"),
        (lambda d: struct.pack("<3i", 180, 90, 90) + d[12:], "only the MERL sampling"),
        (lambda d: struct.pack("<3i", 90, 90, 90) + d[12:], "imply"),
        (lambda d: struct.pack("<3i", -90, 90, 180) + d[12:], "not positive"),
        (lambda d: d[:100] + struct.pack("<d", math.nan) + d[108:], "non-finite"),
        (lambda d: d[: _offset(2, 89, 89, 179)] + struct.pack("<d", math.inf), "non-finite"),
    ],
)
def test_bad_files(tmp_path: Path, mutate, message: str) -> None:
    path = tmp_path / "bad.binary"
    path.write_bytes(bytes(mutate(bytes(_good_bytes()))))
    with pytest.raises(BadInputError, match=message) as info:
        read_merl(path)
    assert str(path) in str(info.value)


def test_missing_file(tmp_path: Path) -> None:
    with pytest.raises(BadInputError, match="no such file"):
        read_merl(tmp_path / "nope.binary")


def test_writer_rejects_bad_values(tmp_path: Path) -> None:
    path = tmp_path / "out.binary"
    with pytest.raises(BadInputError, match="shape"):
        write_merl(path, np.zeros((3, 90, 90, 90)))
    bad = np.zeros((3, 90, 90, 180))
    bad[0, 1, 2, 3] = -0.5
    with pytest.raises(BadInputError, match="non-negative"):
        write_merl(path, bad)
    bad[0, 1, 2, 3] = np.inf
    with pytest.raises(BadInputError, match="non-negative"):
        write_merl(path, bad)
    assert list(tmp_path.iterdir()) == []  # nothing written, no temporary left
