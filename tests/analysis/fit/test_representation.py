"""One representation for scattered measurements (analysis/fit/representation.py).

Independent reference for the orders: a known analytic model, evaluated wherever the order
analysis asks (an infinitely dense table of it), against the orders of the representation the
chooser picks from the same model sampled only at CURET's 205 measured geometries.

Tolerances found honest (measured, ε = 0.03, bands rule): a model inside a candidate family
(Cook–Torrance) is recovered to 10⁻⁹ held out and gives the same (F, P); a two-lobe Lafortune
material (forward and retro lobes: no one-lobe model holds it) goes through the Zernike expansion
(held-out worst band 0.016 at the samples) whose orders come out (9, 5) against the model's
(6, 3): a polynomial of order 11 matched at 205 points carries energy at higher SH orders between
and beyond them (above 80°, where CURET has no samples), so through Zernike F may be up to 3 and P
up to 2 above the material's, never below.
"""

from __future__ import annotations

import numpy as np
import pytest

from shrmkit import load_brdf
from shrmkit.analysis.fit.representation import CANDIDATES, choose_representation
from shrmkit.analysis.orders import choose_orders
from shrmkit.brdf_io.cornell import ScatteredBRDF
from shrmkit.brdf_io.curet import read_curet
from shrmkit.brdf_io.errors import BadInputError


def _sampled(shared_data, spec: str) -> tuple[ScatteredBRDF, object]:
    geo = read_curet(shared_data / "brdf" / "curet", 1)
    model = load_brdf(spec)
    return ScatteredBRDF(geo.L, geo.V, model.eval(geo.L, geo.V), name="synthetic"), model


def test_lambertian_data_and_the_choice_record(shared_data) -> None:
    """Lambert at CURET's geometries: every candidate holds it; the record lists all three with
    held-out errors, and the chosen one's orders are Lambert's."""
    data, model = _sampled(shared_data, "lambert:albedo=0.5")
    choice = choose_representation(data, candidates=("zernike", "lafortune"))
    assert [c.model for c in choice.candidates] == ["zernike", "lafortune"]
    assert all(c.success and c.score < 1e-6 for c in choice.candidates)
    assert choice.success and choice.isotropy is not None and not choice.isotropy.anisotropic
    doc = choice.as_dict()
    assert doc["model"] == choice.model and doc["line"].startswith("analysed through")
    assert len(doc["candidates"]) == 2 and load_brdf(doc["spec"]) is not None
    a, b = choose_orders(choice.brdf, eps=0.03), choose_orders(model, eps=0.03)
    assert (a.F, a.P) == (b.F, b.P)


def test_refuses_what_is_not_scattered() -> None:
    with pytest.raises(BadInputError, match="analyse it directly"):
        choose_representation(load_brdf("lambert:albedo=0.5"))
    assert CANDIDATES == ("lafortune", "cook-torrance", "zernike")


@pytest.mark.slow
@pytest.mark.parametrize(
    ("spec", "family", "dF", "dP"),
    [
        ("cook-torrance:kd=0.3,ks=0.5,alpha=0.3", "cook-torrance", 0, 0),
        ("lafortune:kd=0.4,cxy=-1,cz=1,n=8,ks=0.5,cxy2=1,cz2=1,n2=3,ks2=0.3", "zernike", 3, 2),
    ],
)
def test_orders_through_the_chosen_representation(shared_data, spec: str, family: str, dF: int, dP: int) -> None:
    data, model = _sampled(shared_data, spec)
    choice = choose_representation(data, isotropy=False)
    assert choice.model == family and choice.success
    # the chosen one has the smallest held-out worst band of all candidates
    assert choice.chosen.score == min(c.score for c in choice.candidates if c.success)
    for eps in (0.1, 0.03):
        got, ref = choose_orders(choice.brdf, eps=eps), choose_orders(model, eps=eps)
        assert 0 <= got.F - ref.F <= dF and 0 <= got.P - ref.P <= dP, (eps, (got.F, got.P), (ref.F, ref.P))


def test_fold_fits_start_from_the_whole_sets_seeds(shared_data) -> None:
    """The chooser's fold fits start from the whole set's optimum and its global-stage seeds
    (``fit_brdf(start=...)``, one local run): on CURET velvet's folds 1 and 3, whose one-lobe
    Lafortune optimum is a forward lobe (ψ = π) while the whole set's is retro-reflective (ψ = 0),
    they reach the training error of the full multi-start search on the fold (the slow path: its
    own global stage, 4 local runs), not the whole set's basin."""
    from shrmkit.analysis.fit.crossval import fold_of, subset
    from shrmkit.analysis.fit.optimize import fit_brdf
    from shrmkit.analysis.fit.sampling import collect_samples

    velvet = read_curet(shared_data / "brdf" / "curet", 7)
    samples = collect_samples(velvet, max_theta_deg=80.0)
    whole = fit_brdf(velvet, "lafortune", samples=samples)
    assert whole.shape is not None and len(whole.seeds) == 4 and abs(whole.shape[0]) < 1e-6
    fold = fold_of(len(samples), 5, seed=0)
    for k in (1, 3):
        train = subset(samples, fold != k)
        fast = fit_brdf(velvet, "lafortune", samples=train, start=[whole.shape, *whole.seeds], starts=1)
        slow = fit_brdf(velvet, "lafortune", samples=train, starts=4)
        assert fast.errors["rel_rms"] == pytest.approx(slow.errors["rel_rms"], rel=1e-7), k
        assert fast.shape[0] == pytest.approx(np.pi, abs=1e-3) and fast.options["start"][0] == list(whole.shape)
    with pytest.raises(BadInputError, match="start must hold rows of 2"):
        fit_brdf(velvet, "lafortune", samples=samples, start=[1.0, 2.0, 3.0])
