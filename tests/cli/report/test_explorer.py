"""BRDF Explorer's views in the report (``cli/report/explorer.py``, ``plots.py``).

References, computed here without the code under test: the half/difference angles turned
into directions by rotating D = (sin θ_d cos φ_d, sin θ_d sin φ_d, cos θ_d) about y by θ_h
and mirroring it about H = (sin θ_h, 0, cos θ_h) (Rusinkiewicz 1998, V = 2(H·L)H − L), then
``brdf.eval``; closed forms of a Lambertian surface (ρ = a/π, directional albedo a at every
view, lit-sphere radiance a·max(N·L, 0) under irradiance π); the plane of incidence written
out; the tangent frame of a lit-sphere pixel by the Rodrigues rotation taking N to +z.
"""

from __future__ import annotations

import io
import json
import math
from types import SimpleNamespace

import numpy as np
import pytest
from PIL import Image

import shrmkit
from shrmkit.analysis.brdf_views import SPHERE_LIGHT, halfdiff_slice, lit_sphere
from shrmkit.brdf_io.brdf import BRDF
from shrmkit.brdf_io.colour import REC709_LUMA as LUMA
from shrmkit.brdf_io.cornell import ScatteredBRDF
from shrmkit.brdf_io.merl import MerlBRDF, merl_sample_angles, tabulate_merl
from shrmkit.cli.report.collect import collect_report
from shrmkit.cli.report.explorer import (
    ALBEDO_CURVE_VIEWS_DEG,
    POLAR_INCIDENCE_DEG,
    POLAR_THETA_DEG,
    SPHERE_FILE,
    ReportImage,
    explore,
)
from shrmkit.cli.report.options import profile
from shrmkit.cli.report.plots import BELOW_COLOUR, MISSING_COLOUR, explorer_slice_plot, image_row_plot
from shrmkit.cli.report.writer import report_files

LAMBERT = "lambert:albedo=0.2/0.4/0.8"


def fit_of(spec: str) -> SimpleNamespace:
    """What ``explore`` reads of a ``fit_brdf`` result: the fitted model."""
    return SimpleNamespace(brdf=shrmkit.load_brdf(spec))


def directions(theta_h: np.ndarray, theta_d: np.ndarray, phi_d: float) -> tuple[np.ndarray, np.ndarray]:
    """(L, V) of half/difference angles (φ_h = 0), written out independently of brdf_io.halfdiff."""
    th, td = np.broadcast_arrays(theta_h, theta_d)
    D = np.stack([np.sin(td) * math.cos(phi_d), np.sin(td) * math.sin(phi_d), np.cos(td)], axis=-1)
    c, s = np.cos(th), np.sin(th)
    L = np.stack([c * D[..., 0] + s * D[..., 2], D[..., 1], -s * D[..., 0] + c * D[..., 2]], axis=-1)
    H = np.stack([s, np.zeros_like(s), c], axis=-1)
    V = 2.0 * np.sum(H * L, axis=-1, keepdims=True) * H - L
    return L, V


@pytest.fixture(scope="module")
def holed_table() -> tuple[MerlBRDF, tuple[int, int], tuple[int, int]]:
    """A MERL-format table of a Cook–Torrance material with a block of missing samples
    (θ_h indices 20–39, θ_d indices 30–49, every φ_d): MERL files store them as negative
    numbers, read as NaN."""
    values = tabulate_merl(shrmkit.load_brdf("cook-torrance:kd=0.3,alpha=0.25,f0=0.6"))
    rows, cols = (20, 40), (30, 50)
    values[:, rows[0]:rows[1], cols[0]:cols[1], :] = np.nan
    return MerlBRDF(values, name="holed"), rows, cols


def test_slice_of_a_table_is_its_evaluation_at_the_half_difference_directions(holed_table) -> None:
    brdf, _, _ = holed_table
    fit = "lafortune:kd=0.2,n=30,ks=2"
    block, _ = explore(brdf, [fit_of(fit), None], ("lafortune", "cook-torrance"), albedo_nodes=16)
    s = block["slice"]
    assert s["phi_d_deg"] == 90.0 and len(s["theta_h_deg"]) == len(s["theta_d_deg"]) == 45
    th, td = np.radians(s["theta_h_deg"])[:, None], np.radians(s["theta_d_deg"])[None, :]
    L, V = directions(th, td, math.radians(s["phi_d_deg"]))
    assert np.all(L[..., 2] > 0) and np.all(V[..., 2] > 0) and s["below_surface"] == []  # none at φ_d = 90°
    expected = brdf.eval(L, V) @ LUMA
    got = np.array([[np.nan if v is None else v for v in row] for row in s["lum"]])
    present = ~np.isnan(got)
    assert present.sum() > 0.8 * got.size
    np.testing.assert_allclose(got[present], expected[present], rtol=1e-12, atol=1e-300)
    # each fit on the same grid, a fit that could not run is null
    fitted = np.array(s["fitted_lum"]["lafortune"], dtype=float)
    np.testing.assert_allclose(fitted, shrmkit.load_brdf(fit).eval(L, V) @ LUMA, rtol=1e-12)
    assert s["fitted_lum"]["cook-torrance"] is None


def test_missing_table_cells_are_marked(holed_table) -> None:
    """Cells whose whole interpolation cell is missing are listed, null in the grid and magenta
    in the plot; cells of the slice away from the hole have data."""
    brdf, rows, cols = holed_table
    s = halfdiff_slice(brdf)
    th_s, td_s, _ = merl_sample_angles()
    th, td = np.radians(s["theta_h_deg"]), np.radians(s["theta_d_deg"])
    # strictly inside the hole: the enclosing samples (floor and floor + 1 of the index) are all missing
    inside = ((th > th_s[rows[0]])[:, None] & (th < th_s[rows[1] - 2])[:, None]
              & (td > td_s[cols[0]])[None, :] & (td < td_s[cols[1] - 2])[None, :])
    outside = ((th < th_s[rows[0] - 1]) | (th > th_s[rows[1] + 1]))[:, None] | (
        (td < td_s[cols[0] - 1]) | (td > td_s[cols[1] + 1]))[None, :]
    assert inside.sum() > 20
    assert np.all(s["missing"][inside]) and not np.any(s["missing"][outside])
    block, _ = explore(brdf, [], (), albedo_nodes=16)
    listed = np.zeros(s["missing"].shape, bool)
    for i, j in block["slice"]["missing"]:
        listed[i, j] = True
    assert np.array_equal(listed, s["missing"]) and block["slice"]["n_missing"] == int(listed.sum())
    assert all(block["slice"]["lum"][i][j] is None for i, j in block["slice"]["missing"])
    doc = {"status": "ok", "explorer": json.loads(json.dumps(block))}
    image = np.asarray(Image.open(io.BytesIO(explorer_slice_plot(doc))).convert("RGB"))
    magenta = np.all(image == np.round(np.array(MISSING_COLOUR[:3]) * 255).astype(np.uint8), axis=-1)
    assert magenta.sum() > 20
    assert BELOW_COLOUR != MISSING_COLOUR  # cells below the surface are greyed apart from missing ones


def test_lambert_albedo_polar_and_sphere_are_closed_form() -> None:
    """Lambert a: directional albedo a at every θ_v (to quadrature rounding), ρ = a/π on every
    polar curve, lit-sphere radiance a·max(N·L, 0)."""
    a = np.array([0.2, 0.4, 0.8])
    brdf = shrmkit.load_brdf(LAMBERT)
    block, files = explore(brdf, [fit_of("lambert:albedo=0.5")], ("lambert-fit",), albedo_nodes=24)
    albedo = block["albedo"]
    assert albedo["views_deg"] == [float(v) for v in ALBEDO_CURVE_VIEWS_DEG] and albedo["views_deg"][-1] == 88.0
    np.testing.assert_allclose(albedo["measured_rgb"], np.tile(a, (len(ALBEDO_CURVE_VIEWS_DEG), 1)), rtol=1e-12)
    np.testing.assert_allclose(albedo["fitted_rgb"]["lambert-fit"], 0.5, rtol=1e-12)
    curves = block["polar"]["curves"]
    assert [c["theta_i_deg"] for c in curves] == list(POLAR_INCIDENCE_DEG)
    for c in curves:
        assert c["measured_theta_o_deg"] == POLAR_THETA_DEG.tolist()
        np.testing.assert_allclose(c["measured_rgb"], np.tile(a / np.pi, (POLAR_THETA_DEG.size, 1)), rtol=1e-12)
    radiance, hit = lit_sphere(brdf)
    n = radiance.shape[0]
    c = (2.0 * np.arange(n) + 1.0) / n - 1.0
    x, y = np.meshgrid(c, -c)
    N = np.stack([x, y, np.sqrt(np.maximum(1.0 - x * x - y * y, 0.0))], axis=-1)
    light = np.asarray(SPHERE_LIGHT) / np.linalg.norm(SPHERE_LIGHT)
    expected = np.maximum(N @ light, 0.0)[..., None] * a
    np.testing.assert_allclose(radiance[hit], expected[hit], rtol=1e-12, atol=1e-15)
    assert not radiance[~hit].any()
    assert [f.file for f in files] == [SPHERE_FILE] and isinstance(files[0], ReportImage)
    assert [i["label"] for i in block["sphere"]["images"]] == ["brdf", "lambert-fit"]
    assert block["sphere"]["images"][0]["max_lum"] == pytest.approx(float(a @ LUMA), rel=1e-3)


def test_scattered_measurements_show_samples_near_the_plane_and_fit_albedo() -> None:
    """Scattered data: no slice; the in-plane samples (Δφ within 3° of 0 or 180°) with signed
    θ_o (> 0 on the mirror side), polar curves at the measured θ_i, the fits' albedo only."""
    def d(theta_deg: float, phi_deg: float) -> list[float]:
        t, p = math.radians(theta_deg), math.radians(phi_deg)
        return [math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t)]

    # (θ_i, φ_i, θ_o, φ_o, in plane, signed θ_o)
    rows = [(30, 0, 40, 180, True, 40.0), (30, 0, 20, 2, True, -20.0), (30, 0, 50, 90, False, None),
            (60, 45, 60, 226, True, 60.0), (60, 45, 10, 50, False, None), (60, 45, 70, 44, True, -70.0)]
    L = np.array([d(r[0], r[1]) for r in rows])
    V = np.array([d(r[2], r[3]) for r in rows])
    rgb = np.arange(1, 19, dtype=float).reshape(6, 3) / 10.0
    brdf = ScatteredBRDF(L, V, rgb, name="synthetic")
    block, files = explore(brdf, [fit_of("lafortune:kd=0.3,n=20,ks=1")], ("lafortune",), albedo_nodes=16)
    assert block["of"] == "measured samples" and block["slice"] is None and block["error"] is None
    s = block["samples"]
    kept = [r for r in rows if r[4]]
    assert s["n_in_plane"] == s["n_shown"] == len(kept)
    got = sorted(zip(s["theta_i_deg"], s["theta_o_deg"], map(tuple, s["rgb"]), strict=True))
    want = sorted((float(r[0]), r[5], tuple(rgb[k])) for k, r in enumerate(rows) if r[4])
    for g, w in zip(got, want, strict=True):
        assert g[0] == pytest.approx(w[0]) and g[1] == pytest.approx(w[1]) and g[2] == pytest.approx(w[2])
    curves = block["polar"]["curves"]
    assert [c["theta_i_deg"] for c in curves] == [30.0, 60.0]
    assert sorted(curves[1]["measured_theta_o_deg"]) == pytest.approx([-70.0, 60.0])
    assert block["albedo"]["measured_rgb"] is None and block["albedo"]["fitted_rgb"]["lafortune"] is not None
    assert [i["label"] for i in block["sphere"]["images"]] == ["lafortune"] and len(files) == 1


def test_views_failing_do_not_lose_the_report() -> None:
    class Broken(BRDF):
        name, kind = "broken", "analytic"

        def eval(self, L, V):
            raise RuntimeError("cannot evaluate")

    block, files = explore(Broken(), [], (), albedo_nodes=16)
    assert "cannot evaluate" in block["error"] and block["slice"] is None and files == []


def test_report_holds_the_views_and_their_plots() -> None:
    """A quick report: the ``explorer`` block as documented (data_specs/report_json.md), the
    plots and the lit sphere in the folder and embedded in report.html."""
    options = profile("quick", preview="none", models=("lafortune",), tolerances=(0.1,), eps=0.1, n_pairs=20,
                      explorer_plots=True)
    doc, extras = collect_report("cook-torrance:kd=0.2,alpha=0.3,f0=0.5", options)
    e = doc["explorer"]
    assert set(e) == {"of", "error", "luminance", "slice", "samples", "polar", "albedo", "sphere",
                      "explorer_seconds"}
    assert set(e["slice"]) == {"phi_d_deg", "theta_h_deg", "theta_d_deg", "lum", "missing", "below_surface",
                               "n_missing", "fitted_lum"}
    assert set(e["polar"]) == {"theta_o_deg", "curves"} and set(e["polar"]["curves"][0]) == {
        "theta_i_deg", "measured_theta_o_deg", "measured_rgb", "fitted_rgb"}
    assert set(e["albedo"]) == {"views_deg", "nodes", "measured_rgb", "fitted_rgb"}
    assert set(e["sphere"]) == {"file", "size", "light", "view", "irradiance", "tone", "exposure", "images"}
    assert e["albedo"]["nodes"] == options.albedo_nodes
    # the albedo curve agrees with the report's own check at the shared views
    checks = doc["data_checks"]["albedo"]
    for view, rgb in zip(checks["views_deg"], checks["rgb"], strict=True):
        if view in e["albedo"]["views_deg"]:
            np.testing.assert_allclose(e["albedo"]["measured_rgb"][e["albedo"]["views_deg"].index(view)], rgb,
                                       rtol=1e-9)
    files = report_files(doc, extras)
    for name in ("plot_explorer_slice.png", "plot_explorer_polar.png", "plot_explorer_albedo.png", SPHERE_FILE):
        assert files[name][:8] == b"\x89PNG\r\n\x1a\n", name
    html = files["report.html"].decode("utf-8")
    md = files["report.md"].decode("utf-8")
    assert "## BRDF Explorer views" in md and f"]({SPHERE_FILE})" in md and "](plot_explorer_polar.png)" in md
    assert html.count("data:image/png;base64,") >= 9 and "BRDF Explorer views" in html
    json.dumps(doc, allow_nan=False)


def test_the_sphere_row_holds_every_image_unchanged_under_its_title() -> None:
    rng = np.random.default_rng(4)
    images = [rng.integers(0, 256, (40, 40, 3), dtype=np.uint8), rng.integers(0, 256, (40, 40, 3), dtype=np.uint8)]
    row = np.asarray(Image.open(io.BytesIO(image_row_plot(images, ["brdf", "lafortune"]))).convert("RGB"))
    # find each tile by its exact pixels: the row is lossless and the tiles are not resampled
    for image in images:
        hits = [(y, x) for y in range(row.shape[0] - 39) for x in range(row.shape[1] - 39)
                if np.array_equal(row[y, x], image[0, 0]) and np.array_equal(row[y:y + 40, x:x + 40], image)]
        assert len(hits) == 1 and hits[0][0] > 8  # below its title
    title_band = row[: hits[0][0]]
    assert (title_band < 128).any()  # dark title text above the tiles
