"""Exception types of shrmkit.

Every reader and parser raises :class:`BadInputError` (a ``ValueError``) for input a
user can fix, with a message that names the file or spec and the problem. The CLI turns
it into one line on stderr and exit code 2.
"""

from __future__ import annotations

__all__ = ["ShrmError", "BadInputError", "ScatteredEvalError"]


class ShrmError(Exception):
    """Base class of every error shrmkit raises on purpose."""


class BadInputError(ShrmError, ValueError):
    """Input a user can fix: unreadable, truncated, wrong-size or non-finite data,
    unknown spec names, nonsense parameters.

    Parameters
    ----------
    source
        The file path or spec string the problem is in (``None`` when there is none).
    problem
        What is wrong, with the offending value echoed.
    """

    def __init__(self, source: object, problem: str) -> None:
        self.source = None if source is None else str(source)
        self.problem = problem
        super().__init__(f"{self.source}: {problem}" if self.source else problem)


class ScatteredEvalError(ShrmError, TypeError):
    """Raised when a scattered (non-tabulated) measurement is evaluated everywhere."""
