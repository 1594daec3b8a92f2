"""The lights beside the SHRM (DESIGN §5a) in the WebGL2 view page (``render.webgl_page``).

The page embeds the light samples and the BRDF's parameters (``data["lights"]``,
``data_specs/view_html.md``) and shades them per pixel with the same GLSL files as the desktop
shaders (``render/webgl/brdf_*.glsl``, ``lights.glsl``). References: the numpy CPU ray caster
(``render.cpu_reference``, analytic ray–sphere intersection; the page draws a fine icosphere)
shading :meth:`SHRM.radiance` — whose lights are ``analysis.lights``'
``light_radiance``, the models' float64 ρ̂ — or, for ``distant``, the bilinear lookup of
:meth:`SHRM.view_map` plus the lights at each pixel's V; composited and tone-mapped by
``render.output.to_8bit``. Browser: headless chromium with SwiftShader WebGL2 (tests/conftest.py).
"""

from __future__ import annotations

import base64
import io
import json

import numpy as np
import pytest
from PIL import Image
from scipy.ndimage import binary_dilation, binary_erosion

import shrmkit
from shrmkit.analysis.shrm import SHRM
from shrmkit.brdf_io.latlong import bilinear_lookup
from shrmkit.brdf_io.specs import load_brdf
from shrmkit.brdf_io.table import TableBRDF, tabulate_table
from shrmkit.render.brdf_glsl import BRDF_GLSL, BrdfTable, table_light_radiance
from shrmkit.render.cpu_reference import shade, sphere_geometry
from shrmkit.render.output import composite, to_8bit
from shrmkit.render.webgl_page import ViewBudget, build_view, page_camera, page_html, stored_lights, write_view

pytestmark = pytest.mark.render

#: Screenshot size (pixels).
SIZE = 256
#: The page's mesh: an icosphere fine enough (20480 triangles) that its interpolated normals are
#: the analytic sphere's to ~1e-4 rad, far inside the narrowest highlight compared.
MESH = "builtin:sphere:subdivisions=5"
#: Relative RMS of the 8-bit screenshot against the CPU reference, silhouette band left out (the
#: threshold of tests/render/test_webgl_view.py).
REL_RMS_MAX = 0.03
MODELS = [
    "phong:s=40,ks=1/0.8/0.6",
    "microfacet:sigma=0.15,ks=1/0.5/0.25",
    "lambert:albedo=0.5/0.6/0.7",
    "lafortune:kd=0.1/0.2/0.3,cxy=-1,cz=1,n=20/30/40,ks=1,cxy2=-0.5,cz2=0.8,n2=5,ks2=0.3/0.2/0.1",
    "cook-torrance:kd=0.1,ks=1,alpha=0.2,f0=0.04/0.5/0.9,dist=beckmann",
    "cook-torrance:kd=0.05,ks=1,alpha=0.08,f0=0.9/0.6/0.3,dist=ggx",
]
#: (azimuth, elevation, zoom) of the views compared
VIEWS = [(30.0, 20.0, 1.0), (-120.0, -35.0, 1.3)]


def reference(page, shrm: SHRM, mode: str, view: tuple[float, float, float], exposure: float,
              radiance=None) -> tuple[np.ndarray, np.ndarray]:
    """8-bit CPU reference of the page's view (black background) and the hit mask."""
    camera = page_camera(*view, SIZE, SIZE)
    geometry = sphere_geometry(camera, SIZE, SIZE)
    if radiance is None and mode == "distant":
        view_map = shrm.view_map(camera.view_direction(np.zeros(3)))

        def radiance(R, V):
            return bilinear_lookup(view_map, R) + shrm.light_radiance(R, V)
    linear = shade(geometry, radiance or shrm.radiance).astype(np.float32)
    linear = composite(linear, geometry.hit.astype(np.float32), np.zeros((SIZE, SIZE, 3), np.float32))
    return to_8bit(linear, exposure=exposure, curve="filmic"), geometry.hit


def relative_rms(image: np.ndarray, ref: np.ndarray, mask: np.ndarray) -> float:
    a = image[mask].astype(np.float64) / 255.0
    b = ref[mask].astype(np.float64) / 255.0
    return float(np.sqrt(np.mean((a - b) ** 2)) / np.sqrt(np.mean(b**2)))


def inner(hit: np.ndarray) -> np.ndarray:
    """The covered pixels less the one-pixel silhouette band."""
    return hit & ~(binary_dilation(hit) & ~binary_erosion(hit))


def shot(browser, url: str, mode: str, view: tuple[float, float, float], exposure: float) -> np.ndarray:
    """Open ``url`` (when it is not the page shown), set the view in the URL hash, wait for the
    frame drawn for it and return the screenshot (H, W, 3) uint8."""
    root = "document.getElementById('shrm-view')"
    if browser.evaluate("location.href.split('#')[0]") != url:
        state = browser.open(url + "#ui=0", ["shrm-view"])["shrm-view"]
        assert state == "ready", browser.evaluate(f"{root}.dataset.reason || ''")
    az, el, zoom = view
    frames = browser.evaluate(f"{root}.dataset.frames")
    browser.evaluate(f"location.hash = {json.dumps(f'azimuth={az}&elevation={el}&zoom={zoom}&exposure={exposure}')}"
                     f" + {json.dumps(f'&mode={mode}&background=0&ui=0')}")
    browser.wait(f"{root}.dataset.frames !== {json.dumps(frames)}", "a new frame")
    browser.evaluate("new Promise(r => requestAnimationFrame(() => requestAnimationFrame(r)))", await_promise=True)
    png = base64.b64decode(browser.call("Page.captureScreenshot", session=True, format="png")["data"])
    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB"))


def write_page(folder, name: str, shrm: SHRM, **kwargs) -> tuple[object, str]:
    page = build_view(shrm, None, mesh=MESH, still="none", **kwargs)
    return page, write_view(folder / f"{name}.html", page_html(page)).resolve().as_uri()


# ------------------------------------------------------------------------------------------
# the page's document (no browser)
# ------------------------------------------------------------------------------------------


def test_page_embeds_the_samples_and_the_model(tmp_path, lights_only, n_dots) -> None:
    """data["lights"]: the samples (float32 of the SHRM's), the model's uniforms and #defines, its
    GLSL files (inlined with the viewer); a page without lights has none; the CPU still image of
    a lit scene shows the lights (distant: the map plus the lights at each pixel's V)."""
    brdf = load_brdf(MODELS[4])
    shrm = lights_only(brdf)
    page = build_view(shrm, None, mesh=MESH, still="cpu", exposure=0.0)
    lights = page.data["lights"]
    assert lights["count"] == len(shrm.lights) == n_dots and lights["model"] == "cook-torrance"
    assert lights["glsl"] == ["brdf_common.glsl", BRDF_GLSL[type(brdf)].source, "lights.glsl"]
    assert all(name in page.sources for name in lights["glsl"])
    u = lights["uniforms"]
    np.testing.assert_array_equal(np.reshape(u["shrmLightDir"]["value"], (-1, 3)),
                                  shrm.lights.directions.astype(np.float32))
    np.testing.assert_array_equal(np.reshape(u["shrmLightPower"]["value"], (-1, 3)),
                                  shrm.lights.power.astype(np.float32))
    assert u["shrmLightCount"] == {"type": "int", "value": [n_dots]}
    assert u["shrmCtAlpha"]["value"] == [np.float32(0.2)] and lights["defines"]["SHRM_CT_GGX"] == 0
    assert lights["defines"]["SHRM_NLIGHTS"] == n_dots and lights["table"] is None
    assert "light samples shaded per pixel" in page_html(page)
    # the still image (CPU reference, distant) holds the lights: the object is not black
    still = np.asarray(Image.open(io.BytesIO(page.still_png)).convert("RGB"))
    assert still.max() > 100
    stored = page.stored_shrm(shrm)
    assert stored.has_lights and stored.lights is shrm.lights
    decoded = stored_lights(page.data)  # what a reference of the page's image can read back
    np.testing.assert_allclose(decoded.directions, shrm.lights.directions, atol=1e-7)
    np.testing.assert_allclose(decoded.power, shrm.lights.power, rtol=1e-7)
    assert stored_lights({"lights": None}) is None
    plain = build_view(SHRM(F=0, P=0, coeffs=np.ones((1, 8, 16, 3), np.float32)), None, mesh=MESH, still="none")
    assert plain.data["lights"] is None


def test_measured_brdf_table_in_the_page_within_its_budget(lights_only) -> None:
    """A measured (tabulated) BRDF: its half/difference table as half floats within the budget's
    share, the error of what the page holds measured and stated in a note and in the document."""
    source = load_brdf("cook-torrance:kd=0.2,alpha=0.3,f0=0.5/0.4/0.3,dist=ggx")
    axes = (np.linspace(0.0, np.pi / 2, 24), np.linspace(0.0, np.pi / 2, 24), np.linspace(0.0, np.pi, 24))
    ti, to, pd = axes
    brdf = TableBRDF(ti, to, pd, tabulate_table(source, theta_i=ti, theta_o=to, phi_d=pd), name="ct-table")
    shrm = lights_only(brdf)
    budget = ViewBudget(page_bytes=1 << 20, brdf_bytes=200_000)
    page = build_view(shrm, None, mesh=MESH, still="none", budget=budget)
    table = page.data["lights"]["table"]
    assert table is not None and page.data["lights"]["model"] == "table"
    assert len(table["texels"]) <= 200_000 and 0.0 < table["rel_rms"] <= table["worst_band_rel_rms"]
    assert any("table of the measured BRDF" in note for note in page.notes)
    assert len(page_html(page).encode("utf-8")) <= budget.page_bytes


# ------------------------------------------------------------------------------------------
# in the browser
# ------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def browser(chromium, browser_class):
    b = browser_class(chromium, SIZE, SIZE, timeout=30.0)
    yield b
    b.close()


class TestInBrowser:
    """One unit of work under xdist (tests/conftest.py): one chromium for these tests."""

    @pytest.mark.slow
    @pytest.mark.parametrize("spec", MODELS)
    def test_each_model_against_the_cpu_reference(self, browser, tmp_path, lights_only, spec) -> None:
        """The dots map's lights alone, per model: perpixel at two views and distant at one, against
        the CPU reference of the same scene (measured 0.2–0.9 % relative RMS of the 8-bit image)."""
        shrm = lights_only(load_brdf(spec))
        page, url = write_page(tmp_path, "m", shrm, exposure=0.0)
        errors, images = [], []
        for mode, view in (("perpixel", VIEWS[0]), ("perpixel", VIEWS[1]), ("distant", VIEWS[0])):
            images.append(shot(browser, url, mode, view, 0.0))
            ref, hit = reference(page, shrm, mode, view, 0.0)
            assert ref[hit].max() > 60  # the lights are seen
            errors.append(relative_rms(images[-1], ref, inner(hit)))
        assert max(errors) <= REL_RMS_MAX, (spec, errors)
        # without the lights the object would be black: what is compared is the lights' shading (in the
        # screenshots themselves, both modes; VIEWS[0] is the view of the first and last, ``hit`` its mask)
        assert images[0][inner(hit)].max() > 60 and images[2][inner(hit)].max() > 60

    @pytest.mark.slow
    @pytest.mark.parametrize("mode", ["distant", "perpixel"])
    def test_sky_shrm_and_its_sun(self, browser, tmp_path, mode) -> None:
        """builtin:sky: the SHRM of the sky plus the sun as a light, both modes, against the CPU
        reference; the reference without the lights is far from the screenshot."""
        env = shrmkit.load_env("builtin:sky", height=32)
        shrm = shrmkit.prefilter(env, "microfacet:sigma=0.25", eps=0.05, lights="auto")
        assert shrm.has_lights
        page, url = write_page(tmp_path, "sky", shrm, exposure=0.0)
        view = VIEWS[0]
        image = shot(browser, url, mode, view, 0.0)
        stored = page.stored_shrm(shrm)
        ref, hit = reference(page, stored, mode, view, 0.0)
        err = relative_rms(image, ref, inner(hit))
        if mode == "distant":
            view_map = stored.view_map(page_camera(*view, SIZE, SIZE).view_direction(np.zeros(3)))
            without, _ = reference(page, stored, mode, view, 0.0, lambda R, V: bilinear_lookup(view_map, R))
        else:
            without, _ = reference(page, stored, mode, view, 0.0, lambda R, V: stored.radiance(R, V, lights=False))
        assert err <= REL_RMS_MAX and relative_rms(image, without, inner(hit)) > 3 * err + 0.01, err

    @pytest.mark.slow
    def test_measured_table_in_the_browser(self, browser, tmp_path, lights_only) -> None:
        """A tabulated BRDF's lights: the page's table (as stored) in WebGL equals the numpy lookup of
        that table, and the BRDF's own eval within the table's measured error."""
        source = load_brdf("cook-torrance:kd=0.2,alpha=0.3,f0=0.5/0.4/0.3,dist=ggx")
        ti, to, pd = np.linspace(0.0, np.pi / 2, 24), np.linspace(0.0, np.pi / 2, 24), np.linspace(0.0, np.pi, 24)
        brdf = TableBRDF(ti, to, pd, tabulate_table(source, theta_i=ti, theta_o=to, phi_d=pd), name="ct-table")
        shrm = lights_only(brdf)
        page, url = write_page(tmp_path, "table", shrm, exposure=0.0)
        doc = page.data["lights"]["table"]
        nh, nd, npd = doc["shape"]
        atlas = (np.frombuffer(base64.b64decode(doc["texels"]), "<f2").astype(np.float32) / np.float32(doc["scale"]))
        atlas = atlas.reshape(doc["rows"] * nd, doc["cols"] * npd, 3)
        values = np.stack([atlas[(i // doc["cols"]) * nd:(i // doc["cols"] + 1) * nd,
                                 (i % doc["cols"]) * npd:(i % doc["cols"] + 1) * npd] for i in range(nh)])
        table = BrdfTable(values, doc["scale"], periodic=doc["periodic"])

        def table_radiance(R, V):
            return table_light_radiance(table, shrm.lights, R, V)

        image = shot(browser, url, "perpixel", VIEWS[0], 0.0)
        tab, hit = reference(page, shrm, "perpixel", VIEWS[0], 0.0, table_radiance)
        exact, _ = reference(page, shrm, "perpixel", VIEWS[0], 0.0)
        assert relative_rms(image, tab, inner(hit)) <= REL_RMS_MAX
        assert relative_rms(tab, exact, inner(hit)) <= 3 * doc["worst_band_rel_rms"] + 0.01
        assert json.dumps(doc["shape"])  # the document names its grid
