"""The one cube-face table (brdf_io/cubemap.py) in both of its frames, against hand-written directions."""

from __future__ import annotations

import numpy as np
import pytest

from shrmkit.analysis.shrm import cube_directions
from shrmkit.brdf_io.cubemap import (
    CUBE_FACES,
    CUBE_TO_PROJECT,
    cube_map_directions,
    cube_texel_directions,
    cube_texel_index,
    cube_texel_solid_angles,
)

# face centres (major axes) in the cube frame, faces px, nx, py, ny, pz, nz
CENTRES = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], dtype=float)
# OpenGL Table 8.19 by hand: the cube corner at (s, t) = (0, 0), the top-left corner of
# each face (px: sc = −rz = −1, tc = −ry = −1, so (1, 1, 1); ...)
TOP_LEFT = np.array([[1, 1, 1], [-1, 1, -1], [-1, 1, -1], [-1, -1, 1], [-1, 1, 1], [1, 1, -1]], dtype=float)
# data_specs/environment_maps.md §4: project direction of each cube-file face centre
PROJECT_CENTRES = np.array([[0, -1, 0], [0, 1, 0], [0, 0, 1], [0, 0, -1], [1, 0, 0], [-1, 0, 0]], dtype=float)


def test_face_centres_and_corners_by_hand():
    """An odd face has a texel exactly at its centre; the top-left texel of an N-texel face
    lies (1 − 1/N) of the way from the face centre to the face's top-left cube corner."""
    dirs = cube_map_directions(5)
    assert dirs.shape == (6, 5, 5, 3)
    np.testing.assert_array_equal(dirs[:, 2, 2], CENTRES)
    corner = CENTRES + (1 - 1 / 5) * (TOP_LEFT - CENTRES)
    np.testing.assert_allclose(dirs[:, 0, 0], corner / np.linalg.norm(corner, axis=-1, keepdims=True), atol=1e-15)
    np.testing.assert_allclose(np.linalg.norm(dirs, axis=-1), 1.0, atol=1e-15)
    for f, face in enumerate(CUBE_FACES):
        np.testing.assert_array_equal(cube_texel_directions(5, face), dirs[f])


@pytest.mark.parametrize("size", [1, 2, 5, 12])
def test_shrm_cube_directions_are_the_table_in_the_z_up_frame(size):
    """analysis.shrm.cube_directions (SHRM cube maps) = the table read with the identity cube frame."""
    got = cube_directions(size)
    np.testing.assert_array_equal(got, cube_map_directions(size))
    if size % 2:
        np.testing.assert_array_equal(got[:, size // 2, size // 2], CENTRES)  # +x, −x, +y, −y, +z, −z


def test_cube_file_frame_to_project():
    """Cube-map files: X = z_c, Y = −x_c, Z = y_c (a reflection that keeps the faces unmirrored)."""
    np.testing.assert_array_equal(CENTRES @ CUBE_TO_PROJECT.T, PROJECT_CENTRES)
    assert np.linalg.det(CUBE_TO_PROJECT) == pytest.approx(-1.0)
    # face pz, seen from inside along project +X with Z up: its columns run towards −Y (the right)
    pz = cube_texel_directions(4, "pz") @ CUBE_TO_PROJECT.T
    assert np.all(np.diff(pz[..., 1], axis=1) < 0) and np.all(np.diff(pz[..., 2], axis=0) < 0)


def test_texel_index_inverts_texel_directions():
    n = 7
    dirs = cube_map_directions(n)
    index = cube_texel_index(dirs[..., 0], dirs[..., 1], dirs[..., 2], n)
    np.testing.assert_array_equal(index, np.arange(6 * n * n).reshape(6, n, n))


def test_texel_solid_angles_sum_to_4pi():
    assert 6 * cube_texel_solid_angles(9).sum() == pytest.approx(4 * np.pi, rel=1e-14)
    assert cube_texel_solid_angles(1)[0, 0] == pytest.approx(4 * np.pi / 6, rel=1e-14)
