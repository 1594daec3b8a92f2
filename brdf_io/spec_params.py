"""The ``key=value`` parameters of spec strings: one parser and one typed, range-checked
accessor, shared by BRDF specs (``phong:s=32,ks=0.5/0.6/0.7``, :mod:`~shrmkit.brdf_io.specs`)
and built-in environments (``builtin:sky,height=64``, :mod:`~shrmkit.brdf_io.builtin_env`).

Grammar (data_specs/spec_strings.md, data_specs/environment_maps.md §5)::

    params := param ("," param)*
    param  := key "=" value            (spaces around key and value are ignored)
    value  := number | number "/" number "/" number (r/g/b) | word

Every problem raises :class:`~shrmkit.brdf_io.errors.BadInputError` whose source is the
whole spec string and whose message names the key and echoes the value.

Public objects: :func:`parse_params`, :class:`SpecParams`.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Sequence

import numpy as np

from .errors import BadInputError

__all__ = ["parse_params", "parse_number", "NonFiniteNumberError", "SpecParams", "MAX_NUMBER_CHARS"]

#: Longest number a spec value may spell, characters (``0.123456789012345678e-300`` is 25).
MAX_NUMBER_CHARS = 64
_NUMBER = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?")
_NON_FINITE = re.compile(r"[+-]?(?:nan|inf|infinity)", re.IGNORECASE)


def _shown(text: str, limit: int = MAX_NUMBER_CHARS) -> str:
    """``repr`` of a value for a message, cut to ``limit`` characters."""
    return repr(text) if len(text) <= limit else repr(text[:limit]) + f"... ({len(text)} characters)"


class NonFiniteNumberError(ValueError):
    """A number spelled ``nan``/``inf`` (``overflow`` False) or overflowing a float
    (``1e999``, ``overflow`` True)."""

    def __init__(self, message: str, overflow: bool) -> None:
        super().__init__(message)
        self.overflow = overflow


def parse_number(text: str, *, strip: bool = True) -> float:
    """One finite decimal number (``8``, ``-0.5``, ``2.5e-3``; spaces around it ignored
    unless ``strip`` is False). The one definition of a number in every text format we
    read (spec strings, Cornell, CURET and gonioreflectometer files).

    Raises
    ------
    NonFiniteNumberError
        ``nan``/``inf``, or a number that overflows a float (``1e999``).
    ValueError
        Otherwise with the reason: not a decimal number (including Python-only spellings
        such as ``1_000``), or a spelling longer than :data:`MAX_NUMBER_CHARS` characters.
    """
    token = text.strip() if strip else text
    if len(token) > MAX_NUMBER_CHARS:
        raise ValueError(f"is not a number of at most {MAX_NUMBER_CHARS} characters")
    if _NON_FINITE.fullmatch(token):
        raise NonFiniteNumberError("is not finite", overflow=False)
    if not _NUMBER.fullmatch(token):
        raise ValueError("is not a number")
    value = float(token)
    if not math.isfinite(value):
        raise NonFiniteNumberError("is not finite (overflows a float)", overflow=True)
    return value


def parse_params(
    spec: str, items: Iterable[str], allowed: Sequence[str] | None = None, owner: str = ""
) -> dict[str, str]:
    """Raw ``{key: value}`` strings of the ``key=value`` items of ``spec``.

    Parameters
    ----------
    spec
        The whole spec string (named in every error).
    items
        The ``key=value`` pieces (the spec body split at commas).
    allowed
        If given, the only keys accepted; an unknown key is refused with this list.
    owner
        What the parameters belong to (``"builtin:sky"``), for the unknown-key message.

    Raises
    ------
    BadInputError
        A piece without ``=``, an empty key or value, a key given twice, an unknown key.
    """
    raw: dict[str, str] = {}
    for item in items:
        key, sep, value = (s.strip() for s in item.partition("="))
        if not sep or not key or not value:
            raise BadInputError(spec, f"parameter {item.strip()!r} is not of the form key=value")
        if allowed is not None and key not in allowed:
            where = f" for {owner}" if owner else ""
            raise BadInputError(spec, f"unknown parameter {key!r}{where}; valid: {', '.join(allowed)}")
        if key in raw:
            raise BadInputError(spec, f"parameter {key!r} given twice")
        raw[key] = value
    return raw


class SpecParams:
    """Typed access to the raw parameters of one spec, with the range checks in one place.

    Every accessor records the key it was asked for; :meth:`finish` then refuses the keys
    nobody asked for, listing the ones that were.

    Parameters
    ----------
    spec
        The whole spec string (named in every error).
    raw
        ``{key: value}`` strings, as from :func:`parse_params`.
    owner
        What the parameters belong to (``"phong"``), for the unknown-key message.
    """

    def __init__(self, spec: str, raw: dict[str, str], owner: str = "") -> None:
        self.spec = spec
        self.raw = dict(raw)
        self.owner = owner
        self.asked: list[str] = []

    def _ask(self, key: str) -> bool:
        if key not in self.asked:
            self.asked.append(key)
        return key in self.raw

    def has(self, key: str) -> bool:
        """Whether ``key`` was given."""
        return self._ask(key)

    def numbers(self, key: str) -> list[float]:
        """The one or three (r/g/b) finite numbers given for ``key``."""
        self._ask(key)
        text = self.raw[key]
        parts = text.split("/")
        if len(parts) not in (1, 3):
            raise BadInputError(self.spec, f"parameter {key}={_shown(text)}: give one value or r/g/b")
        values = []
        for part in parts:
            try:
                values.append(parse_number(part))
            except ValueError as err:
                raise BadInputError(self.spec, f"parameter {key}={_shown(text)} {err}") from None
        return values

    def _check_range(self, key: str, values: list[float], lo: float, hi: float, lo_open: bool) -> None:
        for v in values:
            if v < lo or v > hi or (lo_open and v == lo):
                bracket = "(" if lo_open else "["
                raise BadInputError(
                    self.spec, f"parameter {key}={self.raw[key][:MAX_NUMBER_CHARS]} outside {bracket}{lo:g}, {hi:g}]"
                )

    def color(
        self,
        key: str,
        default: float | tuple[float, float, float] | None,
        lo: float = -np.inf,
        hi: float = np.inf,
        lo_open: bool = False,
    ) -> np.ndarray:
        """A scalar or r/g/b value as a float64 array of shape (3,), each in [lo, hi]
        (or (lo, hi] with ``lo_open``); ``default`` when absent, required if it is None."""
        if not self._ask(key):
            if default is None:
                raise BadInputError(self.spec, f"missing parameter {key!r}")
            return np.broadcast_to(np.asarray(default, dtype=np.float64), (3,)).copy()
        values = self.numbers(key)
        self._check_range(key, values, lo, hi, lo_open)
        return np.broadcast_to(np.asarray(values, dtype=np.float64), (3,)).copy()

    def scalar(
        self, key: str, default: float | None, lo: float = -np.inf, hi: float = np.inf, lo_open: bool = False
    ) -> float:
        """One number in [lo, hi] (or (lo, hi]); ``default`` when absent, required if it is None."""
        if self._ask(key) and "/" in self.raw[key]:
            raise BadInputError(self.spec, f"parameter {key} takes one value, not r/g/b")
        return float(self.color(key, default, lo, hi, lo_open)[0])

    def integer(self, key: str, default: int | None, lo: float = -np.inf, hi: float = np.inf) -> int:
        """A whole number in [lo, hi]; ``default`` when absent, required if it is None."""
        value = self.scalar(key, default, lo, hi)
        if value != int(value):
            raise BadInputError(self.spec, f"parameter {key}={self.raw[key]} is not an integer")
        return int(value)

    def choice(self, key: str, default: str | None, options: Sequence[str], fold_case: bool = False) -> str:
        """One of ``options`` (compared in lower case with ``fold_case``); ``default`` when
        absent, required if it is None."""
        if not self._ask(key):
            if default is None:
                raise BadInputError(self.spec, f"missing parameter {key!r}")
            return default
        value = self.raw[key].lower() if fold_case else self.raw[key]
        if value not in options:
            raise BadInputError(
                self.spec, f"parameter {key}={_shown(self.raw[key])}: choose one of {', '.join(options)}"
            )
        return value

    def finish(self) -> None:
        """Refuse the given keys that no accessor asked for, listing those it asked for."""
        unknown = [k for k in self.raw if k not in self.asked]
        if unknown:
            where = f" for {self.owner}" if self.owner else ""
            raise BadInputError(
                self.spec, f"unknown parameter(s) {', '.join(unknown)}{where}; valid: {', '.join(self.asked)}"
            )
