"""Rusinkiewicz half/difference coordinates (brdf_io/halfdiff.py)."""

from __future__ import annotations

import numpy as np
import pytest

from shrmkit.brdf_io.halfdiff import directions_to_halfdiff, halfdiff_to_directions, spherical_angles


def _random_hemisphere(rng: np.random.Generator, n: int) -> np.ndarray:
    v = rng.normal(size=(n, 3))
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    v[:, 2] = np.abs(v[:, 2])
    return v


def _rot_z(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _rot_y(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def test_round_trip_directions() -> None:
    """directions -> (θ_h, θ_d, φ_d, φ_h) -> directions reproduces random pairs."""
    rng = np.random.default_rng(1)
    L, V = _random_hemisphere(rng, 5000), _random_hemisphere(rng, 5000)
    th, td, pd, ph = directions_to_halfdiff(L, V, return_phi_h=True)
    L2, V2 = halfdiff_to_directions(th, td, pd, ph)
    np.testing.assert_allclose(L2, L, atol=1e-12)
    np.testing.assert_allclose(V2, V, atol=1e-12)


def test_round_trip_angles() -> None:
    """(θ_h, θ_d, φ_d) -> directions -> angles is the identity on the open domain."""
    rng = np.random.default_rng(2)
    th = rng.uniform(0.01, np.pi / 2, 4000)
    td = rng.uniform(0.01, np.pi / 2 - 0.01, 4000)
    pd = rng.uniform(-np.pi + 0.01, np.pi, 4000)
    ph = rng.uniform(-np.pi + 0.01, np.pi, 4000)
    out = directions_to_halfdiff(*halfdiff_to_directions(th, td, pd, ph), return_phi_h=True)
    for got, want in zip(out, (th, td, pd, ph), strict=True):
        np.testing.assert_allclose(got, want, atol=1e-11)


def test_reciprocity_half_turn() -> None:
    """Swapping L and V keeps θ_h, θ_d and maps φ_d to φ_d + π (mod 2π)."""
    rng = np.random.default_rng(3)
    L, V = _random_hemisphere(rng, 3000), _random_hemisphere(rng, 3000)
    th, td, pd = directions_to_halfdiff(L, V)
    th2, td2, pd2 = directions_to_halfdiff(V, L)
    np.testing.assert_allclose(th2, th, atol=1e-12)
    np.testing.assert_allclose(td2, td, atol=1e-12)
    diff = np.mod(pd2 - pd - np.pi + np.pi, 2 * np.pi) - np.pi  # wrapped (φ_d' − φ_d − π)
    np.testing.assert_allclose(diff, 0.0, atol=1e-10)


def test_against_explicit_rotation_matrices() -> None:
    """Independent construction (Rusinkiewicz 1998 §3): D = Ry(−θ_h) Rz(−φ_h) L with
    explicit 3×3 matrices, H from normalize(L + V) and angles by arccos, one pair at a time."""
    rng = np.random.default_rng(4)
    L, V = _random_hemisphere(rng, 200), _random_hemisphere(rng, 200)
    th, td, pd = directions_to_halfdiff(L, V)
    for n in range(200):
        H = (L[n] + V[n]) / np.linalg.norm(L[n] + V[n])
        theta_h = np.arccos(H[2])
        phi_h = np.arctan2(H[1], H[0])
        D = _rot_y(-theta_h) @ _rot_z(-phi_h) @ L[n]
        assert th[n] == pytest.approx(theta_h, abs=1e-7)
        assert td[n] == pytest.approx(np.arccos(D[2]), abs=1e-7)
        assert pd[n] == pytest.approx(np.arctan2(D[1], D[0]), abs=1e-9)
        # the half vector is the pole of the rotated frame
        np.testing.assert_allclose(_rot_y(-theta_h) @ _rot_z(-phi_h) @ H, [0, 0, 1], atol=1e-12)


def test_known_configurations() -> None:
    """Closed forms: mirror pair at θ (θ_h = 0, θ_d = θ); L = V (θ_d = 0, θ_h = θ)."""
    theta = 0.7
    L = np.array([np.sin(theta), 0.0, np.cos(theta)])
    mirror = np.array([-np.sin(theta), 0.0, np.cos(theta)])
    th, td, pd = directions_to_halfdiff(L, mirror)
    assert th == pytest.approx(0.0, abs=1e-12)
    assert td == pytest.approx(theta, abs=1e-12)
    assert pd == pytest.approx(0.0, abs=1e-12)
    th, td, _ = directions_to_halfdiff(L, L)
    assert th == pytest.approx(theta, abs=1e-12)
    assert td == pytest.approx(0.0, abs=1e-7)
    # θ_h = 0, φ_d = 0: L = (sin θ_d, 0, cos θ_d) and V its mirror image
    L2, V2 = halfdiff_to_directions(0.0, 0.3, 0.0)
    np.testing.assert_allclose(L2, [np.sin(0.3), 0.0, np.cos(0.3)], atol=1e-15)
    np.testing.assert_allclose(V2, [-np.sin(0.3), 0.0, np.cos(0.3)], atol=1e-15)


def test_spherical_angles_convention() -> None:
    """DESIGN §2: ω = (sin θ cos φ, sin θ sin φ, cos θ)."""
    theta, phi = spherical_angles(np.array([np.sin(0.4) * np.cos(-2.0), np.sin(0.4) * np.sin(-2.0), np.cos(0.4)]))
    assert theta == pytest.approx(0.4)
    assert phi == pytest.approx(-2.0)


def test_broadcasting_shapes() -> None:
    L = np.array([0.0, 0.0, 1.0])
    V = _random_hemisphere(np.random.default_rng(5), 12).reshape(3, 4, 3)
    th, td, pd = directions_to_halfdiff(L, V)
    assert th.shape == td.shape == pd.shape == (3, 4)
    L2, V2 = halfdiff_to_directions(th, td, pd, 0.0)
    assert L2.shape == V2.shape == (3, 4, 3)


def test_broadcast_angles_give_the_pointwise_directions() -> None:
    """Angles of different shapes (the sines and cosines are taken on each angle's own shape)
    give, bit for bit, the directions of each element's angles passed alone."""
    rng = np.random.default_rng(4)
    th, td = rng.uniform(0, 1.5, (4, 1, 1)), rng.uniform(0, 1.5, (1, 3, 1))
    pd, ph = rng.uniform(-3, 3, (1, 1, 5)), rng.uniform(-3, 3, (4, 3, 5))
    L, V = halfdiff_to_directions(th, td, pd, ph)
    assert L.shape == V.shape == (4, 3, 5, 3)
    for i, j, k in np.ndindex(4, 3, 5):
        l1, v1 = halfdiff_to_directions(th[i, 0, 0], td[0, j, 0], pd[0, 0, k], ph[i, j, k])
        assert l1.shape == (3,) and np.array_equal(L[i, j, k], l1) and np.array_equal(V[i, j, k], v1)
    L0, _ = halfdiff_to_directions(0.3, td, pd)  # φ_h defaults to 0: a scalar
    assert L0.shape == (1, 3, 5, 3)
