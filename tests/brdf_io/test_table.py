"""shrmkit BRDF table (.npz) reader/writer and interpolation (brdf_io/table.py, brdf_io/masked_grid.py)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import shrmkit
from shrmkit.brdf_io.errors import BadInputError
from shrmkit.brdf_io.halfdiff import spherical_angles
from shrmkit.brdf_io.masked_grid import interpolate_excluding_missing
from shrmkit.brdf_io.merl import MerlBRDF
from shrmkit.brdf_io.table import (
    TableBRDF,
    read_table,
    tabulate_table,
    write_table,
)

SMOOTH_SPEC = "lafortune:kd=0.2/0.3/0.4,cxy=-1,cz=1,n=6,ks=0.5/0.6/0.7"


def _direction(theta: np.ndarray, phi: np.ndarray) -> np.ndarray:
    return np.stack((np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)), axis=-1)


def _grid() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    # deliberately non-uniform
    theta_i = np.radians(np.concatenate((np.arange(0, 60, 2.0), np.arange(60, 85.1, 1.0))))
    theta_o = np.radians(np.linspace(0, 85, 70) ** 1.0)
    phi_d = np.radians(np.concatenate((np.arange(0, 150, 3.0), np.arange(150, 180.1, 1.5))))
    return theta_i, theta_o, phi_d


def _save_npz(path: Path, **arrays: object) -> Path:
    with path.open("wb") as f:
        np.savez(f, **arrays)
    return path


def _valid_arrays() -> dict[str, object]:
    meta = {"format": "shrmkit-brdf-table", "format_version": 1, "units": "1/sr", "name": "x"}
    return {
        "theta_i": np.array([0.0, 0.5, 1.0]),
        "theta_o": np.array([0.0, 0.7, 1.4]),
        "phi_d": np.array([0.0, 1.0, 2.0, 3.0]),
        "values": np.ones((3, 3, 4, 3)),
        "metadata": np.array(json.dumps(meta)),
    }


def test_linear_function_reproduced_exactly(tmp_path: Path) -> None:
    """Trilinear interpolation in angle reproduces a function linear in (θ_i, θ_o, φ_d)
    exactly (closed form), on a non-uniform grid, including φ_d < 0 folded by symmetry."""
    theta_i, theta_o, phi_d = _grid()
    coeff = np.array([[0.1, 0.2, 0.3, 0.05], [0.4, 0.1, 0.0, 0.02], [0.3, 0.0, 0.5, 0.01]])  # per channel

    def linear(ti, to, pd):
        return np.stack([c[0] + c[1] * ti + c[2] * to + c[3] * pd for c in coeff], axis=-1)

    values = linear(*np.meshgrid(theta_i, theta_o, phi_d, indexing="ij"))
    path = write_table(tmp_path / "lin.npz", values, theta_i=theta_i, theta_o=theta_o, phi_d=phi_d)
    table = read_table(path)
    rng = np.random.default_rng(1)
    ti, to = rng.uniform(0, np.radians(85), (2, 20000))
    phi_i = rng.uniform(-np.pi, np.pi, 20000)
    dphi = rng.uniform(-np.pi, np.pi, 20000)
    rho, without = table.eval_counted(_direction(ti, phi_i), _direction(to, phi_i + dphi))
    assert without == 0
    np.testing.assert_allclose(rho, linear(ti, to, np.abs(dphi)), rtol=1e-11, atol=1e-12)


def test_model_round_trip(tmp_path: Path) -> None:
    """Tabulate a smooth model, read back: exact at the grid points, small interpolation
    error at random directions, metadata recorded."""
    model = shrmkit.load_brdf(SMOOTH_SPEC)
    theta_i, theta_o, phi_d = _grid()
    path = write_table(tmp_path / "m.npz", model, theta_i=theta_i, theta_o=theta_o, phi_d=phi_d,
                       provenance="unit test")
    table = shrmkit.load_brdf(str(path))
    assert isinstance(table, TableBRDF) and table.kind == "tabulated"
    assert table.metadata["provenance"] == "unit test"
    assert table.metadata["units"] == "1/sr" and table.metadata["format_version"] == 1
    assert table.name == model.name and table.n_missing == 0
    # grid points
    ti, to, pd = np.meshgrid(theta_i[::7], theta_o[::9], phi_d[::11], indexing="ij")
    L, V = _direction(ti, 0.4), _direction(to, 0.4 + pd)
    np.testing.assert_allclose(table.eval(L, V), model.eval(L, V), rtol=1e-10)
    # random directions
    rng = np.random.default_rng(2)
    t = rng.uniform(0, np.radians(80), (2, 50000))
    phi = rng.uniform(-np.pi, np.pi, (2, 50000))
    L, V = _direction(t[0], phi[0]), _direction(t[1], phi[1])
    want = model.eval(L, V)
    rel = (table.eval(L, V) - want) / want
    assert np.sqrt(np.mean(rel**2)) < 0.01


def test_missing_samples_excluded_and_counted(tmp_path: Path) -> None:
    """A NaN block: queries whose cell is all missing are counted and give 0; next to it a
    constant table stays constant (missing samples do not dilute); compare a scalar table."""
    theta_i, theta_o, phi_d = _grid()
    values = np.full((theta_i.size, theta_o.size, phi_d.size), 0.3)
    values[10:20, 20:30, :] = np.nan
    table = read_table(write_table(tmp_path / "s.npz", values, theta_i=theta_i, theta_o=theta_o, phi_d=phi_d))
    assert table.values.ndim == 3 and table.n_missing == 10 * 10 * phi_d.size
    rng = np.random.default_rng(3)
    inside_i = rng.uniform(theta_i[10] + 1e-3, theta_i[19] - 1e-3, 300)
    inside_o = rng.uniform(theta_o[20] + 1e-3, theta_o[29] - 1e-3, 300)
    near_i = rng.uniform(theta_i[8], theta_i[22], 700)
    # cells that straddle the block's θ_o edges (one corner missing, one present)
    below, above = rng.uniform(theta_o[18], theta_o[20], 700), rng.uniform(theta_o[29], theta_o[31], 700)
    near_o = np.where(rng.uniform(size=700) < 0.5, below, above)
    ti = np.concatenate((inside_i, near_i))
    to = np.concatenate((inside_o, near_o))
    pd = rng.uniform(0, np.pi, ti.size)
    rho, without = table.eval_counted(_direction(ti, 0.0), _direction(to, pd))
    assert without == 300
    assert np.all(rho[:300] == 0.0)
    np.testing.assert_allclose(rho[300:], 0.3, rtol=1e-14)
    assert rho.shape == (1000, 3)


def test_shared_helper_against_slow_loop() -> None:
    """interpolate_excluding_missing vs a direct per-corner loop (renormalized weights),
    with scattered missing samples, a periodic axis and clamping outside the grid."""
    rng = np.random.default_rng(4)
    grid = rng.uniform(size=(5, 6, 7, 2))
    grid[rng.uniform(size=grid.shape) < 0.3] = np.nan
    coords = (rng.uniform(-0.5, 4.5, 400), rng.uniform(0, 5, 400), rng.uniform(-3, 10, 400))
    got, no_data = interpolate_excluding_missing(grid, coords, periodic=(False, False, True))
    for n in range(400):
        u = min(max(coords[0][n], 0.0), 4.0)
        v = coords[1][n]
        w = coords[2][n] % 7
        i0, j0, k0 = min(int(u), 3), min(int(v), 4), int(w)
        for c in range(2):
            num = den = 0.0
            for di in (0, 1):
                for dj in (0, 1):
                    for dk in (0, 1):
                        wt = ((u - i0) if di else (1 - u + i0)) * ((v - j0) if dj else (1 - v + j0)) * (
                            (w - k0) if dk else (1 - w + k0)
                        )
                        s = grid[i0 + di, j0 + dj, (k0 + dk) % 7, c]
                        if not np.isnan(s):
                            num += wt * s
                            den += wt
            if den > 0:
                assert got[n, c] == pytest.approx(num / den, rel=1e-12)
            else:
                assert got[n, c] == 0.0 and no_data[n]


def test_merl_source_no_data_becomes_nan() -> None:
    """Tabulating a MERL table with a hole marks the points without data as missing (NaN).

    The hole is θ_d index ≥ 40, i.e. θ_d ≥ 40°. In the plane of incidence θ_d is
    |θ_i − θ_o|/2 for φ_d = 0 (same side) and (θ_i + θ_o)/2 for φ_d = π (closed forms).
    """
    values = np.full((3, 90, 90, 180), 0.2)
    values[:, :, 40:, :] = np.nan
    merl = MerlBRDF(values, name="hole")
    theta_deg = np.array([0.0, 10.0, 30.0, 85.0])
    theta = np.radians(theta_deg)
    out = tabulate_table(merl, theta_i=theta, theta_o=theta, phi_d=np.array([0.0, np.pi]))
    td_same = np.abs(theta_deg[:, None] - theta_deg[None, :]) / 2
    td_opposite = (theta_deg[:, None] + theta_deg[None, :]) / 2
    expected = np.stack((td_same >= 40, td_opposite >= 40), axis=-1)
    assert expected.sum() >= 4 and (~expected).sum() >= 4
    assert np.array_equal(np.isnan(out[..., 0]), expected)
    np.testing.assert_allclose(out[~np.isnan(out)], 0.2)


def test_rewrite_table_without_grid(tmp_path: Path) -> None:
    theta_i, theta_o, phi_d = _grid()
    rng = np.random.default_rng(5)
    values = rng.uniform(size=(theta_i.size, theta_o.size, phi_d.size, 3))
    values[0, 0, 0, 1] = np.nan
    first = read_table(write_table(tmp_path / "a.npz", values, theta_i=theta_i, theta_o=theta_o, phi_d=phi_d))
    second = read_table(write_table(tmp_path / "b.npz", first))
    np.testing.assert_array_equal(second.values, values)
    assert second.n_missing == 1


# ----------------------------------------------------------------------------- bad input


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"values": np.ones((3, 3, 3, 3))}, "shape"),
        ({"values": np.ones((3, 3, 4, 2))}, "shape"),
        ({"theta_i": np.array([0.0, 1.0, 0.5])}, "strictly increasing"),
        ({"theta_o": np.array([0.0, np.nan, 1.4])}, "non-finite"),
        ({"theta_o": np.array([0.0, 0.7, 2.0])}, "outside"),
        ({"phi_d": np.ones((2, 2))}, "1-D"),
        ({"values": -np.ones((3, 3, 4, 3))}, "negative"),
        ({"values": np.full((3, 3, 4, 3), np.inf)}, "infinite"),
        ({"values": np.array(["a"] * 108).reshape(3, 3, 4, 3)}, "dtype"),
        ({"metadata": np.array(json.dumps({"format": "shrmkit-brdf-table", "format_version": 2,
                                           "units": "1/sr"}))}, "format_version 2"),
        ({"metadata": np.array(json.dumps({"format": "other", "format_version": 1}))}, "format"),
        ({"metadata": np.array(json.dumps({"format": "shrmkit-brdf-table", "format_version": 1,
                                           "units": "sr"}))}, "units"),
        ({"metadata": np.array("{not json")}, "JSON"),
        ({"metadata": np.array([1.0])}, "JSON string"),
    ],
)
def test_reader_rejects(tmp_path: Path, change: dict, message: str) -> None:
    arrays = _valid_arrays()
    arrays.update(change)
    path = _save_npz(tmp_path / "bad.npz", **arrays)
    with pytest.raises(BadInputError, match=message) as info:
        read_table(path)
    assert str(path) in str(info.value)


def test_reader_valid_baseline(tmp_path: Path) -> None:
    """The unmodified arrays of the bad-input cases are a valid table (so each case fails
    for its own reason)."""
    table = read_table(_save_npz(tmp_path / "ok.npz", **_valid_arrays()))
    assert table.name == "x" and table.values.shape == (3, 3, 4, 3)


@pytest.mark.parametrize("key", ["theta_i", "values", "metadata"])
def test_reader_missing_key(tmp_path: Path, key: str) -> None:
    arrays = _valid_arrays()
    del arrays[key]
    with pytest.raises(BadInputError, match=f"missing key.*{key}"):
        read_table(_save_npz(tmp_path / "k.npz", **arrays))


def test_reader_not_npz(tmp_path: Path) -> None:
    path = tmp_path / "junk.npz"
    path.write_bytes(b"PK\x03\x04 definitely not a zip")
    with pytest.raises(BadInputError, match="not a readable"):
        read_table(path)
    with pytest.raises(BadInputError, match="no such file"):
        read_table(tmp_path / "absent.npz")


def test_writer_rejects_and_leaves_nothing(tmp_path: Path) -> None:
    theta = np.array([0.0, 0.5, 1.0])
    phi = np.array([0.0, 3.0])
    out = tmp_path / "t.npz"
    with pytest.raises(BadInputError, match="needs the grid"):
        write_table(out, shrmkit.load_brdf("lambert:albedo=0.5"))
    with pytest.raises(BadInputError, match="negative"):
        write_table(out, -np.ones((3, 3, 2)), theta_i=theta, theta_o=theta, phi_d=phi)
    with pytest.raises(BadInputError, match="strictly increasing"):
        write_table(out, np.ones((3, 3, 2)), theta_i=theta[::-1], theta_o=theta, phi_d=phi)
    with pytest.raises(BadInputError, match="shape"):
        write_table(out, np.ones((3, 2, 2)), theta_i=theta, theta_o=theta, phi_d=phi)
    assert list(tmp_path.iterdir()) == []


def test_failed_write_keeps_old_file(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A write that fails half-way leaves the previous file intact and no temporary."""
    path = tmp_path / "keep.npz"
    path.write_bytes(b"old")

    def failing(f, **arrays):
        f.write(b"partial")
        raise OSError("disk full")

    monkeypatch.setattr(np, "savez_compressed", failing)
    theta = np.array([0.0, 1.0])
    with pytest.raises(BadInputError, match="cannot write .disk full.; nothing was written") as raised:
        write_table(path, np.ones((2, 2, 2)), theta_i=theta, theta_o=theta, phi_d=theta)
    assert str(path) in str(raised.value)
    assert path.read_bytes() == b"old"
    assert [p.name for p in tmp_path.iterdir()] == ["keep.npz"]


def test_phi_fold_and_below_surface() -> None:
    """φ_d enters as |φ_o − φ_i| folded to [0, π]; below-surface queries give 0, uncounted."""
    rng = np.random.default_rng(6)
    theta = np.linspace(0, 1.5, 8)
    phi = np.linspace(0, np.pi, 9)
    table = TableBRDF(theta, theta, phi, rng.uniform(size=(8, 8, 9, 3)), name="r")
    ti, to = rng.uniform(0, 1.5, (2, 100))
    phi_i, d = rng.uniform(-np.pi, np.pi, (2, 100))
    base = table.eval(_direction(ti, phi_i), _direction(to, phi_i + d))
    for other in (-d, d + 2 * np.pi, 2 * np.pi - d):
        np.testing.assert_allclose(table.eval(_direction(ti, phi_i), _direction(to, phi_i + other)), base)
    L = _direction(ti, phi_i)
    V = _direction(to, phi_i + d) * np.array([1, 1, -1])
    rho, without = table.eval_counted(L, V)
    assert without == 0 and np.all(rho == 0)
    assert spherical_angles(L)[0] == pytest.approx(ti)
