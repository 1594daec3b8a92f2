"""``shrm report --no-plots``: the same numbers, no plot files, pages that link none."""

from __future__ import annotations

from shrmkit.cli.report.collect import collect_report, strip_timings
from shrmkit.cli.report.options import profile
from shrmkit.cli.report.writer import report_files


def test_report_without_plots_has_the_same_numbers_and_no_plot_files():
    base = dict(preview="none", models=("lafortune",), tolerances=(0.1,), eps=0.1, n_pairs=20, fit_samples=1024,
                albedo_nodes=16)
    with_plots, previews = collect_report("phong:s=16", profile("quick", **base))
    without, previews_np = collect_report("phong:s=16", profile("quick", plots=False, **base))
    assert without["options"]["plots"] is False and with_plots["options"]["plots"] is True
    a, b = strip_timings(with_plots), strip_timings(without)
    a["options"].pop("plots"), b["options"].pop("plots")
    assert a == b
    files = report_files(without, previews_np)
    assert not any(name.startswith("plot_") for name in files)
    assert {"report.json", "report.md", "report.html"} <= set(files)
    md = files["report.md"].decode()
    assert "Plots not drawn (--no-plots)" in md and "plot_" not in md
    assert "plot_" not in files["report.html"].decode()
    drawn = report_files(with_plots, previews)
    assert any(name.startswith("plot_energy") for name in drawn)


def test_quick_profile_draws_the_rh02_plots_and_leaves_the_brdf_views_to_explorer_plots():
    from shrmkit.cli.report.plots import EXPLORER_PLOTS, PLOT_TITLES

    base = dict(preview="none", models=("lafortune",), tolerances=(0.1,), eps=0.1, n_pairs=20, fit_samples=1024,
                albedo_nodes=16)
    quick, previews = collect_report("phong:s=16", profile("quick", **base))
    assert quick["options"]["explorer_plots"] is False and profile("full").explorer_plots is True
    files = report_files(quick, previews)
    drawn = {name[len("plot_"):-len(".png")] for name in files if name.startswith("plot_")}
    assert drawn == {"energy", "accuracy_by_p", "speed_error", "fit_bands"}
    md = files["report.md"].decode()
    assert "--explorer-plots draws them" in md and not any(f"plot_{k}.png" in md for k in EXPLORER_PLOTS)
    assert quick["explorer"]["polar"]["curves"]  # the numbers stay in report.json
    quick["options"]["explorer_plots"] = True  # the same document asking for every plot draws the rest
    everything = report_files(quick, previews)
    assert {k for k in PLOT_TITLES if f"plot_{k}.png" in everything} == drawn | {
        "fit_slices", "explorer_slice", "explorer_polar", "explorer_albedo"}
