"""K-fold cross-validation over measured geometries: the held-out error of a fit.

A fit's error on the samples it was fitted to (the training error) flatters any model with
many parameters: a 55-term Zernike expansion on CURET's 205 geometries can follow the
measurement noise. The error a representation is judged by here is the **held-out** error:
the samples are split into ``folds`` groups (a seeded random permutation, so the split is
deterministic), each group is predicted by a fit to the other groups, and the pooled
predictions — every sample predicted exactly once, by a fit that never saw it — are scored
with the metrics of ``metrics.py`` and per view band (``summary.band_errors``).

Public objects: :func:`fold_of`, :func:`subset`, :func:`held_out`, :data:`DEFAULT_FOLDS`.

Reference: [Hastie09] §7.10 (K-fold cross-validation; K = 5 or 10).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ...brdf_io.errors import BadInputError
from ..defaults import DEFAULT_FOLDS  # numpy-free home, for the CLI's parsers
from .sampling import FitSamples

__all__ = ["DEFAULT_FOLDS", "fold_of", "subset", "held_out"]


def fold_of(n: int, folds: int = DEFAULT_FOLDS, *, seed: int = 0) -> np.ndarray:
    """The fold (0..folds−1) of each of ``n`` samples: a seeded permutation dealt round-robin,
    so the folds differ in size by at most one.

    Raises
    ------
    BadInputError
        ``folds`` < 2 or more folds than samples.
    """
    if not (isinstance(folds, int | np.integer) and 2 <= folds <= n):
        raise BadInputError(None, f"cross-validation needs 2 <= folds <= samples ({n}), got {folds!r}")
    order = np.random.default_rng(seed).permutation(n)
    out = np.empty(n, dtype=np.int64)
    out[order] = np.arange(n) % folds
    return out


def subset(samples: FitSamples, index: np.ndarray) -> FitSamples:
    """The samples at ``index`` (integer or boolean), with the same source and no dropped count."""
    return FitSamples(L=samples.L[index], V=samples.V[index], rho=samples.rho[index],
                      weight=samples.weight[index], n_dropped=0, source=samples.source)


def held_out(
    samples: FitSamples,
    predict: Callable[[FitSamples, FitSamples], np.ndarray],
    folds: int = DEFAULT_FOLDS,
    *,
    seed: int = 0,
) -> np.ndarray:
    """Every sample's ρ predicted by a fit that did not see it.

    Parameters
    ----------
    samples
        All samples (n).
    predict
        ``predict(train, test)`` fits to ``train`` and returns ρ (len(test), 3) at ``test``'s
        directions.
    folds, seed
        :func:`fold_of`.

    Returns
    -------
    numpy.ndarray
        (n, 3) held-out predictions of ρ in 1/sr, in the samples' order.
    """
    fold = fold_of(len(samples), folds, seed=seed)
    out = np.empty_like(samples.rho)
    for k in range(folds):
        test = fold == k
        out[test] = predict(subset(samples, ~test), subset(samples, test))
    return out
