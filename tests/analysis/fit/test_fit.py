"""Unit tests of shrmkit.analysis.fit: sampling weights, bounded least squares, metrics,
bands, and a quick analytic round trip. Each test names its independent reference."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.optimize import minimize, nnls

from shrmkit.analysis.fit import fit_brdf
from shrmkit.analysis.fit.fit_file import write_fit_json
from shrmkit.analysis.fit.metrics import log_epsilon, log_rms, rel_rms
from shrmkit.analysis.fit.objective import solve_bounded_lsq
from shrmkit.analysis.fit.sampling import FitSamples, collect_samples, sample_halfdiff
from shrmkit.analysis.fit.summary import band_errors
from shrmkit.brdf_io.errors import BadInputError
from shrmkit.brdf_io.models import CookTorrance, Lafortune, LafortuneLobe, Lambert, SimplifiedMicrofacet, rgb
from shrmkit.brdf_io.specs import load_brdf


def lafortune(kd, lobes) -> Lafortune:
    return Lafortune(
        kd=rgb(kd),
        lobes=tuple(LafortuneLobe(cxy=rgb(a), cz=rgb(b), n=rgb(n), ks=rgb(k)) for a, b, n, k in lobes),
    )


@pytest.mark.parametrize("max_theta", [90.0, 80.0, 60.0])
def test_sample_weights_integrate_the_pair_measure(max_theta):
    """Closed form: ∫∫ dω_i dω_o over θ_i, θ_o <= θ_max is (2π (1 − cos θ_max))²."""
    _, _, w = sample_halfdiff(1 << 16, seed=3, max_theta_deg=max_theta)
    ref = (2 * np.pi * (1 - np.cos(np.radians(max_theta)))) ** 2
    assert w.sum() == pytest.approx(ref, rel=5e-3)


def test_sample_weights_integrate_a_function():
    """Closed form: ∫∫ cos θ_i cos θ_o dω_i dω_o over both hemispheres is π²."""
    L, V, w = sample_halfdiff(1 << 16, seed=5, max_theta_deg=90.0)
    assert np.sum(w * L[:, 2] * V[:, 2]) == pytest.approx(np.pi**2, rel=5e-3)


def test_samples_are_deterministic_and_seeded():
    L1, _, _ = sample_halfdiff(4096, seed=1)
    L2, _, _ = sample_halfdiff(4096, seed=1)
    L3, _, _ = sample_halfdiff(4096, seed=2)
    assert np.array_equal(L1, L2)
    assert not np.array_equal(L1[:100], L3[:100])


def _brute_force_qp(G, b, a):
    """Reference: scipy SLSQP on min cᵀGc − 2bᵀc, c >= 0, aᵀc <= 1."""
    m = len(b)
    cons = [] if a is None else [{"type": "ineq", "fun": lambda c: 1.0 - a @ c, "jac": lambda c: -a}]
    best = None
    for x0 in (np.zeros(m), np.full(m, 0.1), np.full(m, 1.0 / m)):
        res = minimize(lambda c: c @ G @ c - 2 * b @ c, x0, jac=lambda c: 2 * G @ c - 2 * b,
                       bounds=[(0, None)] * m, constraints=cons, method="SLSQP",
                       options={"ftol": 1e-15, "maxiter": 500})
        if best is None or res.fun < best.fun:
            best = res
    return best.x, best.fun


@pytest.mark.parametrize("trial", range(12))
def test_bounded_lsq_matches_reference(trial):
    """Reference: scipy.optimize.nnls (no energy bound) and SLSQP (with the bound)."""
    rng = np.random.default_rng(trial)
    m = 1 + trial % 4
    A = rng.random((60, m))
    y = A @ (rng.random(m) * rng.choice([-1.0, 1.0], m)) + 0.05 * rng.standard_normal(60)
    G, b = (A.T @ A)[None], (A.T @ y)[None]
    c = solve_bounded_lsq(G, b)[0]
    c_ref, _ = nnls(A, y)
    assert np.allclose(c, c_ref, atol=1e-8)
    a = rng.random(m) * 3.0
    c = solve_bounded_lsq(G, b, a)[0]
    q = c @ G[0] @ c - 2 * b[0] @ c
    _, q_ref = _brute_force_qp(G[0], b[0], a)
    assert np.all(c >= 0) and a @ c <= 1 + 1e-9
    assert q <= q_ref + 1e-9 * max(1.0, abs(q_ref))


def _toy_samples(n=500, seed=0):
    rng = np.random.default_rng(seed)
    L, V, w = sample_halfdiff(2048, seed=seed)
    rho = rng.random((len(L), 3)) + 0.1
    return FitSamples(L=L, V=V, rho=rho, weight=w, n_dropped=0, source="toy")


def test_metrics_closed_forms():
    """Closed forms: a model (1+δ)·y has rel_rms = |δ|; a model k·y with ε → 0 has
    log_rms = |ln k|; the truth has both zero."""
    s = _toy_samples()
    assert rel_rms(s, s.rho) == 0.0 and log_rms(s, s.rho) == 0.0
    assert rel_rms(s, 1.07 * s.rho) == pytest.approx(0.07, rel=1e-12)
    assert log_rms(s, 2.0 * s.rho, eps=1e-300) == pytest.approx(np.log(2.0), rel=1e-12)
    assert log_epsilon(s) == pytest.approx(0.01 * np.average((s.rho * s.cos_i[:, None]).mean(1), weights=s.weight))


def test_band_errors_partition_the_samples():
    """The bands partition the samples; a uniform 5 % error shows up as 5 % in every band."""
    s = _toy_samples()
    bands = band_errors(s, 1.05 * s.rho)
    assert sum(b.n for b in bands) == len(s)
    assert all(b.rel_rms == pytest.approx(0.05, rel=1e-10) for b in bands)
    with pytest.raises(ValueError):
        band_errors(s, s.rho, edges_deg=(0.0, 50.0, 40.0))


def test_roundtrip_analytic_lafortune_one_lobe():
    """Reference: the known parameters of the Lafortune model the data come from."""
    truth = lafortune((0.3, 0.2, 0.1), [(-1.0, 0.95, 60.0, (0.5, 0.6, 0.7))])
    r = fit_brdf(truth, "lafortune", lobes=1, n_samples=8192)
    assert r.success and r.status in ("XTOL_REACHED", "FTOL_REACHED", "SUCCESS", "STOPVAL_REACHED")
    lobe = r.params["lobes"][0]
    assert np.allclose(r.params["kd"], [0.3, 0.2, 0.1], rtol=1e-4)
    assert np.allclose(lobe["ks"], [0.5, 0.6, 0.7], rtol=1e-4)
    assert lobe["cxy"] == pytest.approx(-1.0, rel=1e-5) and lobe["cz"] == pytest.approx(0.95, rel=1e-5)
    assert lobe["n"] == pytest.approx(60.0, rel=1e-4)
    assert r.errors["rel_rms"] < 1e-4
    # the fitted BRDF is an ordinary model: its spec string loads back to the same values
    again = load_brdf(r.brdf.to_spec())
    L, V, _ = sample_halfdiff(512, seed=9)
    assert np.allclose(again.eval(L, V), truth.eval(L, V), rtol=1e-4)


@pytest.mark.parametrize("dist", ["beckmann", "ggx"])
def test_roundtrip_analytic_cook_torrance(dist):
    """Reference: the known parameters of the Cook–Torrance model the data come from."""
    truth = CookTorrance(kd=rgb((0.3, 0.2, 0.1)), ks=rgb((0.3, 0.4, 0.5)), alpha=0.12,
                         f0=rgb((0.05, 0.5, 0.9)), distribution=dist)
    r = fit_brdf(truth, "cook-torrance", distribution=dist, n_samples=8192)
    assert r.success
    assert r.params["alpha"] == pytest.approx(0.12, rel=1e-4)
    for key, ref in (("kd", truth.kd), ("ks", truth.ks), ("f0", truth.f0)):
        assert np.allclose(r.params[key], ref, rtol=1e-3), key
    assert r.errors["rel_rms"] < 1e-4


def test_roundtrip_analytic_microfacet():
    """Reference: RH02 eq. 11 with known σ and RGB ks."""
    truth = SimplifiedMicrofacet(sigma=0.15, ks=rgb((0.2, 0.5, 0.9)))
    r = fit_brdf(truth, "microfacet", n_samples=4096)
    assert r.success
    assert r.params["sigma"] == pytest.approx(0.15, rel=1e-5)
    assert np.allclose(r.params["ks"], [0.2, 0.5, 0.9], rtol=1e-5)


def test_fit_is_deterministic_given_seed():
    truth = lafortune((0.2, 0.2, 0.2), [(-1.0, 1.0, 20.0, (0.3, 0.3, 0.3))])
    noisy_samples = collect_samples(truth, n_samples=2048, seed=4)
    rng = np.random.default_rng(0)
    rho = noisy_samples.rho * (1 + 0.05 * rng.standard_normal(noisy_samples.rho.shape))
    s = FitSamples(noisy_samples.L, noisy_samples.V, rho, noisy_samples.weight, 0, "noisy")
    a = fit_brdf(truth, "lafortune", lobes=2, samples=s, seed=7, starts=2)
    b = fit_brdf(truth, "lafortune", lobes=2, samples=s, seed=7, starts=2)
    assert a.brdf.to_spec() == b.brdf.to_spec() and a.errors == b.errors


def test_energy_constraint_holds_on_non_physical_data():
    """Data 3× brighter than a Lambertian with albedo 0.9 (albedo 2.7): the energy-
    conserving fit stops at kd = 1 (Lafortune energy bound), the unconstrained one does not."""
    data = Lambert(albedo=rgb(0.9))
    s = collect_samples(data, n_samples=2048)
    s = FitSamples(s.L, s.V, 3.0 * s.rho, s.weight, 0, "bright")
    r = fit_brdf(data, "lafortune", samples=s, starts=1)
    total = np.asarray(r.params["kd"]) + sum(
        np.asarray(lobe["ks"]) * 2 * np.pi / (lobe["n"] + 2) for lobe in r.params["lobes"]
    )
    assert np.all(total <= 1 + 1e-9)
    free = fit_brdf(data, "lafortune", samples=s, starts=1, energy_conserving=False)
    assert free.errors["rel_rms"] < r.errors["rel_rms"]


def test_log_metric_fit_recovers_truth():
    """The log metric has the same minimum (zero) at the truth."""
    truth = lafortune((0.1, 0.1, 0.2), [(-1.0, 0.9, 30.0, (0.4, 0.3, 0.2))])
    r = fit_brdf(truth, "lafortune", metric="log", n_samples=4096, starts=2)
    assert r.params["lobes"][0]["n"] == pytest.approx(30.0, rel=1e-3)
    assert r.errors["log_rms"] < 1e-4


def test_json_document_loads_back_as_the_model(tmp_path):
    """Reference: load_brdf (brdf_io/specs.py) reads the written file's model_spec."""
    truth = lafortune((0.25, 0.2, 0.15), [(-1.0, 0.97, 40.0, (0.2, 0.3, 0.4))])
    r = fit_brdf(truth, "lafortune", n_samples=4096, starts=2)
    path = write_fit_json(tmp_path / "fit.json", r, source="analytic")
    doc = json.loads(path.read_text())
    assert doc["model_spec"] == r.brdf.to_spec()
    assert set(doc) >= {"params", "errors", "bands", "provenance", "fit", "options"}
    assert [p.name for p in tmp_path.iterdir()] == ["fit.json"]  # no temporary left
    back = load_brdf(path)
    L, V, _ = sample_halfdiff(256, seed=2)
    assert np.allclose(back.eval(L, V), truth.eval(L, V), rtol=1e-4)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"model": "phong"}, "unknown model"),
        ({"metric": "l1"}, "unknown metric"),
        ({"lobes": 0}, "lobes"),
        ({"distribution": "blinn"}, "distribution"),
        ({"starts": 0}, "starts"),
        ({"n_samples": 10}, "n_samples"),
    ],
)
def test_bad_options_raise_bad_input(kwargs, match):
    with pytest.raises(BadInputError, match=match):
        fit_brdf(Lambert(albedo=rgb(0.5)), **kwargs)


def test_zero_brdf_is_bad_input():
    with pytest.raises(BadInputError, match="zero everywhere"):
        fit_brdf(Lambert(albedo=rgb(0.0)), n_samples=1024)


def test_spec_string_input():
    r = fit_brdf("lambert:albedo=0.4", "lafortune", n_samples=1024, starts=1)
    assert np.allclose(r.params["kd"], 0.4, rtol=1e-6)
