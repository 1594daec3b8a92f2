"""Docstrings cite with a short key into one bibliography page (issue 27, point 7).

``data_specs/bibliography.md`` lists every paper, dataset and specification under one key; a
docstring writes ``[RH02] §5.1`` instead of pasting the reference. Checked here: every key with
a year that the library's text cites ([RH02], [Green07], …) is in that page, and no module
docstring of the library pastes RH02's full reference (its DOI) any more, every key a module
docstring cites (with a year or not: [PBRT4], [KTX2]) is in that page, and no module docstring is
longer than :data:`MAX_MODULE_DOC_LINES` lines (a few lines of what the module does; the details
live in the functions' docstrings and in data_specs/).
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
#: A bracketed key in a module docstring: not a subscript (``Sequence[Representation]``, ``a[i]``).
_DOC_CITED = re.compile(r"(?<![\w.\]\)])\[([A-Za-z][A-Za-z0-9-]*)\](?![(_])")
RH02_DOI = "566654.566611"

#: A module docstring says what the module does in a few lines (issue 27 point 7); the details live
#: in the functions' docstrings and in data_specs/.
MAX_MODULE_DOC_LINES = 30


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
    # in module docstrings every key is checked, with a year or not ([PBRT4], [KTX2], [Mitsuba3]);
    # a subscript such as Sequence[Representation] is not a citation
    keys = _keys()
    unknown = sorted({(path, k) for path, doc in docs.items() for k in _DOC_CITED.findall(doc) if k not in keys})
    assert not unknown, f"citation keys missing from data_specs/bibliography.md: {unknown}"
    pasted = sorted(path for path, doc in docs.items() if RH02_DOI in doc)
    assert not pasted, f"RH02's reference pasted (cite [RH02] instead): {pasted}"


def test_module_docstrings_are_short():
    docs = {path: _module_docstring(text) for path, text in _sources().items()}
    lines = {path: len(doc.splitlines()) for path, doc in docs.items()}
    assert lines["brdf_io/reparam.py"] > 5  # the docstrings are read whole
    long = {path: n for path, n in sorted(lines.items()) if n > MAX_MODULE_DOC_LINES}
    assert not long, (f"module docstrings over {MAX_MODULE_DOC_LINES} lines (say what the module does in a few "
                      f"lines; details go to the functions' docstrings or data_specs/): {long}")
