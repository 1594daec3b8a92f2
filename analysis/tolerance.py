"""The tolerance ε on uncaptured energy ([RH02] §5.1): its one default and its one validator.

Every API that takes ε takes it keyword-only as ``eps=`` with default :data:`DEFAULT_EPS`
and checks it with :func:`check_eps`; the CLI's ``--eps`` uses the same pair.

Reference: [RH02] (``data_specs/bibliography.md``).
"""

from __future__ import annotations

import math

from ..brdf_io.errors import BadInputError

__all__ = ["DEFAULT_EPS", "check_eps"]

#: Default tolerance on the uncaptured energy fraction ε (RH02 uses 0.03 in §7).
DEFAULT_EPS = 0.03


def check_eps(eps: float, name: str = "eps") -> float:
    """Return ``eps`` as a float after checking that it lies in the open interval (0, 1).

    Raises
    ------
    BadInputError
        When ``eps`` is not a finite number in (0, 1); the message names ``name`` and the value.
    """
    try:
        value = float(eps)
    except (TypeError, ValueError):
        raise BadInputError(None, f"{name} must be a number in (0, 1), got {eps!r}") from None
    if not (math.isfinite(value) and 0.0 < value < 1.0):
        raise BadInputError(None, f"{name} must be in (0, 1), got {eps!r}")
    return value
