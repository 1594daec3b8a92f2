"""The pixel rule (analysis/pixels.py) against brute force: per-pixel relative errors of a lit
sphere under Grace (issue 23's target: Phong s = 200, median <= 0.05, 90th percentile <= 0.15), the
statement it makes beside them, and the ladder search's monotonicity."""

from __future__ import annotations

import numpy as np
import pytest

import shrmkit
from shrmkit.analysis.pixels import _first_on_ladder, _ladder
from shrmkit.analysis.reference import reference_radiance
from shrmkit.brdf_io.exr import luminance_weights
from shrmkit.render.camera import Camera
from shrmkit.render.cpu_reference import sphere_geometry


def test_grace_phong_per_pixel_errors_against_brute_force(shared_data):
    """400 pixels of the default orthographic sphere (the camera of `shrm render`), luminance, the
    exact angular integral over every pixel of the 128-row map as reference. The energy rule alone
    (F_B 28) leaves median 0.17 / p90 0.58; the pixel rule (F_B 41) meets the issue's target, and its
    stated p90 (against a higher order, on the residual map) is not below what brute force shows."""
    env = shrmkit.load_env(shared_data / "env" / "grace_latlong.exr", up="y", flip=True, height=128)
    brdf = shrmkit.load_brdf("phong:s=200")
    geometry = sphere_geometry(Camera.looking_at(projection="ortho"), 128, 128)
    covered = np.flatnonzero(geometry.hit.ravel())
    pick = np.random.default_rng(1).choice(covered, 400, replace=False)
    R, V = geometry.R.reshape(-1, 3)[pick], geometry.V.reshape(-1, 3)[pick]
    luma = luminance_weights()
    reference = reference_radiance(env, brdf, R, V) @ luma

    def errors(shrm) -> tuple[float, float]:
        e = np.abs(shrm.radiance(R, V) @ luma - reference) / reference
        return float(np.median(e)), float(np.percentile(e, 90))

    energy_only = shrmkit.prefilter(env, brdf, pixel_rule=False)
    assert errors(energy_only)[1] > 0.3  # the case the rule exists for
    shrm = shrmkit.prefilter(env, brdf)
    median, p90 = errors(shrm)
    assert median <= 0.05 and p90 <= 0.15, (shrm.F, median, p90)
    stated = shrm.meta["pixel_errors"]
    assert shrm.meta["pixel_rule"]["F_from"] == energy_only.F < shrm.F
    assert stated["p90"] <= stated["tolerance"] == pytest.approx(np.sqrt(0.03))
    assert p90 <= stated["p90"] and median <= stated["median"]


def test_ladder_search_is_a_scan_and_monotone_in_strictness():
    """The stride search over the ladder gives a bottom-up scan's first passing rung for monotone
    predicates, and for any predicate never a lower rung for a stricter one (what makes the rule
    monotone in ε)."""
    ladder = _ladder(5, 200)
    orders = [order for order, _ in ladder]
    assert orders[0] == 5 and orders[-1] == 200 and all(b > a for a, b in zip(orders, orders[1:], strict=False))
    # one global ladder: the rungs above 30 are the same from any start below them
    assert [o for o, c in _ladder(7, 200) if o > 30] == [o for o, c in ladder if o > 30]
    for threshold in (5, 6, 7, 19, 64, 150, 200):
        assert _first_on_ladder(ladder, lambda f, t=threshold: f >= t) == next(f for f in orders if f >= threshold)
    assert _first_on_ladder(ladder, lambda f: False) is None
    rng = np.random.default_rng(0)
    for _ in range(200):
        error = dict(zip(orders, rng.random(len(orders)), strict=True))  # any error per rung
        tight, loose = sorted(rng.random(2))  # the tight tolerance is the smaller
        strict = _first_on_ladder(ladder, lambda f, t=tight, e=error: e[f] <= t)
        lax = _first_on_ladder(ladder, lambda f, t=loose, e=error: e[f] <= t)
        if strict is not None:
            assert lax is not None and lax <= strict
