"""The lights' BRDF table: the below-surface fill and the partial tabulation against slow paths."""

import numpy as np
import pytest

from shrmkit.brdf_io.halfdiff import halfdiff_to_directions
from shrmkit.brdf_io.specs import load_brdf
from shrmkit.render._brdf_table import _lookup_mask, table_angles, tabulate_brdf


def _slow_table(brdf, shape, periodic):
    """Every sample evaluated alone, ρ cos θ_L cos θ_V; past the last sample above the surface along θ_d,
    that sample."""
    nh, nd, npd = shape
    th, td, pd = table_angles(shape, periodic)
    out = np.zeros((nh, nd, npd, 3))
    for i in range(nh):
        for k in range(npd):
            L, V = halfdiff_to_directions(np.full(nd, th[i]), td, np.full(nd, pd[k]))
            rho = np.asarray(brdf.eval(L, V), np.float64) * (np.maximum(L[:, 2], 0) * np.maximum(V[:, 2], 0))[:, None]
            above = np.flatnonzero((L[:, 2] > 0) & (V[:, 2] > 0))
            if above.size and above[-1] < nd - 1:
                rho[above[-1] + 1:] = rho[above[-1]]
            out[i, :, k] = rho
    return out.astype(np.float32)


def test_table_and_its_partial_tabulation_match_sample_by_sample_evaluation():
    brdf = load_brdf("cook-torrance:alpha=0.2,kd=0.1,ks=0.5")
    shape = (9, 11, 13)
    slow = _slow_table(brdf, shape, periodic=False)
    full = tabulate_brdf(brdf, shape, periodic=False)
    np.testing.assert_allclose(full.values, slow, rtol=1e-6, atol=0)
    # the samples read by lookups at random directions, evaluated alone, hold the same values
    rng = np.random.default_rng(3)
    L = rng.normal(size=(200, 3))
    V = rng.normal(size=(200, 3))
    L[:, 2], V[:, 2] = np.abs(L[:, 2]), np.abs(V[:, 2])
    L /= np.linalg.norm(L, axis=1, keepdims=True)
    V /= np.linalg.norm(V, axis=1, keepdims=True)
    mask = _lookup_mask(shape, False, L, V)
    assert 0 < mask.sum() < mask.size
    part = tabulate_brdf(brdf, shape, periodic=False, only=mask)
    np.testing.assert_array_equal(part.values[mask], full.values[mask])
    assert not part.values[~mask].any()


def test_light_near_the_horizon_is_not_blown_up_by_the_table(shared_data):
    """An RGL material's ρ grows like 1/cos θ_L toward the horizon: a table of ρ itself spread a node's
    value at cos θ_L ≈ 0.001 over its cell, and lights 1-3° above the horizon came out up to 24× too
    bright in `shrm render` (issue 29's Mitsuba comparison). The table holds ρ cos θ_L cos θ_V."""
    from shrmkit.render.brdf_glsl import table_lookup

    brdf = load_brdf(str(shared_data / "brdf" / "rgl" / "colodur_napoli_4f_rgb.bsdf"))
    table = tabulate_brdf(brdf, (46, 46, 91), periodic=False)
    rng = np.random.default_rng(5)
    n = 4000
    lz, vz = rng.uniform(0.01, 0.05, n), rng.uniform(0.5, 1.0, n)
    pl, pv = rng.uniform(0, 2 * np.pi, n), rng.uniform(0, 2 * np.pi, n)
    L = np.stack([np.sqrt(1 - lz**2) * np.cos(pl), np.sqrt(1 - lz**2) * np.sin(pl), lz], axis=1)
    V = np.stack([np.sqrt(1 - vz**2) * np.cos(pv), np.sqrt(1 - vz**2) * np.sin(pv), vz], axis=1)
    exact = np.asarray(brdf.eval(L, V)) * lz[:, None]
    got = table_lookup(table, L, V)
    rel = np.sqrt(np.sum((got - exact) ** 2) / np.sum(exact**2))
    assert rel < 0.2, rel
    assert np.max(got[:, 1] / np.maximum(exact[:, 1], 1e-12)) < 3.0


def test_theta_d_rows_are_exactly_the_rows_lookups_in_the_view_cones_read():
    """Brute force: for lights L and cones of views (axis A, half-angle a), the rows the lookups at
    (L, V) read, V densely over each cone with its two extremes (V in the plane of L and A at ±a
    from A: θ_d = ½(γ ∓ a); V = L when L is in the cone) and its rim, are the band of
    ``theta_d_rows`` with margin 0 — every row inside, both end rows read (a band one row narrower
    at either end misses a read) — and the default band is that one with a margin row on each side."""
    from shrmkit.render._brdf_table import THETA_D_MARGIN_ROWS, _lookup_corners, theta_d_ranges, theta_d_rows

    rng = np.random.default_rng(11)
    shape = (91, 91, 181)
    nd = shape[1]
    for _ in range(6):
        L = rng.normal(size=3)
        L /= np.linalg.norm(L)
        A = rng.normal(size=3)
        A /= np.linalg.norm(A)
        for a in (0.0, 0.2, 0.7, 1.4):
            # V over the cone: rim and interior about A, plus the two extremes toward and away from L
            u = np.cross(A, L)
            u = u / np.linalg.norm(u) if np.linalg.norm(u) > 0 else np.cross(A, [1.0, 0.0, 0.0])
            w = np.cross(A, u)
            ang, rad = np.meshgrid(np.linspace(0, 2 * np.pi, 181), np.linspace(0, a, 12))
            V = (np.cos(rad)[..., None] * A + np.sin(rad)[..., None]
                 * (np.cos(ang)[..., None] * u + np.sin(ang)[..., None] * w)).reshape(-1, 3)
            toward = L - np.dot(L, A) * A
            toward = toward / np.linalg.norm(toward) if np.linalg.norm(toward) > 0 else w
            V = np.concatenate([V, [np.cos(a) * A + np.sin(a) * toward, np.cos(a) * A - np.sin(a) * toward]]
                               + ([L[None]] if np.dot(L, A) >= np.cos(a) else []))  # L in the cone: θ_d = 0
            _, (j0, j1), _, _ = _lookup_corners(shape, False, np.broadcast_to(L, V.shape), V)
            read = np.zeros(nd, bool)
            read[j0] = read[j1] = True
            ranges = theta_d_ranges(L[None], [(A, a)])
            band = theta_d_rows(ranges, nd, margin=0)
            np.testing.assert_array_equal(read, band, err_msg=f"a={a}: rows read {np.flatnonzero(read)}")
            first, last = np.flatnonzero(band)[[0, -1]]
            wide = np.zeros(nd, bool)
            wide[max(first - THETA_D_MARGIN_ROWS, 0):last + THETA_D_MARGIN_ROWS + 1] = True
            np.testing.assert_array_equal(theta_d_rows(ranges, nd), wide)


def test_view_cone_holds_every_direction_to_the_eye_and_no_wider():
    """``Camera.view_cone`` against brute force: the directions toward the eye from points in and on
    the ball (centre, r) lie within the cone, and the tangent points reach its half-angle asin(r/d);
    ortho: −forward, half-angle 0; the eye inside the ball: every direction (π)."""
    from shrmkit.render.camera import Camera

    rng = np.random.default_rng(2)
    centre, r = np.array([0.3, -0.2, 0.1]), 0.7
    cam = Camera.looking_at(center=centre, view=(1.0, 0.35, 0.45), radius=r, distance=2.0)
    axis, a = cam.view_cone(centre, r)
    assert a == pytest.approx(np.arcsin(r / 2.0), abs=1e-12)
    p = rng.normal(size=(20000, 3))
    p = centre + r * p / np.linalg.norm(p, axis=1, keepdims=True) * rng.uniform(0, 1, (len(p), 1)) ** 0.25
    v = cam.eye - p
    ang = np.arccos(np.clip((v / np.linalg.norm(v, axis=1, keepdims=True)) @ axis, -1, 1))
    assert ang.max() <= a + 1e-12 and ang.max() > a - 0.01
    ortho = Camera.looking_at(center=centre, view=(1.0, 0.35, 0.45), radius=r, projection="ortho")
    np.testing.assert_array_equal(ortho.view_cone(centre, r)[0], -ortho.forward)
    assert ortho.view_cone(centre, r)[1] == 0.0
    assert cam.view_cone(cam.eye + [0.1, 0.0, 0.0], 0.5)[1] == np.pi


def _sun_only(brdf):
    """A lights-only SHRM (black maps) of builtin:sky's sun at 32 rows (the quick report's map)."""
    import shrmkit
    from shrmkit.analysis.lights import extract_lights
    from shrmkit.analysis.shrm import SHRM

    lights = extract_lights(shrmkit.load_env("builtin:sky", height=32), "auto").lights
    return SHRM(F=0, P=0, coeffs=np.zeros((1, 8, 16, 3), np.float32),
                meta={"max_view_deg": 80.0, "brdf": brdf.name, "environment": "sky", "lights_requested": "auto"},
                lights=lights, brdf=brdf)


def _table_brdf():
    """A measured-kind BRDF (a Cook–Torrance sampled on a 24³ (θ_i, θ_o, φ_d) grid): the shaders tabulate it."""
    from shrmkit.brdf_io.table import TableBRDF, tabulate_table

    axes = (np.linspace(0.0, np.pi / 2, 24), np.linspace(0.0, np.pi / 2, 24), np.linspace(0.0, np.pi, 24))
    source = load_brdf("cook-torrance:kd=0.2,alpha=0.3,f0=0.5/0.4/0.3,dist=ggx")
    return TableBRDF(*axes, tabulate_table(source, theta_i=axes[0], theta_o=axes[1], phi_d=axes[2]), name="ct-table")


def test_views_table_reads_as_the_whole_one_at_every_pixel_of_the_preview():
    """The report preview's camera on the unit sphere, unrotated and under an environment rotation:
    the lights' reflection looked up (``table_light_radiance``, as the shader) in the table made for
    those views equals, at every pixel, the whole table's, to the bit; its stated error is the whole
    table's; it holds a fraction of the texels. A table made ignoring the rotation does not (the test
    sees a band that misses the rotated frame's rows)."""
    from shrmkit.brdf_io.env_rotation import env_rotation_matrix
    from shrmkit.render.brdf_glsl import light_shading, table_light_radiance
    from shrmkit.render.cpu_reference import shade, sphere_geometry
    from shrmkit.render.mesh import load_mesh
    from shrmkit.render.pipeline import view_cones
    from shrmkit.render.preview import preview_camera

    shrm = _sun_only(_table_brdf())
    camera = preview_camera()
    geometry = sphere_geometry(camera, 64, 64)
    sphere = load_mesh("builtin:sphere:subdivisions=1")
    whole = light_shading(shrm)
    assert whole.table.rows is None and whole.table.tabulated == np.prod(whole.table.shape)
    def image(table, q):
        return shade(geometry, lambda R, V: table_light_radiance(table, shrm.lights, R, V), env_rotation=q)

    tables = {}
    turned = env_rotation_matrix(150.0, 30.0)
    for name, q in (("none", None), ("rotated", turned)):
        views = light_shading(shrm, views=view_cones(sphere, [camera], q))
        assert views.table_error == whole.table_error  # the stated error, to the bit
        assert views.table.rows is not None and views.table.tabulated < 0.6 * whole.table.tabulated
        assert views.table.missing <= whole.table.missing
        ref = image(whole.table, q)
        assert ref.max() > 0
        np.testing.assert_array_equal(image(views.table, q), ref, err_msg=name)
        tables[name] = views.table
    assert tables["none"].rows != tables["rotated"].rows
    assert not np.array_equal(image(tables["none"], turned), ref)  # the rotation ignored: rows missing


def test_light_shading_cache_keys_on_the_views_the_table_was_made_for():
    """``cached_light_shading``: a table made for one camera is not handed to a render from another
    whose θ_d rows it lacks (the whole table is made then, and replaces it); it is reused for views
    within its rows."""
    from shrmkit.render._brdf_table import table_covers, theta_d_ranges
    from shrmkit.render.camera import Camera
    from shrmkit.render.shader import cached_light_shading

    shrm = _sun_only(_table_brdf())
    sun = shrm.lights.directions[0]
    ortho = [(Camera.looking_at(view=sun, projection="ortho").view_cone(np.zeros(3), 1.0))]  # θ_d ≈ 0
    behind = [(Camera.looking_at(view=-sun + [0.0, 0.0, 0.5], projection="ortho").view_cone(np.zeros(3), 1.0))]
    first = cached_light_shading(shrm, ortho)
    assert first.table.rows is not None
    assert not table_covers(first.table, theta_d_ranges(shrm.lights.directions, behind))
    assert cached_light_shading(shrm, ortho) is first  # made once per views
    second = cached_light_shading(shrm, behind)
    assert second is not first and table_covers(second.table, theta_d_ranges(shrm.lights.directions, behind))
    # a second set of views it lacks: the whole table, which replaces the partial one (one table kept per
    # SHRM, however many cameras a frame-by-frame caller brings)
    assert second.table.rows is None
    assert cached_light_shading(shrm, ortho) is second and cached_light_shading(shrm) is second
    for k in range(6):  # a camera circling the sphere: nothing new is made
        around = [Camera.looking_at(view=[np.cos(k), np.sin(k), 0.3], projection="ortho").view_cone(np.zeros(3), 1.0)]
        assert cached_light_shading(shrm, around) is second


@pytest.mark.render
def test_render_frames_with_the_views_table_equal_the_whole_tables(offscreen):
    """``render_frames`` tabulates the lights' table only for its cameras (and per-frame environment
    rotations); the float frames equal, bit for bit, those drawn with the whole table (the same
    SHRM content, its cache given the whole table first): the report preview's camera (``distant``),
    an ortho camera, a camera close to the sphere (a 50° cone of views), a lighting turntable
    (``env_rotation`` per frame) in ``perpixel``."""
    from shrmkit.render.camera import Camera
    from shrmkit.render.mesh import load_mesh
    from shrmkit.render.pipeline import light_turntable_rotations, render_frames
    from shrmkit.render.preview import preview_camera
    from shrmkit.render.shader import cached_light_shading

    brdf = _table_brdf()
    sphere = load_mesh("builtin:sphere:subdivisions=2")
    view = (1.0, 0.35, 0.45)
    cases = [("preview", "distant", [preview_camera()], None),
             ("ortho", "distant", [Camera.looking_at(view=view, projection="ortho")], None),
             ("close", "distant", [Camera.looking_at(view=view, distance=1.3)], None),
             ("turntable", "perpixel", [preview_camera()] * 3, light_turntable_rotations(3))]
    for name, mode, cameras, rotations in cases:
        frames = []
        for whole in (True, False):
            shrm = _sun_only(brdf)
            if whole:
                assert cached_light_shading(shrm).table.rows is None
            out, _ = render_frames(sphere, shrm, cameras, size=32, mode=mode, background="black", fps_frames=0,
                                   env_rotation=rotations)
            frames.append(np.stack([f.linear for f in out]))
            made = cached_light_shading(shrm, [])  # no views: the SHRM's first shading, the one rendered
            assert (made.table.rows is None) == whole, name
        assert frames[0].max() > 0, name
        np.testing.assert_array_equal(frames[1], frames[0], err_msg=name)


def test_render_info_says_what_the_table_covers():
    """``info["lights"]["brdf_table"]`` (``shrm render``'s JSON): a whole table (the build knows no
    cameras) says every θ_d row and every texel; the description of a table made for some views names
    its rows and share of texels."""
    from shrmkit.render.brdf_glsl import light_shading
    from shrmkit.render.camera import Camera
    from shrmkit.render.modes import lights_info

    shrm = _sun_only(_table_brdf())
    info, line = lights_info(shrm)
    table = info["brdf_table"]
    nh, nd, npd = table["shape"]
    assert table["theta_d_rows"] == [[0, nd - 1]] and table["texels"] == nh * nd * npd and table["missing"] == 0
    assert {"rel_rms", "worst_band_rel_rms", "grids_tried", "seconds"} <= set(table)
    assert "tabulated in theta_d rows" not in line
    cone = Camera.looking_at(view=shrm.lights.directions[0], projection="ortho").view_cone(np.zeros(3), 1.0)
    views = light_shading(shrm, views=[cone])
    (first, last), = views.table.rows
    assert f"tabulated in theta_d rows {first}-{last}, the views'" in views.describe()
