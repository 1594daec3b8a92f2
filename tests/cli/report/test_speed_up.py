"""The report's speed-up: brute force's CPU time over the prefilter's (stable under load), the wall
ratio for reports written before CPU times were recorded."""

from shrmkit.cli.report.markdown import _scene_headline as environment_line
from shrmkit.cli.report.markdown import _speed_up


def _row(**extra):
    return {"env": "sky", "tolerance": 0.03, "prefilter_seconds": 0.5, "reference_map_seconds": 20.0, **extra}


def test_speed_up_is_the_cpu_ratio_when_recorded() -> None:
    assert _speed_up(_row()) == 40.0  # wall: an old report.json
    assert _speed_up(_row(prefilter_cpu_seconds=0.8, reference_map_cpu_seconds=12.0)) == 15.0


def test_headline_states_cpu_seconds_and_their_ratio() -> None:
    env = {"name": "sky", "height": 32, "width": 64, "F_B": 13, "P_B": 10, "predicted_rel_rms": 0.01,
           "bound_rel_rms": 0.05, "measured_rel_rms": 0.015, "n_pairs": 150}
    doc = {"main": {"tolerance": 0.03},
           "speed_vs_error": [_row(prefilter_cpu_seconds=0.8, reference_map_cpu_seconds=12.0)]}
    line = environment_line(doc, env)
    assert "prefilter 0.8 s CPU against ≈ 12 s CPU" in line and "(15× less CPU)" in line
    old = environment_line({"main": {"tolerance": 0.03}, "speed_vs_error": [_row()]}, env)
    assert "prefilter 0.5 s against ≈ 20 s" in old and "(40× faster)" in old


def test_headline_sets_the_worst_band_measured_beside_the_bound() -> None:
    """A new user read 'bound 0.0283, measured 0.0349' as a broken bound: the pooled all-pairs
    error beside a worst-band bound. The headline now states the worst band's measured value (± s.e.)
    and names the pooled one."""
    env = {"name": "pisa", "height": 32, "width": 64, "F_B": 9, "P_B": 0, "predicted_rel_rms": 0.0222,
           "bound_rel_rms": 0.0283, "measured_rel_rms": 0.0349, "measured_worst_band_rel_rms": 0.0271,
           "measured_worst_band_stderr": 0.0031, "n_pairs": 150}
    line = environment_line({"main": {"tolerance": 0.03}, "speed_vs_error": []}, env)
    assert "bound 0.0283, **measured 0.0271 ± 0.0031** (the worst band measured" in line
    assert "all 150 pairs pooled: 0.0349" in line
