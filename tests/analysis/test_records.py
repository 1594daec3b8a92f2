"""The typed records of ``prefilter`` (analysis/records.py) against the serialized ``SHRM.meta``.

The reference is the meta dict itself: ``meta`` is what every verb prints and every file stores
(``data_specs/shrm_file.md``), so the record must write back exactly its keys, in its order, with
its values, and read the files written before a key existed.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

import shrmkit
from shrmkit.analysis.records import PrefilterInfo, Timings, ViewBand, WindowInfo
from shrmkit.analysis.shrm import SHRM, load_shrm

#: ``SHRM.meta``'s keys in order, as ``prefilter`` wrote them before the records (commit ed8dae9,
#: ``shrm prefilter --env builtin:sky --brdf microfacet:sigma=0.1 --json``): the file format.
META_KEYS = [
    "brdf", "environment", "environment_source", "lights_requested", "lights", "lights_flux_share",
    "lights_threshold", "lights_left_in_map", "lights_brdf", "statement_signal", "F_rho", "P_rho", "F_L",
    "lighting_capped", "orders_message", "orders_asked", "timings", "shrmkit_version", "frame", "azimuth_free",
    "window", "window_requested", "window_strength", "window_reason", "window_threshold", "window_cost",
    "eps_reflected_unwindowed", "negative_before", "negative_after", "negative_fraction_after",
    "negative_max_view_deg", "negative_sample_pairs", "window_capped", "criterion", "max_view_deg", "scene_capped",
    "capped", "capped_by", "pixel_rule", "pixel_errors", "view_bands", "map_budget", "extrapolated_samples",
]
#: One band of that run's ``meta["view_bands"]`` (its sun taken out as a light).
BAND_KEYS = [
    "theta_v_deg", "predicted_rel_rms", "bound_rel_rms", "truncation_rel_rms", "map_rel_rms", "inside",
    "extrapolated_samples", "bound_holds", "lights_rel_rms", "lights_rel_rms_residual", "predicted_rel_rms_residual",
    "bound_rel_rms_residual", "bound_informative", "map_bound_cost", "bound_rel_rms_exact_lookup",
]


@pytest.fixture(scope="module")
def with_lights() -> SHRM:
    """The sky's sun taken out as a light, the pixel rule run, a cube map: every optional part."""
    env = shrmkit.load_env("builtin:sky", height=32)
    return shrmkit.prefilter(env, "microfacet:sigma=0.25", eps=0.05, cube=True)


def _same(a: object, b: object) -> bool:
    """Equal values and, for dicts at any depth, the same key order (what JSON output shows)."""
    return json.dumps(a) == json.dumps(b)


def test_meta_is_the_record_written_back(with_lights: SHRM) -> None:
    """prefilter's meta (lights, pixel rule, cube timings) = PrefilterInfo.from_meta(meta).to_meta(),
    keys in the same order at every depth; the typed fields read the same numbers."""
    meta = with_lights.meta
    info = with_lights.info
    assert list(meta) == META_KEYS and all(list(band) == BAND_KEYS for band in meta["view_bands"])
    assert _same(info.to_meta(), meta)
    assert list(meta["timings"]) == ["orders", "lights", "lighting", "window", "pixels", "map size", "synthesis",
                                     "cube", "errors", "total"]
    assert info.timings.map_size == meta["timings"]["map size"] and info.timings.cube == meta["timings"]["cube"]
    assert info.window.used == meta["window"] and info.window.reason == meta["window_reason"]
    assert len(info.lights) == len(meta["lights"]) == 1 and info.lights.brdf == meta["lights_brdf"]
    assert [b.predicted_rel_rms for b in info.view_bands] == [b["predicted_rel_rms"] for b in meta["view_bands"]]
    assert all(b.lights_rel_rms is not None and b.bound_informative is not None for b in info.view_bands)
    assert info.capped_by == tuple(meta["capped_by"]) and info.pixel_rule == meta["pixel_rule"]


def test_rh02_without_window_or_lights() -> None:
    """The rh02 rule, no window, no lights: no pixel rule (null), no pixels timing, window 'none'."""
    m = shrmkit.prefilter("builtin:constant,height=16", "lambert:albedo=0.5", criterion="rh02", window="none",
                          lights="none")
    assert _same(m.info.to_meta(), m.meta) and list(m.meta) == META_KEYS
    assert [list(band) for band in m.meta["view_bands"]] == [BAND_KEYS[:8] + BAND_KEYS[12:]] * len(m.info.view_bands)
    assert m.info.pixel_rule is None and m.info.timings.pixels is None and "pixels" not in m.meta["timings"]
    assert m.info.window.used == "none" and m.info.window.describe() == "none"
    assert m.info.lights.brdf is None and len(m.info.lights) == 0
    assert all(b.lights_rel_rms is None and "lights_rel_rms" not in b.to_json() for b in m.info.view_bands)


def test_saved_file_reads_the_same_record(with_lights: SHRM, tmp_path) -> None:
    """A saved SHRM's info (from its header's meta) equals the one prefilter made."""
    loaded = load_shrm(with_lights.save(tmp_path / "m.shrm.npz"))
    assert loaded.info == with_lights.info
    assert _same(loaded.meta, json.loads(json.dumps(with_lights.meta)))


def test_old_file_without_window_keys(tmp_path) -> None:
    """A file written before the window, the lights and the statements existed (meta of provenance only)
    loads, keeps its meta as written, and its info reads the missing keys as None or empty."""
    meta = {"brdf": "lambert", "environment": "sky", "F_rho": 2, "P_rho": 0, "F_L": 3,
            "timings": {"orders": 0.1, "lighting": 0.2, "synthesis": 0.3, "total": 0.6}}
    old = SHRM(F=1, P=0, coeffs=np.ones((1, 4, 8, 3), np.float32), tolerance=0.1, eps={"brdf": 0.01}, meta=meta)
    loaded = load_shrm(old.save(tmp_path / "old.shrm.npz"))
    assert loaded.meta == meta
    info = loaded.info
    assert (info.brdf, info.F_L, info.timings.total, info.timings.window) == ("lambert", 3, 0.6, None)
    assert info.window == WindowInfo() and info.view_bands == () and info.capped_by == () and info.capped is None
    assert info.timings.to_json() == meta["timings"]
    assert PrefilterInfo.from_meta({}) == PrefilterInfo() and SHRM(F=0, P=0, coeffs=old.coeffs).info == PrefilterInfo()


def test_view_band_keeps_unknown_keys_and_order() -> None:
    """A band with a key this record does not know writes it back after the known ones; the optional
    tail is left out when absent, the base keys are written even when null (a NaN in a file)."""
    band = {"theta_v_deg": [0.0, 15.0], "predicted_rel_rms": None, "bound_rel_rms": 0.2, "truncation_rel_rms": 0.1,
            "map_rel_rms": 0.01, "inside": True, "extrapolated_samples": 0, "bound_holds": True, "future_key": [1]}
    record = ViewBand.from_json(band)
    assert record.theta_v_deg == (0.0, 15.0) and record.extra == {"future_key": [1]}
    assert _same(record.to_json(), band)
    assert Timings(orders=1.0, map_size=2.0).to_json() == {"orders": 1.0, "map size": 2.0}


def test_stated_band_is_the_worst_band_marked_inside() -> None:
    """PrefilterInfo.stated_band: the largest predicted relative RMS among bands with inside True (a
    band outside, or without ``inside``, never counts); the reference is the hand-made list itself."""
    bands = [{"theta_v_deg": [0, 10], "predicted_rel_rms": 0.02, "bound_rel_rms": 0.03, "inside": True},
             {"theta_v_deg": [10, 20], "predicted_rel_rms": 0.05, "bound_rel_rms": 0.06, "inside": True},
             {"theta_v_deg": [20, 30], "predicted_rel_rms": 0.04, "bound_rel_rms": 0.09, "inside": True},
             {"theta_v_deg": [80, 90], "predicted_rel_rms": 0.50, "bound_rel_rms": 0.70, "inside": False},
             {"theta_v_deg": [70, 80], "predicted_rel_rms": 0.90, "bound_rel_rms": 0.95}]
    worst = PrefilterInfo.from_meta({"view_bands": bands}).stated_band()
    assert worst is not None
    assert (worst.theta_v_deg, worst.predicted_rel_rms, worst.bound_rel_rms) == ((10, 20), 0.05, 0.06)
    assert PrefilterInfo.from_meta({"view_bands": bands[3:]}).stated_band() is None
    assert PrefilterInfo.from_meta({}).stated_band() is None


def test_record_of_an_shrm_a_stand_in_or_a_meta_dict() -> None:
    """PrefilterInfo.of: the record itself, an object's ``info``, an object holding only ``meta``, the
    dict; anything else states nothing."""
    meta = {"view_bands": [{"theta_v_deg": [0, 10], "predicted_rel_rms": 0.02, "inside": True}]}
    record = PrefilterInfo.from_meta(meta)

    class WithInfo:
        info = record

    class OnlyMeta:
        def __init__(self) -> None:
            self.meta = meta

    assert PrefilterInfo.of(record) is record and PrefilterInfo.of(WithInfo()) is record
    assert PrefilterInfo.of(OnlyMeta()) == record == PrefilterInfo.of(meta)
    assert PrefilterInfo.of(object()).view_bands == ()
