"""The WebGL2 view page (``render.webgl_page``, ``shrm view``) against the CPU reference renderer.

References: the numpy CPU reference renderer (``render.cpu_reference``: analytic ray–sphere
intersection, then :meth:`SHRM.radiance` for ``perpixel`` or the bilinear lookup of
:meth:`SHRM.view_map` for ``distant``), composited over the environment the page holds and
tone-mapped by ``render.output.to_8bit``, for the camera of ``webgl_page.page_camera``;
``analysis.sh.real_sph_harm`` for the viewer's JavaScript SH. The browser is Debian's
``chromium`` (headless, SwiftShader WebGL2 through ANGLE), driven over the DevTools protocol on
a pipe (``--remote-debugging-pipe``: one browser for every screenshot); measured on Chromium
156 with SwiftShader: relative RMS of the 8-bit image 0.3–0.9 % (data_specs/view_html.md,
Tests). The browser tests are marked slow and skip with a message where chromium is absent
(CI installs it: .ci/apt-packages.txt).
"""

from __future__ import annotations

import base64
import io
import json
import re
import subprocess
from pathlib import Path

import numpy as np
import pytest
from PIL import Image
from scipy.ndimage import binary_dilation, binary_erosion

import shrmkit
from shrmkit.analysis.sh import real_sph_harm
from shrmkit.analysis.shrm import SHRM
from shrmkit.brdf_io.errors import BadInputError
from shrmkit.brdf_io.latlong import bilinear_lookup, pixel_directions
from shrmkit.cli.main import main
from shrmkit.render.camera import Camera
from shrmkit.render.cpu_reference import shade, sphere_geometry
from shrmkit.render.output import composite, environment_background, to_8bit
from shrmkit.render.webgl_page import (
    ViewBudget,
    build_view,
    fit_coefficients,
    page_camera,
    page_html,
    view_fragment,
    write_view,
)

#: Screenshot size (pixels) of the browser tests.
SIZE = 256
#: Relative RMS of the 8-bit sRGB screenshot against the CPU reference (silhouette band of one
#: pixel left out): the documented threshold (data_specs/view_html.md; measured ≤ 0.9 %).
REL_RMS_MAX = 0.03
#: The fixed views: (azimuth, elevation, zoom, exposure offset in stops from the page's default).
VIEWS = [(30.0, 20.0, 1.0, 0.0), (-90.0, 0.0, 1.0, 1.0), (160.0, -30.0, 1.6, 0.0)]
MATERIALS = ["microfacet:sigma=0.2", "cook-torrance:alpha=0.3,f0=0.5"]
OTHER_MODE = {"distant": "perpixel", "perpixel": "distant"}


# ------------------------------------------------------------------------------------------
# the view page in headless chromium (the driver: ``Browser`` of tests/conftest.py)
# ------------------------------------------------------------------------------------------


def _open(browser, url: str) -> str:
    """Navigate to ``url`` and wait until the viewer is ready or shows the fallback; its state."""
    return browser.open(url, ["shrm-view"])["shrm-view"]


def _screenshot(browser, hash_params: str) -> np.ndarray:
    """The view page after setting its URL hash (``Browser.view_frame`` of tests/conftest.py)."""
    return browser.view_frame(hash_params)


@pytest.fixture(scope="module")
def browser(chromium, browser_class):
    b = browser_class(chromium, SIZE, SIZE, timeout=30.0)
    yield b
    b.close()


@pytest.fixture(scope="module")
def sky():
    return shrmkit.load_env("builtin:sky", height=64)


@pytest.fixture(scope="module")
def material_pages(sky, tmp_path_factory) -> dict:
    """Per material: the SHRM, its page and the page's file URL (no still image: not needed)."""
    folder = tmp_path_factory.mktemp("view")
    out = {}
    for k, spec in enumerate(MATERIALS):
        shrm = shrmkit.prefilter(sky, spec, eps=0.05, size=64)
        page = build_view(shrm, sky, still="none")
        path = write_view(folder / f"m{k}.html", page_html(page))
        out[spec] = (shrm, page, path.resolve().as_uri())
    return out


def reference_image(shrm: SHRM, page, mode: str, az: float, el: float, zoom: float, exposure: float,
                    background: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """8-bit CPU reference of the page's view and the hit mask: analytic sphere, SHRM.radiance
    (perpixel) or the bilinear lookup of SHRM.view_map(Ṽ) (distant), over the page's environment."""
    camera = page_camera(az, el, zoom, SIZE, SIZE)
    geometry = sphere_geometry(camera, SIZE, SIZE)
    if mode == "perpixel":
        radiance = shade(geometry, shrm.radiance)
    else:
        view_map = shrm.view_map(camera.view_direction(np.zeros(3)))
        # the map holds the SHRM part; the explicit lights are shaded at each pixel's V (DESIGN §5a)
        radiance = shade(geometry, lambda R, V: bilinear_lookup(view_map, R) + shrm.light_radiance(R, V))
    if background:
        bg = environment_background(page.env_radiance, camera, SIZE, SIZE)
    else:
        bg = np.zeros((SIZE, SIZE, 3), np.float32)
    linear = composite(radiance.astype(np.float32), geometry.hit.astype(np.float32), bg)
    return to_8bit(linear, exposure=exposure, curve="filmic"), geometry.hit


def relative_rms(image: np.ndarray, reference: np.ndarray, mask: np.ndarray) -> float:
    a = image[mask].astype(np.float64) / 255.0
    b = reference[mask].astype(np.float64) / 255.0
    return float(np.sqrt(np.mean((a - b) ** 2)) / np.sqrt(np.mean(b**2)))


# ------------------------------------------------------------------------------------------
# browser tests
# ------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def references() -> dict:
    """CPU reference images already drawn, by (material, mode, az, el, zoom, exposure): the
    ``distant`` test compares against the ``perpixel`` reference of the same view and the other way
    round, so each of the 12 references is drawn once instead of twice (0.8 s CPU a perpixel one)."""
    return {}


class TestInBrowser:
    """The tests of the browser and material_pages fixtures: one unit of work under xdist
    (tests/conftest.py), one chromium and one set of pages."""

    @pytest.mark.slow
    @pytest.mark.parametrize("mode", ["distant", "perpixel"])
    @pytest.mark.parametrize("material", MATERIALS)
    def test_screenshots_match_cpu_reference(self, browser, material_pages, references, material, mode) -> None:
        """Three views (orbit, exposure, zoom from the URL hash) of the page in chromium against the
        CPU reference renderer of the same SHRM and camera: relative RMS of the 8-bit image ≤
        REL_RMS_MAX, on the whole image and on the object, the one-pixel silhouette band left out
        (the page draws an icosphere of 5120 triangles, the reference the analytic sphere); and
        the object is at least twice as far from the other mode's reference."""
        shrm, page, url = material_pages[material]
        assert _open(browser, url + "#ui=0") == "ready"
        base = page.data["view"]["exposure"]
        errors = []
        for az, el, zoom, dexp in VIEWS:
            exposure = base + dexp
            shot = _screenshot(browser, f"azimuth={az}&elevation={el}&zoom={zoom}&exposure={exposure}&mode={mode}&ui=0")
            for drawn in (mode, OTHER_MODE[mode]):
                key = (material, drawn, az, el, zoom, exposure)
                if key not in references:
                    references[key] = reference_image(shrm, page, drawn, az, el, zoom, exposure)
            ref, hit = references[(material, mode, az, el, zoom, exposure)]
            other, _ = references[(material, OTHER_MODE[mode], az, el, zoom, exposure)]
            band = binary_dilation(hit) & ~binary_erosion(hit)
            inner = binary_erosion(hit)
            whole, inside = relative_rms(shot, ref, ~band), relative_rms(shot, ref, inner)
            errors.append((az, el, zoom, round(whole, 4), round(inside, 4), round(relative_rms(shot, other, inner), 4)))
        # within the threshold, and the mode drawn is the one asked for (the other mode's image is
        # 2.8-12 % away from it on these views)
        assert all(w <= REL_RMS_MAX and i <= REL_RMS_MAX and 2.0 * i < o for *_, w, i, o in errors), errors

    @pytest.mark.slow
    @pytest.mark.parametrize("mode", ["distant", "perpixel"])
    def test_spot_on_plus_x_lights_the_right_half_seen_from_minus_y(self, browser, tmp_path, mode) -> None:
        """Orientation: builtin:spot at +x seen from −y (azimuth −90°) lights the right half of the
        screenshot (image right = +x), as in the VTK renderer's test; the page agrees with the CPU
        reference there."""
        env = shrmkit.load_env("builtin:spot,dir=x", height=32)
        shrm = shrmkit.prefilter(env, "microfacet:sigma=0.2", eps=0.05, size=32)
        page = build_view(shrm, env, still="none", exposure=0.0)
        url = write_view(tmp_path / "spot.html", page_html(page)).resolve().as_uri()
        assert _open(browser, url + "#ui=0") == "ready"
        shot = _screenshot(browser, f"azimuth=-90&elevation=0&mode={mode}&background=0&ui=0")
        lum = shot.astype(np.float64).sum(axis=-1)
        half = SIZE // 2
        assert lum[:, half:].sum() > 5.0 * lum[:, :half].sum()
        ref, hit = reference_image(shrm, page, mode, -90.0, 0.0, 1.0, 0.0, background=False)
        assert relative_rms(shot, ref, binary_erosion(hit)) <= REL_RMS_MAX

    @pytest.mark.slow
    def test_javascript_sh_match_analysis_sh(self, browser, material_pages) -> None:
        """ShrmView.realSH (the recurrence the shaders use) equals analysis.sh.real_sph_harm to 1e-12 up to P = 20."""
        _, _, url = material_pages[MATERIALS[0]]
        _open(browser, url + "#ui=0")
        rng = np.random.default_rng(3)
        v = rng.normal(size=(6, 3))
        v /= np.linalg.norm(v, axis=1, keepdims=True)
        v[0] = (0.0, 0.0, 1.0)  # a pole
        got = np.array(browser.evaluate(f"{json.dumps(v.tolist())}"
                                        ".map(d => Array.from(window.ShrmView.realSH(20, d)))"))
        assert np.abs(got - real_sph_harm(20, v)).max() < 1e-12

    @pytest.mark.slow
    def test_first_frame_fills_the_canvas_without_interaction(self, browser, material_pages) -> None:
        """A page opened as is (no hash change, no resize, no input) draws at the canvas's laid-out
        size: the first frame used to be drawn while the canvas was hidden, leaving it 1 × 1."""
        _, _, url = material_pages[MATERIALS[0]]
        assert _open(browser, url) == "ready"
        browser.evaluate("new Promise(r => setTimeout(() => requestAnimationFrame(r), 300))", await_promise=True)
        width, height = browser.evaluate(
            "(() => { const c = document.querySelector('#shrm-view canvas'); return [c.width, c.height]; })()")
        assert width >= SIZE // 2 and height >= SIZE // 2, (width, height)


@pytest.mark.slow
def test_without_webgl2_the_page_shows_the_still_image(chromium, browser_class, sky, tmp_path) -> None:
    """With the 3D APIs disabled the viewer falls back to the embedded PNG (DOM after the scripts ran)."""
    shrm = shrmkit.prefilter(sky, "phong:s=32", eps=0.05, size=32)
    page = build_view(shrm, sky, still="cpu")
    url = write_view(tmp_path / "still.html", page_html(page)).resolve().as_uri()
    dom = subprocess.run([chromium, *browser_class.FLAGS, "--disable-3d-apis", "--disable-webgl", "--dump-dom", url],
                         capture_output=True, text=True, timeout=60).stdout
    root = re.search(r'<div class="shrm-view"[^>]*>', dom)
    assert root is not None, dom[:500]
    assert 'data-state="fallback"' in root.group(0) and "WebGL2" in root.group(0)
    img = re.search(r'<img class="shrm-view-fallback"[^>]*src="data:image/png;base64,([^"]+)"', dom)
    assert img is not None
    still = np.asarray(Image.open(io.BytesIO(base64.b64decode(img.group(1)))))
    assert still.shape == (384, 384, 3) and still.std() > 1.0
    assert "Showing a still image" in dom


# ------------------------------------------------------------------------------------------
# the page without a browser
# ------------------------------------------------------------------------------------------


def test_page_is_self_contained_and_within_budget(sky) -> None:
    """No network reference, the viewer and all shaders inlined, size within the budget."""
    shrm = shrmkit.prefilter(sky, "phong:s=32", eps=0.05, size=32)
    page = build_view(shrm, sky, still="none")
    text = page_html(page)
    assert len(text.encode("utf-8")) <= ViewBudget().page_bytes
    assert "http://" not in text and "https://" not in text and "<link" not in text
    assert re.search(r"<script[^>]+src=", text) is None
    for name in ("latlong.glsl", "shrm_sum.glsl", "tonemap.glsl", "object_perpixel.frag", "background.frag"):
        assert json.dumps(name) in text
    # the stored coefficients are the SHRM's to half-float precision (nothing reduced)
    assert not page.fit.reduced and page.notes == ()
    assert np.abs(page.coeffs - shrm.coeffs).max() <= 1e-3 * np.abs(shrm.coeffs).max()


def test_placeholders_in_user_text_are_not_substituted_again(sky) -> None:
    """A title holding the template's own placeholders and HTML (issue 28: an environment named
    `{{FRAGMENT}}.hdr` made `shrm view` paste the page fragment into itself): the page holds one
    viewer, the title appears as text (escaped), and no placeholder is left or re-expanded."""
    from dataclasses import replace

    shrm = shrmkit.prefilter(sky, "phong:s=32", eps=0.05, size=32)
    hostile = '{{FRAGMENT}} {{TITLE}} {{VERSION}} </script><img src=x onerror="alert(1)">'
    text = page_html(replace(build_view(shrm, sky, still="none"), title=hostile))
    assert text.count('<div class="shrm-view" id="shrm-view"') == 1
    assert text.count("window.ShrmView.mount(") == 1
    assert "<img src=x" not in text and "&lt;img src=x onerror=&quot;alert(1)&quot;&gt;" in text
    assert f"<title>{'{{FRAGMENT}} {{TITLE}} {{VERSION}}'}" in text


def test_over_budget_material_is_reduced_with_a_visible_note(sky) -> None:
    """A synthetic SHRM of 81 maps 96×192 (27 MiB as half floats) in a 2 MiB page: the page holds,
    the note is in the HTML, and the estimated added error is the measured one within 30 %
    (measured: SHRM.radiance of the stored against the given coefficients, 4000 random pairs)."""
    P, H, W = 8, 96, 192
    rng = np.random.default_rng(0)
    dirs = pixel_directions(H, W)
    c = np.zeros(((P + 1) ** 2, H, W, 3), np.float32)
    for k in range(c.shape[0]):  # smooth maps, energy falling with the view band p
        p = int(np.sqrt(k))
        lobe = np.exp(4.0 * (dirs @ rng.normal(size=3) / 2.0))[..., None]
        c[k] = lobe * rng.uniform(0.5, 1.0, 3) * 0.5**p
    shrm = SHRM(F=20, P=P, coeffs=c, meta={"brdf": "synthetic", "environment": "sky"})
    budget = ViewBudget(page_bytes=2 << 20)
    page = build_view(shrm, sky, still="none", budget=budget)
    text = page_html(page)
    assert len(text.encode("utf-8")) <= budget.page_bytes
    assert page.fit.reduced and page.notes and "page budget" in page.notes[-1]
    assert page.notes[-1].split(":")[0] in text  # the note is on the page
    R = rng.normal(size=(4000, 3))
    V = rng.normal(size=(4000, 3))
    kept = page.stored_shrm(shrm)
    a = shrm.radiance(R, V, clamp=False)
    b = kept.radiance(R, V, clamp=False)
    measured = np.sqrt(np.mean((a - b) ** 2) / np.mean(a**2))
    assert 0.7 * measured <= page.fit.added_rel_rms <= 1.3 * measured + 0.005


def test_budget_rule_drops_empty_view_bands_before_resolution() -> None:
    """Maps with nothing in p ≥ 2 lose those bands (no error) rather than resolution; constant
    maps lose resolution (no error) rather than bands."""
    P, H, W = 3, 64, 128
    rng = np.random.default_rng(1)
    dirs = pixel_directions(H, W)
    c = np.zeros(((P + 1) ** 2, H, W, 3), np.float32)
    for k in range(4):
        c[k] = np.exp(3.0 * dirs @ rng.normal(size=3))[..., None]
    fit = fit_coefficients(c, P, max_bytes=4 * H * W * 6)
    assert fit.P == 1 and fit.coeffs.shape[1:3] == (H, W) and fit.added_rel_rms == 0.0
    flat = np.ones(((P + 1) ** 2, H, W, 3), np.float32)
    fit = fit_coefficients(flat, P, max_bytes=flat.size * 2 // 4)
    assert fit.P == P and fit.coeffs.shape[1] < H and fit.added_rel_rms < 1e-6


def test_mesh_is_decimated_to_its_budget(sky) -> None:
    shrm = shrmkit.prefilter(sky, "phong:s=32", eps=0.05, size=32)
    budget = ViewBudget(mesh_bytes=64 << 10)
    page = build_view(shrm, sky, mesh="builtin:torus-knot:segments=256,sides=24", still="none", budget=budget)
    mesh = page.data["mesh"]
    assert mesh["triangles"] < 256 * 24 * 2
    assert mesh["vertices"] * 24 + mesh["triangles"] * 6 <= budget.mesh_bytes
    assert any("decimated" in n for n in page.notes)
    assert np.linalg.norm(page.mesh.vertices, axis=1).max() <= 1.0 + 1e-9


def test_page_camera_is_the_documented_camera() -> None:
    """Azimuth 0, elevation 0, zoom 1: Camera.looking_at from +x with margin CAMERA_MARGIN (same rays)."""
    mine = page_camera(0.0, 0.0, 1.0, 8, 8)
    ref = Camera.looking_at(view=(1.0, 0.0, 0.0), margin=1.15)
    for a, b in zip(mine.rays(8, 8), ref.rays(8, 8), strict=True):
        assert np.allclose(a, b, atol=1e-12)
    cam = page_camera(90.0, 0.0, 2.0, 8, 8)
    assert np.allclose(cam.eye, (0.0, 3.0, 0.0)) and np.isclose(np.tan(cam.fov_y / 2), np.tan(ref.fov_y / 2) / 2)


def test_fragment_for_reports(sky) -> None:
    """The fragment a report embeds: its own id, no URL-hash control, every script inline."""
    shrm = shrmkit.prefilter(sky, "phong:s=32", eps=0.05, size=32)
    page = build_view(shrm, sky, still="none")
    frag = view_fragment(page, element_id="view-sky")
    assert 'id="view-sky"' in frag and 'id="view-sky-data"' in frag and "{hash: false}" in frag
    with pytest.raises(BadInputError):
        view_fragment(page, element_id="x y")


def test_bad_view_values_are_refused(sky) -> None:
    shrm = shrmkit.prefilter(sky, "phong:s=32", eps=0.05, size=32)
    for kwargs in ({"mode": "rsibr"}, {"tone": "aces"}, {"zoom": 0.0}, {"elevation": 95.0},
                   {"exposure": float("nan")}, {"still": "png"}):
        with pytest.raises(BadInputError):
            build_view(shrm, sky, **kwargs)


def test_cli_view_writes_the_page(tmp_path: Path, capsys) -> None:
    out = tmp_path / "v.html"
    rc = main(["view", "phong:s=32", "--env", "builtin:studio", "--size", "32", "--still", "cpu",
               "--azimuth", "-45", "--mode", "perpixel", "-o", str(out)])
    assert rc == 0
    text = out.read_text(encoding="utf-8")
    assert out.stat().st_size <= ViewBudget().page_bytes and 'class="shrm-view"' in text
    assert '"azimuth":-45.0' in text and '"mode":"perpixel"' in text
    assert "wrote" in capsys.readouterr().out


def test_cli_view_bad_input(tmp_path: Path, capsys) -> None:
    assert main(["view", "phong:s=32", "-o", str(tmp_path / "v.png")]) == 2
    assert "html" in capsys.readouterr().err
    assert main(["view", "nosuchbrdf:x=1", "-o", str(tmp_path / "v.html")]) == 2
    assert not (tmp_path / "v.html").exists()
    with pytest.raises(SystemExit):
        main(["view", "phong:s=32", "--elevation", "120", "-o", str(tmp_path / "v.html")])


