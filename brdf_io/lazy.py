"""A package's public names imported on first use (PEP 562 module ``__getattr__``).

Each layer's ``__init__`` lists its public names in a ``_LAZY`` table (name → defining module) and
takes its ``__getattr__`` and ``__dir__`` from :func:`lazy_exports`, so ``import shrmkit.render``
does not load VTK, and ``tests/test_public_api.py`` reads the table to check the declarations.
"""

from __future__ import annotations

import importlib
import sys
from collections.abc import Callable, Mapping, Sequence
from typing import Any

__all__ = ["lazy_exports", "submodule"]


def submodule(package: str, name: str) -> Any:
    """The sub-package or module ``package.name``, imported on first read of the attribute (as after
    ``import package.name``: ``shrmkit.render.RENDER_MODES`` works after a bare ``import shrmkit``).

    Raises
    ------
    AttributeError
        ``name`` is private (``_…``) or no such module exists.
    """
    if not name.startswith("_"):
        try:
            return importlib.import_module(f"{package}.{name}")
        except ModuleNotFoundError as missing:
            if missing.name != f"{package}.{name}":
                raise  # the module exists and failed to import one of its own dependencies
    raise AttributeError(f"module {package!r} has no attribute {name!r}")


def lazy_exports(package: str, table: Mapping[str, str], names: Sequence[str]
                 ) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """``(__getattr__, __dir__)`` for the package ``package``: a name of ``table`` is imported from
    its module when first read, then bound on the package (later reads skip the hook); ``dir()``
    lists ``names`` (the package's ``__all__``).

    Raises
    ------
    AttributeError
        (from ``__getattr__``) a name the table does not hold that is no module of the package either.
    """

    def __getattr__(name: str) -> Any:
        if name in table:
            value = getattr(importlib.import_module(table[name]), name)
            setattr(sys.modules[package], name, value)
            return value
        return submodule(package, name)

    def __dir__() -> list[str]:
        return sorted(names)

    return __getattr__, __dir__
