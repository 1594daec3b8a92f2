"""Connected components in numpy against SciPy's (csgraph.connected_components, ndimage.label)."""

import numpy as np
import pytest
from scipy import ndimage
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from shrmkit.analysis import components
from shrmkit.analysis.components import connected_labels, grid_labels


def test_graph_labels_are_scipys() -> None:
    """Random graphs (isolated vertices, repeated edges, self loops), a shuffled 2000-vertex path
    (many rounds of jumping) and a graph without edges."""
    rng = np.random.default_rng(3)
    cases = [(rng.integers(0, 50, 30), rng.integers(0, 50, 30), 60) for _ in range(20)]
    perm = rng.permutation(2000)
    cases.append((perm[:-1], perm[1:], 2000))
    cases.append((np.array([], dtype=int), np.array([], dtype=int), 5))
    for a, b, n in cases:
        _, want = connected_components(coo_matrix((np.ones(a.size), (a, b)), shape=(n, n)), directed=False)
        np.testing.assert_array_equal(connected_labels(a, b, n), want)


@pytest.mark.parametrize("numpy_max", [10**9, 100])
@pytest.mark.parametrize("density", [0.0, 0.05, 0.3, 0.55, 1.0])
def test_grid_labels_are_ndimage_labels(density: float, numpy_max: int, monkeypatch) -> None:
    """8-neighbour regions of random masks (and a spiral, one long region) number as ndimage does,
    labelled in numpy (every mask under the size limit) or handed to ndimage (over it)."""
    monkeypatch.setattr(components, "NUMPY_GRID_MAX_PIXELS", numpy_max)
    rng = np.random.default_rng(int(density * 100))
    masks = [rng.random((37, 64)) < density for _ in range(3)]
    spiral = np.zeros((21, 21), dtype=bool)
    spiral[1::4, 1:-1] = True
    spiral[1:-1, 1] = True
    spiral[3::4, -2] = True
    masks.append(spiral)
    for mask in masks:
        want, n_want = ndimage.label(mask, structure=np.ones((3, 3), dtype=bool))
        got, n = grid_labels(mask)
        assert n == n_want
        np.testing.assert_array_equal(got, want)
