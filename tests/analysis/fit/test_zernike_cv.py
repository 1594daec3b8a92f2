"""The cross-validated Zernike fit (analysis/fit/zernike.py: fit_zernike_cv; analysis/fit/crossval.py).

Independent references: the held-out errors are recomputed here from the CURET measurements with
numpy's lstsq on each training fold (the Tikhonov rows of fit_zernike written out), and the
view-band relative RMS from its definition; the fit document is read back by load_brdf.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from shrmkit import load_brdf
from shrmkit.analysis.fit.crossval import fold_of
from shrmkit.analysis.fit.fit_file import write_fit_json
from shrmkit.analysis.fit.sampling import collect_samples
from shrmkit.analysis.fit.zernike import ZERNIKE_STATUS, basis_count, fit_zernike_cv, zernike_basis
from shrmkit.brdf_io.cornell import ScatteredBRDF
from shrmkit.brdf_io.curet import read_curet
from shrmkit.brdf_io.errors import BadInputError


def _band_rel_rms(theta_o: np.ndarray, cos_i: np.ndarray, pred: np.ndarray, y: np.ndarray, lo: float, hi: float,
                  last: bool) -> float:
    inside = (theta_o >= lo) & ((theta_o <= hi) if last else (theta_o < hi))
    d = ((pred[inside] - y[inside]) * cos_i[inside, None]) ** 2
    r = (y[inside] * cos_i[inside, None]) ** 2
    return float(np.sqrt(d.sum() / r.sum()))


def test_fold_split_is_deterministic_and_balanced() -> None:
    a, b = fold_of(205, 5, seed=3), fold_of(205, 5, seed=3)
    np.testing.assert_array_equal(a, b)
    assert sorted(np.bincount(a)) == [41] * 5
    assert not np.array_equal(a, fold_of(205, 5, seed=4))
    with pytest.raises(BadInputError, match="folds"):
        fold_of(3, 5)


def test_curet_held_out_error_recomputed_on_the_folds(shared_data) -> None:
    """CURET felt (sample 1): the reported errors are the held-out ones — recomputed here by
    refitting each training fold with numpy's lstsq at the chosen order and ridge and scoring the
    held-out measurements per view band — and they exceed the training error."""
    felt = read_curet(shared_data / "brdf" / "curet", 1)
    result = fit_zernike_cv(felt)
    assert result.model == "zernike" and result.status == ZERNIKE_STATUS
    n_max, ridge = result.params["n_max"], result.params["ridge"]
    samples = collect_samples(felt, max_theta_deg=80.0)
    assert result.n_samples == len(samples) == int(np.sum((felt.L[:, 2] >= np.cos(np.radians(80))) &
                                                          (felt.V[:, 2] >= np.cos(np.radians(80)))))
    # the split: a seeded permutation dealt round-robin (crossval.fold_of), written out
    order = np.random.default_rng(0).permutation(len(samples))
    fold = np.empty(len(samples), dtype=int)
    fold[order] = np.arange(len(samples)) % 5
    K = basis_count(n_max)
    A = zernike_basis(samples.L, samples.V, n_max)
    c = samples.cos_i[:, None]  # metric "rel": least squares on ρ cos θ_i
    pred = np.empty_like(samples.rho)
    for k in range(5):
        tr = fold != k
        Aw, yw = A[tr] * c[tr], samples.rho[tr] * c[tr]
        if ridge > 0:
            top = np.linalg.norm(Aw, 2)
            Aw = np.concatenate([Aw, np.sqrt(ridge) * top * np.eye(K)])
            yw = np.concatenate([yw, np.zeros((K, 3))])
        coef = np.linalg.lstsq(Aw, yw, rcond=None)[0]
        pred[~tr] = A[~tr] @ coef
    theta_o = np.degrees(np.arccos(samples.V[:, 2]))
    edges = (0, 15, 30, 45, 60, 70, 80, 90)
    per_band = {}
    for j, (lo, hi) in enumerate(zip(edges[:-1], edges[1:], strict=True)):
        n = int(np.sum((theta_o >= lo) & ((theta_o <= hi) if j == 6 else (theta_o < hi))))
        if n >= 10:
            per_band[(lo, hi)] = _band_rel_rms(theta_o, samples.cos_i, pred, samples.rho, lo, hi, j == 6)
    worst = max(per_band, key=per_band.get)
    assert (result.worst.lo_deg, result.worst.hi_deg) == worst
    assert result.worst.rel_rms == pytest.approx(per_band[worst], rel=1e-6)
    overall = np.sqrt(np.sum(((pred - samples.rho) * c) ** 2) / np.sum((samples.rho * c) ** 2))
    assert result.errors["rel_rms"] == pytest.approx(overall, rel=1e-6)
    # held out is harder than training; felt is smooth: a successful fit (RH02 Fig. 8's kind of surface)
    assert result.params["training"]["errors"]["rel_rms"] < result.errors["rel_rms"] < 0.1
    assert result.success and result.worst.rel_rms < 0.2
    # the grid it was chosen from: no setting has a smaller held-out worst band
    grid = result.params["cv"]["grid"]
    assert min(g["worst_band"]["rel_rms"] for g in grid) == pytest.approx(result.worst.rel_rms, rel=1e-9)


def test_fixed_order_and_the_fit_document_round_trip(tmp_path, shared_data) -> None:
    """order=8, ridge=0 on velvet (sample 7): a training error of 0.1 that does not hold out
    (the held-out worst band fails); the document loads back as the same expansion."""
    velvet = read_curet(shared_data / "brdf" / "curet", 7)
    result = fit_zernike_cv(velvet, n_max=8, ridge=0.0)
    assert result.params["n_max"] == 8 and result.params["ridge"] == 0.0
    assert result.params["training"]["errors"]["rel_rms"] < 0.15 < result.errors["rel_rms"]
    assert not result.success and result.message.startswith("failed: held-out rel. RMS")
    path = write_fit_json(tmp_path / "velvet.json", result, source="abrdf.dat#7")
    doc = json.loads(path.read_text())
    assert doc["model"] == "zernike" and doc["fit"]["status"] == ZERNIKE_STATUS and doc["fit"]["success"] is False
    assert doc["fit"]["worst_band"]["rel_rms"] == pytest.approx(result.worst.rel_rms)
    back = load_brdf(path)
    rng = np.random.default_rng(0)
    L = rng.normal(size=(50, 3))
    L[:, 2] = np.abs(L[:, 2])
    L /= np.linalg.norm(L, axis=1, keepdims=True)
    V = L[::-1] * np.array([-1, 1, 1])
    np.testing.assert_allclose(back.eval(L, V), result.brdf.eval(L, V), rtol=1e-13, atol=1e-15)


def test_exact_expansion_is_recovered_with_a_tiny_held_out_error() -> None:
    """Data in the span of order 2 (5 terms) at 300 random pairs: the held-out error is round-off
    and the chosen order holds the data (2 or more)."""
    rng = np.random.default_rng(2)
    z = rng.uniform(0.05, 1.0, (2, 300))
    p = rng.uniform(0, 2 * np.pi, (2, 300))
    d = np.stack([np.sqrt(1 - z * z) * np.cos(p), np.sqrt(1 - z * z) * np.sin(p), z], axis=-1)
    coeffs = np.array([3.0, 0.2, -0.1, 0.3, 0.05])
    rho = zernike_basis(d[0], d[1], 2) @ coeffs
    result = fit_zernike_cv(ScatteredBRDF(d[0], d[1], np.repeat(rho[:, None], 3, 1)))
    assert result.worst.rel_rms < 1e-8 and result.params["n_max"] >= 2 and result.success
