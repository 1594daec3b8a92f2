"""Every dotted ``shrmkit.…`` name the README and the docs' pages show resolves after a bare
``import shrmkit`` (a user copies them; a name that moved or is not exported is a doc error)."""

import importlib
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
NAME = re.compile(r"`(shrmkit(?:\.[A-Za-z_][A-Za-z0-9_]*)+)")


def _names() -> list[tuple[str, str]]:
    found = []
    for page in PAGES:
        for name in dict.fromkeys(NAME.findall(page.read_text(encoding="utf-8"))):
            found.append((page.name, name))
    return found


@pytest.mark.parametrize(("page", "name"), _names())
def test_documented_name_resolves(page: str, name: str) -> None:
    obj = importlib.import_module("shrmkit")
    for part in name.split(".")[1:]:
        obj = getattr(obj, part)  # AttributeError: the page names something the package does not have
