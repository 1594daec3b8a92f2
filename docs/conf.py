"""Sphinx configuration of the shrmkit documentation site (issue 26).

Build from the repository root (CI does, with warnings as errors)::

    .venv/bin/python -m sphinx -W --keep-going -q -b html -c docs . build/docs

The source folder is the repository root, so that the README, ``data_specs/`` and the gallery's
images are read where they are (no copies); ``include_patterns`` picks the pages. The API
reference (``docs/api/``) is made by autodoc from the docstrings of the names each package
declares in ``__all__`` (numpy-style sections through napoleon, ``#:`` comments for constants);
the Markdown pages are read by MyST.
"""

from __future__ import annotations

import ast
import importlib
import inspect
import re
from pathlib import Path

from docutils import nodes
from docutils.statemachine import StringList
from sphinx.errors import PycodeError
from sphinx.pycode import ModuleAnalyzer
from sphinx.util.docutils import SphinxDirective
from sphinx.util.nodes import nested_parse_with_titles

import shrmkit

project = "shrmkit"
author = "The shrmkit developers"
copyright = "the shrmkit developers, BSD-3-Clause"
version = release = shrmkit.__version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "myst_parser",
]

root_doc = "docs/index"
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
include_patterns = [
    "docs/index.md",
    "docs/gallery.md",
    "docs/formats.md",
    "docs/api/*.rst",
    "README.md",
    "CHANGELOG.md",
    "data_specs/*.md",
]
exclude_patterns = [".venv", "build", "dist", "tests", "benchmarks", "**/__pycache__", "shrm-*"]

# autodoc: the declared names only, in source order, with the signatures' type hints
autodoc_default_options = {"members": True, "imported-members": True, "member-order": "bysource"}
autodoc_typehints = "description"
autodoc_typehints_description_target = "documented"
autodoc_typehints_format = "short"
autoclass_content = "class"
napoleon_google_docstring = False
napoleon_numpy_docstring = True
napoleon_use_rtype = False

# MyST: the README and data_specs pages as they are on GitHub
myst_heading_anchors = 3
myst_enable_extensions = ["dollarmath"]


html_theme = "furo"
html_title = f"shrmkit {release}"
html_static_path: list[str] = []
html_extra_path = ["_extra"]  # index.html at the site's root, pointing to docs/index.html
napoleon_use_ivar = True  # "Attributes" as fields: no second description of a dataclass field

_CODE = re.compile(r"(``.+?``|`[^`]+`)")
_PARAM = re.compile(r"^\*{0,2}[A-Za-z_]\w*(\s*,\s*\*{0,2}[A-Za-z_]\w*)*(\s*:.*)?$")
_PARAM_SECTIONS = ("Parameters", "Other Parameters", "Keyword Arguments")


def _plain_bars(line: str) -> str:
    """``|x|`` (an absolute value, a norm) outside code spans, escaped so that reST does not read
    a substitution reference; a line of a reST table or line block is left alone."""
    if "|" not in line or line.lstrip().startswith(("|", "+")):
        return line
    return "".join(part if _CODE.fullmatch(part) else part.replace("|", r"\|") for part in _CODE.split(line))


def _end_parameter_sections(lines: list[str]) -> None:
    """A numpy-style Parameters section followed, after a blank line, by an unindented sentence
    (not a parameter name) is closed by a "Notes" heading, as the author meant: napoleon would
    otherwise read the sentence as one more parameter."""
    section = None
    i = 0
    while i < len(lines):
        line = lines[i]
        if i + 1 < len(lines) and lines[i + 1].strip() and set(lines[i + 1].strip()) == {"-"}:
            section = line.strip()
            i += 2
            continue
        if (section in _PARAM_SECTIONS and line and not line[0].isspace() and i > 0 and not lines[i - 1].strip()
                and not _PARAM.match(line.strip())):
            lines[i:i] = ["Notes", "-----", ""]
            section = "Notes"
            i += 3
            continue
        i += 1


def _origin(module: str, name: str, hops: int = 4) -> tuple[str, str]:
    """The module that assigns ``name`` re-exported by ``module`` (through its ``_LAZY`` table or a
    relative import), and the name there."""
    loaded = importlib.import_module(module)
    lazy = getattr(loaded, "_LAZY", {})
    if name in lazy:
        return lazy[name], name
    path = Path(loaded.__file__ or "")
    for node in ast.parse(path.read_text(encoding="utf-8")).body:
        if isinstance(node, ast.ImportFrom) and node.level and hops:
            for alias in node.names:
                if (alias.asname or alias.name) == name:
                    package = module if path.name == "__init__.py" else module.rsplit(".", 1)[0]
                    parts = package.split(".")
                    base = ".".join(parts[: len(parts) - (node.level - 1)] + ([node.module] if node.module else []))
                    return _origin(base, alias.name, hops - 1)
    return module, name


def _constant_doc(qualified: str) -> list[str]:
    """The ``#:`` comment (or docstring) of a constant where it is assigned: autodoc reads only the
    module it documents, and the packages re-export their constants from the modules."""
    module, _, name = qualified.rpartition(".")
    try:
        origin, there = _origin(module, name)
        docs = ModuleAnalyzer.for_module(origin).find_attr_docs()
    except (ImportError, OSError, SyntaxError, PycodeError):
        return []
    return list(docs.get(("", there), []))


def _process_docstring(app, what, name, obj, options, lines: list[str]) -> None:
    if what == "data":  # not the docstring of the value's type (float, dict, ...)
        lines[:] = _constant_doc(name)
    _end_parameter_sections(lines)
    lines[:] = [_plain_bars(line) for line in lines]


class DeclaredAPI(SphinxDirective):
    """``.. declared-api:: shrmkit.analysis``: the package's docstring, then every name of its
    ``__all__`` in order, each by the autodoc directive of its kind, so that the reference follows
    the declaration (no hand-kept list)."""

    required_arguments = 1

    def run(self) -> list[nodes.Node]:
        package = self.arguments[0]
        module = importlib.import_module(package)
        lines = [f".. automodule:: {package}", "   :no-members:", ""]
        for name in module.__all__:
            obj = getattr(module, name)
            kind = "class" if inspect.isclass(obj) else "function" if inspect.isroutine(obj) else "data"
            lines.append(f".. auto{kind}:: {package}.{name}")
            if kind == "data" and len(repr(obj)) > 60:  # a table: its entries are documented where defined
                lines.append("   :no-value:")
            lines.append("")
        content = StringList(lines, source=f"<declared-api {package}>")
        node = nodes.container()
        nested_parse_with_titles(self.state, content, node)
        return node.children


def _skip_rule_mirrors(app, what, name, obj, skip, options):
    """Options classes' properties that read their ``OrderRule``'s fields (``rule.criterion`` …) are
    documented by the rule: listed too, they made ``:ivar criterion:`` of every class ambiguous."""
    if isinstance(obj, property) and "``rule." in (obj.__doc__ or ""):
        return True
    return None


def setup(app):
    app.add_directive("declared-api", DeclaredAPI)
    app.connect("autodoc-skip-member", _skip_rule_mirrors)
    app.connect("autodoc-process-docstring", _process_docstring, priority=400)  # before napoleon (500)
