"""Rotating the environment at view time (brdf_io.env_rotation, SHRM.radiance(env_rotation=)).

References: a fresh prefilter of the rotated map, made from the closed-form map evaluated at the
rotated directions (no resampling: L_Q(ω) = L(Qᵀ ω) computed exactly on the lat-long grid); an exact
column roll of the lat-long map (``EnvironmentMap.rotated_z`` by a whole number of columns, which
is what ``load_env(azimuth=)`` / ``--env-azimuth`` does); rotation matrices written out by hand.
"""

from __future__ import annotations

import numpy as np
import pytest

from shrmkit.analysis.lights import extract_lights
from shrmkit.analysis.shrm import SHRM, prefilter
from shrmkit.brdf_io.env_rotation import check_env_rotation, env_rotation_matrix, to_map_frame
from shrmkit.brdf_io.envmap import EnvironmentMap, load_env
from shrmkit.brdf_io.errors import BadInputError
from shrmkit.brdf_io.latlong import bilinear_lookup, pixel_directions
from shrmkit.brdf_io.specs import load_brdf

MU = np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8])
MU2 = np.array([-0.7, 0.2, -0.1]) / np.linalg.norm([-0.7, 0.2, -0.1])

#: by hand: 90° about +x, +y, +z (counterclockwise looking down the axis)
RX90 = np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]])
RY90 = np.array([[0.0, 0, 1], [0, 1, 0], [-1, 0, 0]])
RZ90 = np.array([[0.0, -1, 0], [1, 0, 0], [0, 0, 1]])


def blobs(Q: np.ndarray, height: int = 64) -> EnvironmentMap:
    """A smooth closed-form map (sky level and two coloured lobes), rotated by Q exactly: L(Qᵀ ω)."""
    d = pixel_directions(height, 2 * height)
    a, b = Q @ MU, Q @ MU2
    radiance = (0.2 + 5.0 * np.exp(8.0 * (d @ a - 1.0))[..., None] * [1.0, 0.8, 0.6]
                + 2.0 * np.exp(20.0 * (d @ b - 1.0))[..., None] * [0.3, 0.5, 1.0])
    return EnvironmentMap(radiance.astype(np.float32), name="blobs")


def random_pairs(n: int = 3000, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """(R, V) on the whole sphere, V not within 60° of −R (the grazing singularity)."""
    rng = np.random.default_rng(seed)
    R = rng.normal(size=(n, 3))
    V = rng.normal(size=(n, 3))
    R /= np.linalg.norm(R, axis=1, keepdims=True)
    V /= np.linalg.norm(V, axis=1, keepdims=True)
    V = np.where((np.sum(R * V, axis=1) < -0.5)[:, None], -V, V)
    return R, V


def rel_rms(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.sqrt(np.mean((a - b) ** 2)) / np.sqrt(np.mean(b**2)))


def test_matrix_conventions() -> None:
    """Q = R_z(AZ) R_y(−EL) R_x(ROLL): hand-written axis rotations, orthonormal, det +1, and the
    horizon point at azimuth 0 lands at (elevation EL, azimuth AZ)."""
    np.testing.assert_allclose(env_rotation_matrix(90.0), RZ90, atol=1e-15)
    np.testing.assert_allclose(env_rotation_matrix(0.0, 0.0, 90.0), RX90, atol=1e-15)
    np.testing.assert_allclose(env_rotation_matrix(0.0, -90.0), RY90, atol=1e-15)  # +z down to +x
    az, el = 35.0, 20.0
    Q = env_rotation_matrix(az, el, -70.0)
    np.testing.assert_allclose(Q.T @ Q, np.eye(3), atol=1e-14)
    assert np.linalg.det(Q) == pytest.approx(1.0)
    a, e = np.radians([az, el])
    np.testing.assert_allclose(Q @ [1.0, 0.0, 0.0], [np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])
    np.testing.assert_allclose(check_env_rotation((az, el, -70.0)), Q)
    np.testing.assert_allclose(check_env_rotation(Q), Q)
    np.testing.assert_allclose(to_map_frame(Q @ MU, Q), MU)


@pytest.mark.parametrize(("value", "message"), [
    (np.diag([1.0, 1.0, -1.0]), "not a rotation"),
    (2.0 * np.eye(3), "not a rotation"),
    (np.eye(4), "got shape (4, 4)"),
    ((10.0,), "got shape (1,)"),
    ((10.0, np.nan), "finite"),
    ("north", "3x3 rotation or angles"),
])
def test_bad_rotations_are_refused(value, message) -> None:
    with pytest.raises(BadInputError, match=message.replace("(", r"\(").replace(")", r"\)")):
        check_env_rotation(value)


def test_azimuth_is_the_sense_of_env_azimuth() -> None:
    """A lit pixel of a map loaded with azimuth = 45° (a roll by a whole number of columns, 16 of
    128) sits where env_rotation_matrix(45) takes the unrotated pixel's direction."""
    env = load_env("builtin:sun,height=64,elevation=20,azimuth=10")
    turned = load_env("builtin:sun,height=64,elevation=20,azimuth=10", azimuth=45.0)
    d = pixel_directions(64, 128)
    i, j = np.unravel_index(np.argmax(env.radiance.sum(-1)), (64, 128))
    k, m = np.unravel_index(np.argmax(turned.radiance.sum(-1)), (64, 128))
    np.testing.assert_allclose(env_rotation_matrix(45.0) @ d[i, j], d[k, m], atol=1e-12)
    # the whole map: lookup of the unrotated map at Qᵀ ω equals the rolled map (same pixel centres)
    looked = bilinear_lookup(env.radiance.astype(np.float64), to_map_frame(d, env_rotation_matrix(45.0)))
    np.testing.assert_allclose(looked, turned.radiance, rtol=1e-5, atol=1e-6 * float(env.radiance.max()))


@pytest.mark.parametrize("spec", ["microfacet:sigma=0.3", "phong:s=30"])
def test_rotation_equals_prefilter_of_the_rotated_map(spec) -> None:
    """SHRM.radiance(env_rotation=Q) = the SHRM prefiltered anew from the rotated map (same orders),
    ≤ 1e-3 relative RMS on the whole sphere of R and V (measured 4e-5 … 7e-4 with 128-row maps: the
    rest is the lat-long sampling of the lighting and the map lookup; 90° about z: 3e-16)."""
    brdf = load_brdf(spec)
    P = 3 if spec.startswith("microfacet") else 0
    base = prefilter(blobs(np.eye(3)), brdf, lights="none", F=20, P=P, size=128)
    R, V = random_pairs()
    for angles in [(32.0, 0.0, 0.0), (0.0, 32.0, 0.0), (0.0, 0.0, 32.0), (70.0, 20.0, 10.0), (90.0, 0.0, 0.0)]:
        Q = env_rotation_matrix(*angles)
        fresh = prefilter(blobs(Q), brdf, lights="none", F=20, P=P, size=128)
        want = fresh.radiance(R, V)
        assert rel_rms(base.radiance(R, V, env_rotation=Q), want) <= 1e-3, angles
        assert rel_rms(base.radiance(R, V, env_rotation=angles), want) <= 1e-3, angles
        # not trivially: the unrotated SHRM is far from it
        if angles != (90.0, 0.0, 0.0):
            assert rel_rms(base.radiance(R, V), want) > 0.05
    # view_map under rotation: the map of the view Qᵀ V, looked up at Qᵀ R
    v = np.array([0.2, -0.6, 0.77]) / np.linalg.norm([0.2, -0.6, 0.77])
    Q = env_rotation_matrix(70.0, 20.0, 10.0)
    looked = bilinear_lookup(base.view_map(v, env_rotation=Q).astype(np.float64), to_map_frame(R, Q))
    np.testing.assert_allclose(looked, base.radiance(R, np.broadcast_to(v, R.shape), env_rotation=Q),
                               rtol=1e-4, atol=1e-5)


@pytest.mark.parametrize(("rotation", "spot", "lands"), [
    (env_rotation_matrix(90.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0)),      # about z: +x to +y
    (env_rotation_matrix(0.0, 90.0), (1.0, 0.0, 0.0), (0.0, 0.0, 1.0)),  # elevation: +x up to +z
    (env_rotation_matrix(0.0, 0.0, 90.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)),  # roll about x: +y to +z
    (RX90, (0.0, 0.0, 1.0), (0.0, -1.0, 0.0)),
    (RY90, (0.0, 0.0, 1.0), (1.0, 0.0, 0.0)),
    (RZ90, (0.0, 1.0, 0.0), (-1.0, 0.0, 0.0)),
])
def test_highlight_lands_where_the_spot_was_turned(rotation, spot, lands) -> None:
    """A one-bright-spot map and a sharp Phong lobe: at normal incidence (V = R) the highlight of the
    rotated scene is at Q μ (within 4°, the spacing of the sample directions), on each axis."""
    mu = np.asarray(spot)
    d = pixel_directions(64, 128)
    env = EnvironmentMap((0.01 + 50.0 * np.exp(200.0 * (d @ mu - 1.0)))[..., None].repeat(3, -1).astype(np.float32),
                         name="spot")
    shrm = prefilter(env, "phong:s=200", lights="none", F=40, P=0, size=96)
    n = 4000  # Fibonacci sphere: ~3.2° apart
    k = np.arange(n) + 0.5
    z = 1.0 - 2.0 * k / n
    phi = np.pi * (1.0 + 5.0 ** 0.5) * k
    R = np.stack([np.sqrt(1 - z * z) * np.cos(phi), np.sqrt(1 - z * z) * np.sin(phi), z], axis=1)
    peak = R[np.argmax(shrm.radiance(R, R, env_rotation=rotation).sum(-1))]
    assert np.degrees(np.arccos(np.clip(peak @ np.asarray(lands), -1, 1))) < 4.0
    unrotated = R[np.argmax(shrm.radiance(R, R).sum(-1))]
    assert np.degrees(np.arccos(np.clip(unrotated @ mu, -1, 1))) < 4.0


def test_lights_rotate_with_their_map() -> None:
    """A map that is only lights (five bright pixels on black): rotated about z by 4 columns
    (22.5°), the lights' reflection equals that of the lights extracted from the rolled map (same
    pixels, exactly); any rotation equals LightSet.rotated(Q) shaded at the world R, V."""
    brdf = load_brdf("microfacet:sigma=0.2")

    def lights_shrm(env: EnvironmentMap) -> SHRM:
        extraction = extract_lights(env, "auto")
        return SHRM(F=0, P=0, coeffs=np.zeros((1, 8, 16, 3), np.float32), lights=extraction.lights, brdf=brdf)

    radiance = np.zeros((32, 64, 3), np.float32)
    for i, j, c in [(8, 5, (50, 40, 30)), (14, 20, (20, 30, 60)), (20, 44, (40, 40, 40)), (5, 33, (10, 60, 10))]:
        radiance[i, j] = c
    dots = EnvironmentMap(radiance, name="dots")
    R, V = random_pairs(2000, seed=3)
    base = lights_shrm(dots)
    rolled = lights_shrm(dots.rotated_z(np.radians(22.5)))
    want = rolled.radiance(R, V)
    assert want.max() > 0
    np.testing.assert_allclose(base.radiance(R, V, env_rotation=(22.5, 0.0)), want, rtol=1e-9,
                               atol=1e-12 * want.max())
    assert rel_rms(base.radiance(R, V), want) > 0.1
    Q = env_rotation_matrix(-40.0, 55.0, 12.0)
    moved = base.lights.rotated(Q)
    np.testing.assert_allclose(base.light_radiance(R, V, env_rotation=Q), moved.radiance(brdf, R, V),
                               rtol=1e-9, atol=1e-12 * want.max())
