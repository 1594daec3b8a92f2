"""The live WebGL2 previews in report.html (``explorer.live_views``, ``html.report_html``).

A quick report under two environments is written with the report writer and opened from
``file://`` in headless chromium (SwiftShader WebGL2; ``Browser`` of tests/conftest.py). References: the
CPU reference renderer (``render.cpu_reference``: analytic sphere, the bilinear lookup of
``SHRM.view_map`` for the page's ``distant`` mode) of the coefficients and environment *as the
page stores them* (decoded from its JSON document: half floats, reduced to the budget), for the
page's camera (``webgl_page.page_camera``) and tone map; and the report's still preview (the
CPU reference's ``SHRM.radiance`` of the full SHRM, 128 px), which the page shows without
WebGL2. Measured (Chromium 156, SwiftShader): 0.3–0.4 % relative RMS of the 8-bit canvas
against the reference, 2–5.5 % against the still image downsampled to it.

``SHRM_README_SCREENSHOT=docs/images/live_preview.png`` makes the browser test write the
README's screenshot (the first view, with its info bar and controls).
"""

from __future__ import annotations

import base64
import io
import json
import math
import os
import re
import subprocess
from pathlib import Path

import numpy as np
import pytest
from PIL import Image
from scipy.ndimage import binary_dilation, binary_erosion

from shrmkit.analysis.shrm import SHRM
from shrmkit.brdf_io.latlong import bilinear_lookup
from shrmkit.brdf_io.specs import load_brdf
from shrmkit.cli.report.collect import collect_report
from shrmkit.cli.report.explorer import LIVE_VIEW_BUDGET_BYTES, LiveView, preview_view_angles
from shrmkit.cli.report.html import _viewer_once, report_html
from shrmkit.cli.report.options import profile
from shrmkit.cli.report.writer import report_files, write_folder
from shrmkit.render.camera import Camera
from shrmkit.render.cpu_reference import shade, sphere_geometry
from shrmkit.render.output import composite, environment_background, to_8bit
from shrmkit.render.preview import PREVIEW_VIEW, PreviewImage
from shrmkit.render.webgl_page import page_camera, stored_lights, webgl_sources

BRDF = "lafortune:kd=0.45/0.07/0.05,cxy=-1,cz=1,n=60,ks=3"  # the demo's red plastic, analytic
ENVS = ("builtin:sky", "builtin:studio")
#: Relative RMS of the 8-bit canvas against the CPU reference of the stored data (one-pixel
#: silhouette band left out): the threshold of tests/render/test_webgl_view.py.
REL_RMS_MAX = 0.03
#: ... and against the still image (another renderer: SHRM.radiance of the unreduced maps,
#: 128 px, the analytic sphere): "roughly".
STILL_REL_RMS_MAX = 0.10
WINDOW = 900
#: chromium without WebGL: the viewers must show their still images.
NO_WEBGL_FLAGS = ("--disable-3d-apis", "--disable-webgl")


@pytest.fixture(scope="module")
def report(tmp_path_factory) -> dict:
    """A quick report (CPU preview, one model, one tolerance) under two environments, written."""
    options = profile("quick", preview="cpu", models=("lafortune",), tolerances=(0.03,), eps=0.03, n_pairs=50,
                      envs=ENVS)
    doc, extras = collect_report(BRDF, options, name="red")
    folder = write_folder(tmp_path_factory.mktemp("live"), "red", report_files(doc, extras))
    html = (folder / "report.html").read_text(encoding="utf-8")
    return {"doc": doc, "extras": extras, "folder": folder, "html": html,
            "url": (folder / "report.html").resolve().as_uri()}


def page_document(html: str, element_id: str) -> dict:
    m = re.search(rf'<script type="application/json" id="{element_id}-data">(.*?)</script>', html, re.S)
    assert m is not None, element_id
    return json.loads(m.group(1))


def _halves(b64: str, shape: tuple[int, ...], scale: float) -> np.ndarray:
    return (np.frombuffer(base64.b64decode(b64), "<f2").astype(np.float32) / np.float32(scale)).reshape(shape)


def stored_shrm_and_env(data: dict) -> tuple[SHRM, np.ndarray]:
    """The SHRM and the background exactly as the page holds them (data_specs/view_html.md)."""
    s, e = data["shrm"], data["env"]
    h, w, cols = s["height"], s["width"], s["cols"]
    atlas = _halves(s["texels"], (s["rows"] * h, cols * w, 3), s["scale"])
    n = (s["P"] + 1) ** 2
    coeffs = np.stack([atlas[(k // cols) * h:(k // cols + 1) * h, (k % cols) * w:(k % cols + 1) * w]
                       for k in range(n)])
    env = _halves(e["texels"], (e["height"], e["width"], 3), e["scale"])
    lights = stored_lights(data)  # the page shades its explicit lights per pixel (data_specs/lights.md)
    return SHRM(F=s["F"], P=s["P"], coeffs=coeffs, lights=lights, brdf=load_brdf(BRDF) if lights else None), env


def reference_image(data: dict, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
    """8-bit CPU reference of the page's initial view (distant mode) and the hit mask."""
    shrm, env = stored_shrm_and_env(data)
    view = data["view"]
    assert view["mode"] == "distant"
    camera = page_camera(view["azimuth"], view["elevation"], view["zoom"], width, height)
    geometry = sphere_geometry(camera, width, height)
    view_map = shrm.view_map(camera.view_direction(np.zeros(3)))
    radiance = shade(geometry, lambda R, V: bilinear_lookup(view_map, R) + shrm.light_radiance(R, V))
    bg = environment_background(env, camera, width, height)
    linear = composite(radiance.astype(np.float32), geometry.hit.astype(np.float32), bg)
    return to_8bit(linear, exposure=view["exposure"], curve=view["tone"]), geometry.hit


def relative_rms(image: np.ndarray, reference: np.ndarray, mask: np.ndarray | None = None) -> float:
    mask = np.ones(image.shape[:2], bool) if mask is None else mask
    a = image[mask].astype(np.float64) / 255.0
    b = reference[mask].astype(np.float64) / 255.0
    return float(np.sqrt(np.mean((a - b) ** 2)) / np.sqrt(np.mean(b**2)))


def _still_of(html: str, element_id: str) -> bytes:
    m = re.search(rf'<div class="shrm-view[^"]*" id="{element_id}".*?<img class="shrm-view-fallback"[^>]*'
                  r'src="data:image/png;base64,([^"]+)"', html, re.S)
    assert m is not None, element_id
    return base64.b64decode(m.group(1))


# ------------------------------------------------------------------------------------------
# the report without a browser
# ------------------------------------------------------------------------------------------


class TestReport:
    """The tests of the report fixture: one unit of work under xdist (tests/conftest.py), one report."""

    def test_live_previews_are_embedded_once_per_environment_within_budget(self, report) -> None:
        doc, html = report["doc"], report["html"]
        live = doc["live_preview"]
        assert live["budget_bytes"] == LIVE_VIEW_BUDGET_BYTES == 3 << 20 and live["notes"] == []
        assert [v["env"] for v in live["views"]] == [e["name"] for e in doc["environments"]] == ["sky", "studio"]
        views = [x for x in report["extras"] if isinstance(x, LiveView)]
        assert [v.element_id for v in views] == [v["element_id"] for v in live["views"]]
        for entry, view in zip(live["views"], views, strict=True):
            assert entry["html_bytes"] == len(view.html.encode("utf-8")) <= LIVE_VIEW_BUDGET_BYTES
            assert f'<div class="shrm-view" id="{entry["element_id"]}"' in html
            assert f"<!-- live-view {entry['element_id']} -->" not in html  # the mark was replaced
            data = page_document(html, entry["element_id"])
            assert data["shrm"]["P"] == entry["P"] and [data["shrm"]["height"], data["shrm"]["width"]] == entry["maps"]
            # the SHRM at the main tolerance of that environment
            env = next(e for e in doc["environments"] if e["name"] == entry["env"])
            assert (entry["F"], entry["source_P"]) == (env["F_B"], env["P_B"])
        # the viewer, its shaders and style are in the page once; nothing is fetched
        sources = webgl_sources()
        assert html.count(sources["view.js"]) == 1 and html.count(sources["view.css"]) == 1
        assert html.count("window.ShrmViewShaders = window.ShrmViewShaders ||") == 1
        assert "http://" not in html and "https://" not in html and re.search(r"<script[^>]+src=", html) is None
        # report.md says where the live preview is, report.json holds no HTML
        md = (report["folder"] / "report.md").read_text(encoding="utf-8")
        assert "**Live preview** under sky" in md and "<!-- live-view live-view-0-sky -->" in md
        assert "<script" not in (report["folder"] / "report.json").read_text(encoding="utf-8")

    def test_still_image_is_the_report_preview_and_the_camera_matches_it(self, report) -> None:
        """The first view's fallback is preview_sphere.png byte for byte; the others get a CPU still;
        the page's initial camera is the preview camera (same rays)."""
        html, folder = report["html"], report["folder"]
        first, second = (v["element_id"] for v in report["doc"]["live_preview"]["views"])
        assert _still_of(html, first) == (folder / "preview_sphere.png").read_bytes()
        assert report["doc"]["live_preview"]["views"][0]["still"] == "preview_sphere.png"
        assert report["doc"]["live_preview"]["views"][1]["still"] == "cpu-reference"
        still = np.asarray(Image.open(io.BytesIO(_still_of(html, second))))
        assert still.shape == (128, 128, 3) and still.std() > 5.0
        az, el = preview_view_angles()
        view = page_document(html, first)["view"]
        assert (view["azimuth"], view["elevation"], view["zoom"]) == pytest.approx((az, el, 1.0), abs=1e-6)
        ref = Camera.looking_at(view=np.array(PREVIEW_VIEW), up=(0.0, 0.0, 1.0), margin=1.15)
        for a, b in zip(page_camera(az, el, 1.0, 16, 16).rays(16, 16), ref.rays(16, 16), strict=True):
            assert np.allclose(a, b, atol=1e-12)

    @pytest.mark.slow
    def test_live_previews_render_from_file_url_like_the_cpu_reference(self, chromium, browser_class, report) -> None:
        """Every live view of report.html (file://) draws; its canvas is not blank, matches the CPU
        reference of the data it holds within REL_RMS_MAX and the still preview within
        STILL_REL_RMS_MAX (after downsampling to the still's size)."""
        html = report["html"]
        ids = [v["element_id"] for v in report["doc"]["live_preview"]["views"]]
        browser = browser_class(chromium, WINDOW, WINDOW)
        try:
            assert browser.open(report["url"], ids) == {i: "ready" for i in ids}
            errors = []
            for k, element_id in enumerate(ids):
                browser.wait(_canvas_sized(element_id), f"a canvas of the laid-out size in {element_id}")
                readme = os.environ.get("SHRM_README_SCREENSHOT")
                if k == 0 and readme:
                    _write_readme_screenshot(browser.screenshot(f"#{element_id}"), Path(readme))
                browser.evaluate(f"document.querySelectorAll('#{element_id} .shrm-view-info, "
                                 f"#{element_id} .shrm-view-ui').forEach(e => e.style.display = 'none')")
                shot = browser.screenshot(f"#{element_id} canvas")
                h, w = shot.shape[:2]
                assert min(h, w) >= 200 and shot.std() > 10.0  # drawn at its laid-out size, not blank
                data = page_document(html, element_id)
                ref, hit = reference_image(data, w, h)
                band = binary_dilation(hit) & ~binary_erosion(hit)
                # the object differs from the background: the sphere is drawn, not just the environment
                assert np.abs(shot[binary_erosion(hit, iterations=3)].mean() - shot[~binary_dilation(hit)].mean()) > 3.0
                whole, inside = relative_rms(shot, ref, ~band), relative_rms(shot, ref, binary_erosion(hit))
                still = np.asarray(Image.open(io.BytesIO(_still_of(html, element_id))).convert("RGB"))
                small = np.asarray(Image.fromarray(shot).resize(still.shape[1::-1], Image.Resampling.BOX))
                errors.append((element_id, round(whole, 4), round(inside, 4), round(relative_rms(small, still), 4)))
        finally:
            browser.close()
        assert all(w <= REL_RMS_MAX and i <= REL_RMS_MAX and s <= STILL_REL_RMS_MAX for _, w, i, s in errors), errors

    @pytest.mark.slow
    def test_without_webgl_the_report_shows_the_still_images(self, chromium, report) -> None:
        """With the 3D APIs disabled every viewer of report.html falls back to its still PNG, the
        first one being preview_sphere.png (DOM after the scripts ran)."""
        dom = subprocess.run([chromium, "--headless=new", "--no-sandbox", *NO_WEBGL_FLAGS, "--dump-dom", report["url"]],
                             capture_output=True, text=True, timeout=120).stdout
        ids = [v["element_id"] for v in report["doc"]["live_preview"]["views"]]
        for element_id in ids:
            root = re.search(rf'<div class="shrm-view[^"]*" id="{element_id}"[^>]*>', dom)
            assert root is not None, dom[:500]
            assert 'data-state="fallback"' in root.group(0) and "WebGL2" in root.group(0)
        assert _still_of(dom, ids[0]) == (report["folder"] / "preview_sphere.png").read_bytes()
        assert dom.count("Showing a still image") >= len(ids)


def test_preview_none_makes_no_live_view() -> None:
    options = profile("quick", preview="none", models=("lafortune",), tolerances=(0.1,), eps=0.1, n_pairs=20)
    doc, extras = collect_report("phong:s=32", options)
    assert doc["live_preview"]["views"] == [] and doc["live_preview"]["notes"]
    assert not any(isinstance(x, LiveView) for x in extras)
    assert 'class="shrm-view"' not in report_html(doc, {}, [])


def test_viewer_is_kept_once_when_several_views_share_a_page() -> None:
    """html._viewer_once: the second fragment loses the script, the shaders and the style only."""
    sources = webgl_sources()
    frag = (f"<style>{sources['view.css']}</style>\n<div id=\"b\"></div>\n"
            "<script>window.ShrmViewShaders = window.ShrmViewShaders || {\"a.glsl\":\"x;\"};</script>\n"
            f"<script>{sources['view.js']}</script>\n<script>mount()</script>")
    first, second = _viewer_once([frag, frag])
    assert first == frag
    assert second == '<div id="b"></div>\n<script>mount()</script>'


# ------------------------------------------------------------------------------------------
# in the browser
# ------------------------------------------------------------------------------------------


def _canvas_sized(element_id: str) -> str:
    return (f"(() => {{ const c = document.querySelector('#{element_id} canvas');"
            " return c.width > 16 && c.width === Math.round(c.clientWidth * (window.devicePixelRatio || 1))"
            " && c.height === Math.round(c.clientHeight * (window.devicePixelRatio || 1)); })()")


@pytest.mark.slow
def test_demo_reports_preview_live_from_file_url(chromium, browser_class, demo_run) -> None:
    """``shrm demo``: both reports (tabulated MERL files) draw their live preview from file://
    (the demo run of tests/conftest.py's demo_run, shared with tests/cli/test_cli_demo.py)."""
    assert demo_run.code == 0
    pages = sorted((demo_run.out / "report").glob("*/report.html"))
    assert len(pages) == 2
    browser = browser_class(chromium, WINDOW, WINDOW)
    try:
        for page in pages:
            doc = json.loads((page.parent / "report.json").read_text(encoding="utf-8"))
            ids = [v["element_id"] for v in doc["live_preview"]["views"]]
            assert ids and browser.open(page.resolve().as_uri(), ids) == {i: "ready" for i in ids}
            browser.wait(_canvas_sized(ids[0]), "a canvas of the laid-out size")
            browser.evaluate(f"document.querySelectorAll('#{ids[0]} .shrm-view-info, #{ids[0]} .shrm-view-ui')"
                             ".forEach(e => e.style.display = 'none')")
            shot = browser.screenshot(f"#{ids[0]} canvas")
            data = page_document(page.read_text(encoding="utf-8"), ids[0])
            ref, hit = reference_image(data, shot.shape[1], shot.shape[0])
            assert shot.std() > 10.0 and relative_rms(shot, ref, binary_erosion(hit)) <= REL_RMS_MAX
    finally:
        browser.close()


def _write_readme_screenshot(image: np.ndarray, path: Path) -> None:
    """The README's screenshot (PNG, under 150 KB), written only on request."""
    path.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(image).save(path, format="PNG", optimize=True)
    assert path.stat().st_size < 150 * 1024, path.stat().st_size


def test_preview_camera_angles() -> None:
    az, el = preview_view_angles()
    x, y, z = PREVIEW_VIEW
    assert math.isclose(math.tan(math.radians(az)), y / x) and math.isclose(math.tan(math.radians(el)),
                                                                           z / math.hypot(x, y))
    assert isinstance(PreviewImage("sphere", b"", "cpu-reference", 0.0), PreviewImage)
