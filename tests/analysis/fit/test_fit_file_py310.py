"""``analysis/fit/fit_file.py`` loads on Python 3.10 (pyproject: ``requires-python >= 3.10``), where
``datetime`` has no ``UTC`` (added in 3.11; found by mypy checking as 3.10): the module is executed
beside a ``datetime`` module without that name, and the UTC it stamps is ``timezone.utc``."""

from __future__ import annotations

import datetime
import importlib.util
import sys
import types
from pathlib import Path

import shrmkit.analysis.fit.fit_file as fit_file


def test_fit_file_loads_without_datetime_utc(monkeypatch) -> None:
    py310 = types.ModuleType("datetime")
    py310.__dict__.update({k: v for k, v in vars(datetime).items() if k != "UTC"})
    monkeypatch.setitem(sys.modules, "datetime", py310)
    spec = importlib.util.spec_from_file_location("shrmkit.analysis.fit._fit_file_py310", Path(fit_file.__file__))
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)  # Python 3.10 / the code before: ImportError (cannot import name 'UTC')
    assert module.fit_document.__module__ == "shrmkit.analysis.fit._fit_file_py310"
    stamp = module.datetime.now(module.timezone.utc)
    assert stamp.utcoffset() == datetime.timedelta(0)
