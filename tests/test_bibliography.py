"""Docstrings cite with a short key into one bibliography page (issue 27, point 7).

``data_specs/bibliography.md`` lists every paper, dataset and specification under one key; a
docstring writes ``[RH02] §5.1`` instead of pasting the reference. Checked here: every key with
a year that the library's text cites ([RH02], [Green07], …) is in that page, and no module
docstring of the library pastes RH02's full reference (its DOI) any more, and no module docstring
is longer than :data:`MAX_MODULE_DOC_LINES` lines.
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

#: A module docstring says what the module does in a few lines (issue 27 point 7); the details live
#: in the functions' docstrings and in data_specs/.
MAX_MODULE_DOC_LINES = 30
#: Module docstrings still longer (being cut; the list may only shrink).
STILL_LONG = {
    "analysis/__init__.py", "analysis/baselines/gaussian_lobes.py", "analysis/baselines/lobe_truncated.py",
    "analysis/baselines/split_sum.py", "analysis/error_image.py", "analysis/pixels.py", "analysis/view_bands.py",
    "brdf_io/envmap.py", "brdf_io/export_material.py", "brdf_io/ktx2.py", "brdf_io/limits.py", "brdf_io/rgl.py",
    "cli/report/batch.py", "cli/report/threads.py", "render/glsl.py", "render/vtk_renderer.py",
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
    pasted = sorted(path for path, doc in docs.items() if RH02_DOI in doc)
    assert not pasted, f"RH02's reference pasted (cite [RH02] instead): {pasted}"


def test_module_docstrings_are_short():
    docs = {path: _module_docstring(text) for path, text in _sources().items()}
    lines = {path: len(doc.splitlines()) for path, doc in docs.items()}
    assert lines["brdf_io/reparam.py"] > 5  # the docstrings are read whole
    long = {path: n for path, n in sorted(lines.items()) if n > MAX_MODULE_DOC_LINES and path not in STILL_LONG}
    assert not long, (f"module docstrings over {MAX_MODULE_DOC_LINES} lines (say what the module does in a few "
                      f"lines; details go to the functions' docstrings or data_specs/): {long}")
