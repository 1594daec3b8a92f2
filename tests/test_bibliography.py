"""Docstrings cite with a short key into one bibliography page (issue 27, point 7).

``data_specs/bibliography.md`` lists every paper, dataset and specification under one key; a
docstring writes ``[RH02] §5.1`` instead of pasting the reference. Checked here: every key with
a year that the library's text cites ([RH02], [Green07], …) is in that page, and no module
docstring of the library pastes RH02's full reference (its DOI) any more — except the modules
listed below, whose docstrings other work is rewriting (the list may only shrink).
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("brdf_io", "analysis", "render", "cli")

#: A citation key as the bibliography spells them: an author or name and a two-digit year
#: ([RH02], [Cabral99], [BornWolf99]), or one of the page's keys without a year ([sRGB], [PNG]).
_CITED = re.compile(r"\[([A-Za-z][A-Za-z0-9-]*)\](?![(_])")
_YEAR_KEY = re.compile(r"[A-Z][A-Za-z]*[0-9]{2}")
RH02_DOI = "566654.566611"

#: Module docstrings that still paste RH02's reference (being rewritten elsewhere; shrink only).
STILL_PASTED = {
    "analysis/orders.py", "analysis/shrm.py", "analysis/synthesis.py", "analysis/view_bands.py",
    "brdf_io/reparam.py", "cli/cmd_bench.py", "cli/cmd_census.py", "cli/cmd_export.py", "cli/cmd_fit.py",
    "cli/cmd_orders.py", "cli/cmd_prefilter.py", "cli/main.py", "cli/report/collect.py", "cli/report/demo.py",
    "cli/report/plots.py",
}


def _keys() -> set[str]:
    text = (ROOT / "data_specs" / "bibliography.md").read_text(encoding="utf-8")
    return set(re.findall(r"^\| \[([^\]]+)\] \|", text, re.M))


def _sources() -> dict[str, str]:
    """{module path relative to the repository: its text} of the library."""
    return {path.relative_to(ROOT).as_posix(): path.read_text(encoding="utf-8")
            for package in PACKAGES for path in sorted((ROOT / package).rglob("*.py"))}


def _module_docstring(text: str) -> str:
    """The module docstring: the first statement, read by ``ast`` from the file's head only (a
    whole-library parse costs seconds)."""
    head = re.match(r"(?:\s*#[^\n]*\n|\s)*[rRuU]?(\"\"\"|\'\'\')", text)
    if head is None:
        return ""
    end = text.find(head.group(1), head.end())
    return ast.get_docstring(ast.parse(text[:end + 3])) or ""


def test_every_cited_key_is_in_the_bibliography():
    keys = _keys()
    assert {"RH02", "KM00", "Cabral99", "Green07", "MERL03", "Rus98"} <= keys
    # anywhere in the text (docstrings, #: comments, messages), keys spelled with a year
    unknown = sorted({(path, k) for path, text in _sources().items() for k in _CITED.findall(text)
                      if _YEAR_KEY.fullmatch(k) and k not in keys})
    assert not unknown, f"citation keys missing from data_specs/bibliography.md: {unknown}"


def test_module_docstrings_cite_rh02_by_key_not_by_pasted_reference():
    docs = {path: _module_docstring(text) for path, text in _sources().items()}
    assert docs["render/brdf_glsl.py"].startswith("The BRDF in GLSL")  # the docstrings are read
    pasted = {path for path, doc in docs.items() if RH02_DOI in doc}
    assert pasted <= STILL_PASTED, f"RH02's reference pasted (cite [RH02] instead): {sorted(pasted - STILL_PASTED)}"
