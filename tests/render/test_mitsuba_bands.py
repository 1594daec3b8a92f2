"""An RGL sphere under an environment map, per view band, against Mitsuba 3 (issue 29).

The independent reference is another renderer's output: Mitsuba 3.9.1's ``measured`` plugin under
its ``envmap`` emitter, integrator ``direct``, recorded by ``benchmarks/mitsuba_bands.py --record``
into ``tests/resources/mitsuba_bands_grace16.json`` (the command, Mitsuba's version and the scene
are in the file; data_specs/rgl_bsdf.md, "Rendered against Mitsuba"). The recorded values are
checked always; the slow test renders the scene again when ``mitsuba`` imports.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
RECORD = ROOT / "tests" / "resources" / "mitsuba_bands_grace16.json"


@pytest.fixture(scope="module")
def recorded(shared_data: Path, benchmark_module):
    """The record, the benchmark module, the scene it describes and the file of the material."""
    record = json.loads(RECORD.read_text())
    bench = benchmark_module("mitsuba_bands")
    scene = bench.sphere_scene(record["size"], tuple(record["view"]))
    env = bench.scene_env(record["env_rows"], shared_data / record["env"])
    return record, bench, scene, env, shared_data / record["material"]


def _recorded_pixels(record: dict) -> np.ndarray:
    return np.concatenate([np.asarray(b["mitsuba_pixels"]).reshape(-1, 3) for b in record["bands"] if b["pixels"]])


def _order(bench, scene, record) -> np.ndarray:
    """Our hit pixels in the record's order (band by band, image order within a band)."""
    edges = [b["theta_v_deg"] for b in record["bands"]]
    return np.concatenate([np.flatnonzero((scene.theta_v_deg >= lo) & (scene.theta_v_deg < hi)) for lo, hi in edges])


def test_reference_render_matches_recorded_mitsuba_bands(recorded):
    """The brute-force render (camera convention, the default) against Mitsuba's recorded render of
    cc_ibiza_sunset (a satin vinyl, 8-19 % non-reciprocal): per band the mean within Mitsuba's
    noise (2 s.e.) plus 1.5 %, the per-pixel relative RMS within Mitsuba's per-pixel noise plus 2 %
    (measured: 0.1-1.1 % and 0.3-1.6 %, the largest at 75-85 deg where the local horizon crosses the
    map's pixels, integrated by points). The light convention, the old default, misses in most
    bands (band means 0.6-20 % off, pixels 4-24 %: the issue's 0.05-0.33)."""
    record, bench, scene, env, path = recorded
    assert [b["pixels"] for b in record["bands"]] == [
        int(np.sum((scene.theta_v_deg >= lo) & (scene.theta_v_deg < hi))) for lo, hi in
        (b["theta_v_deg"] for b in record["bands"])]
    theirs = _recorded_pixels(record)
    order = _order(bench, scene, record)
    fails = {}
    for convention in ("view", "light"):
        upsample = record["reference_upsample"] if convention == "view" else 1  # light: only needs to miss
        ours = bench.reference_render(path, env, scene, table_direction=convention, upsample=upsample)[order]
        fails[convention] = []
        start = 0
        for band in record["bands"]:
            n = band["pixels"]
            if not n:
                continue
            o, t = ours[start:start + n], theirs[start:start + n]
            start += n
            m = np.asarray(band["mitsuba"])
            np.testing.assert_allclose(t.mean(axis=0), m, rtol=1e-5, atol=1e-7)  # the record is consistent
            diff = np.linalg.norm(o.mean(axis=0) - m) / np.linalg.norm(m)
            rms = np.sqrt(np.sum((o - t) ** 2) / np.sum(t**2))
            if not (diff <= band["noise"] + 0.015 and rms <= band["pix_noise"] + 0.02):
                fails[convention].append((band["theta_v_deg"], round(diff, 4), round(rms, 4)))
    assert not fails["view"], fails["view"]
    assert len(fails["light"]) >= 3, fails["light"]


def test_shrm_render_matches_recorded_mitsuba_bands(recorded, shared_data: Path):
    """The SHRM ``shrm render`` builds (ε 0.03, lights auto; here on the record's 32 map rows: F 31,
    P 9) against Mitsuba's recorded render, on the record's pixels: per band the mean within
    Mitsuba's noise plus the SHRM's statement carried to the band's pixels, and the per-pixel
    relative RMS within Mitsuba's per-pixel noise plus the same (``pixels_statement``: the larger
    of the band's stated relative RMS and its absolute RMS over the pixels' own RMS; 1–6× the
    stated value to 70°). Measured: band means 0.5–1.9 % off to 70° (per pixel 2.3–8.0 %); at 70–85°
    this sphere's few pixels (28) reflect 11–26× less than the band's RMS and are 67–110 % off per
    pixel, beyond the stated band values (24–59 %) and within the carried ones (2.6–15: honest,
    not informative). The same SHRM of the light convention misses in 4 bands (0–60°: 3.7–21 %
    off in the mean)."""
    from shrmkit.analysis.compare.band_error import pixels_statement
    from shrmkit.analysis.error_image import band_signal
    from shrmkit.analysis.shrm import prefilter
    from shrmkit.brdf_io.rgl import RGLGamutWarning
    from shrmkit.brdf_io.specs import load_brdf

    record, bench, scene, env, path = recorded
    theirs = _recorded_pixels(record)
    order = _order(bench, scene, record)
    g = scene.geometry
    fails = {}
    for suffix in ("", "#light"):
        with pytest.warns(RGLGamutWarning):  # as shrm render loads it: 746 small negative values clamped
            brdf = load_brdf(f"{path}{suffix}")
        shrm = prefilter(env, brdf, eps=0.03)
        ours = shrm.radiance(g.R[g.hit], g.V[g.hit])
        stated = pixels_statement(shrm, ours, scene.theta_v_deg, signal=band_signal(shrm, pairs_per_band=512))
        ours = ours[order]
        fails[suffix] = []
        start = 0
        for band, mine in zip(record["bands"], stated, strict=True):
            n = band["pixels"]
            assert mine["pixels"] == n and mine["factor"] >= 1.0
            if not n:
                continue
            o, t = ours[start:start + n], theirs[start:start + n]
            start += n
            m = np.asarray(band["mitsuba"])
            diff = np.linalg.norm(o.mean(axis=0) - m) / np.linalg.norm(m)
            rms = np.sqrt(np.sum((o - t) ** 2) / np.sum(t**2))
            bound = mine["bound_rel_rms"]
            if not (diff <= band["noise"] + bound and rms <= band["pix_noise"] + bound):
                fails[suffix].append((band["theta_v_deg"], round(diff, 4), round(rms, 4), round(bound, 4)))
    assert not fails[""], fails[""]
    assert len(fails["#light"]) >= 3, fails["#light"]


@pytest.mark.slow
def test_mitsuba_render_now_matches_record_and_reference(recorded):
    """Mitsuba rendered now (skipped without ``mitsuba``), 4 seeds of 256 spp: the envmap's
    orientation (Mitsuba's eval equal to the project map on most directions), then per band the
    mean within the combined noise of the record and this render plus 0.5 %, and our reference
    within that noise plus 1 %."""
    pytest.importorskip("mitsuba")
    record, bench, scene, env, path = recorded
    check = bench.check_envmap(env.radiance, record["upsample"], n=1000)
    assert check["equal_fraction"] > 0.5 and check["median_rel"] < 1e-5, check
    runs = np.stack([bench.mitsuba_render(path, env.radiance, scene, spp=256, seed=7 + 1000 * s,
                                          upsample=record["upsample"]) for s in range(4)])
    ours = bench.reference_render(path, env, scene, upsample=record["reference_upsample"])
    now = bench.compare_bands(runs, ours, scene.theta_v_deg)
    for band, mine in zip(record["bands"], now, strict=True):
        if not band["pixels"]:
            continue
        m = np.asarray(band["mitsuba"])
        noise = np.hypot(band["noise"], mine["noise"])
        assert np.linalg.norm(np.asarray(mine["mitsuba"]) - m) / np.linalg.norm(m) <= noise + 0.005, (band, mine)
        assert mine["diff"] <= mine["noise"] + 0.01, mine
