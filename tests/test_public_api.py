"""The declared public API (issue 27): what each package exports is written down in ``__all__``.

The public packages are ``shrmkit``, its four layers and every sub-package whose ``__init__``
declares ``__all__``. For each:

- (source, nothing imported) every public name the ``__init__`` binds — a function or class
  defined there, a name imported from the package's own modules, a module-level assignment, a key
  of its lazy-import table ``_LAZY`` — is in ``__all__``: a new public name cannot slip in
  undeclared;
- (imported) every name in ``__all__`` resolves and is documented: a function, class or module
  by its own docstring (not a dataclass's generated signature), a constant by a ``#:`` comment
  or a docstring beside its assignment in the module that defines it (what Sphinx's autodoc
  shows in the API reference).
"""

from __future__ import annotations

import ast
import importlib
import inspect
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
LAYERS = ("brdf_io", "analysis", "render", "cli")


def _module_path(module: str) -> Path:
    """The source file of a shrmkit module name (the package is laid out by setuptools package-dir)."""
    parts = module.split(".")[1:]
    base = ROOT.joinpath(*parts)
    return base / "__init__.py" if base.is_dir() else base.with_suffix(".py")


def _declaring_packages() -> list[str]:
    out = ["shrmkit", *(f"shrmkit.{layer}" for layer in LAYERS)]
    for layer in LAYERS:
        for init in sorted((ROOT / layer).rglob("__init__.py")):
            name = ".".join(["shrmkit", *init.parent.relative_to(ROOT).parts])
            if name not in out and "__all__" in _bound_names(init.read_text(encoding="utf-8")):
                out.append(name)
    return out


def _bound_names(source: str) -> dict[str, str | None]:
    """Top-level names a package ``__init__`` binds that are part of the package (not stdlib or
    third-party helpers it imports), each with the module it comes from (relative import or
    ``_LAZY`` entry; None when defined in the ``__init__`` itself)."""
    names: dict[str, str | None] = {}
    for node in ast.parse(source).body:
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
            names[node.name] = None
        elif isinstance(node, ast.ImportFrom) and node.level:
            for alias in node.names:
                names[alias.asname or alias.name] = "." * node.level + (node.module or "")
        elif isinstance(node, ast.Assign | ast.AnnAssign):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            for target in targets:
                if isinstance(target, ast.Name):
                    names[target.id] = None
                    if target.id == "_LAZY" and isinstance(node.value, ast.Dict):
                        for key, value in zip(node.value.keys, node.value.values, strict=True):
                            if isinstance(key, ast.Constant) and isinstance(value, ast.Constant):
                                names[key.value] = value.value
    return names


def public_names(source: str) -> set[str]:
    """The names of an ``__init__`` that must be declared: bound there, no leading underscore."""
    return {n for n in _bound_names(source) if not n.startswith("_")}


def _all_literal(source: str) -> list[str] | None:
    """``__all__`` as written (list entries and ``*_LAZY``), read from the source."""
    tree = ast.parse(source)
    lazy = [n for n, m in _bound_names(source).items() if m and not m.startswith(".")]
    for node in tree.body:
        if isinstance(node, ast.Assign) and any(isinstance(t, ast.Name) and t.id == "__all__" for t in node.targets):
            value = node.value
            if isinstance(value, ast.Call) and isinstance(value.func, ast.Name) and value.func.id == "list":
                return lazy  # __all__ = list(_LAZY)
            out: list[str] = []
            for element in getattr(value, "elts", []):
                if isinstance(element, ast.Constant):
                    out.append(element.value)
                elif isinstance(element, ast.Starred):
                    out.extend(lazy)
            return out
    return None


PACKAGES = _declaring_packages()


def test_the_checker_sees_a_new_name() -> None:
    """The source check itself: an undeclared function, class, re-export or lazy entry is seen."""
    source = (
        "from __future__ import annotations\nimport importlib\nfrom typing import Any\n"
        "from .brdf import BRDF, _private\n_LAZY = {'load_env': 'shrmkit.brdf_io.envmap'}\n"
        "__all__ = ['BRDF', *_LAZY]\n"
        "def new_helper():\n    pass\nclass NewThing:\n    pass\ndef _hidden():\n    pass\n"
    )
    assert public_names(source) == {"BRDF", "load_env", "new_helper", "NewThing"}
    assert public_names(source) - set(_all_literal(source) or []) == {"new_helper", "NewThing"}


def test_the_public_packages() -> None:
    assert PACKAGES[:5] == ["shrmkit", "shrmkit.brdf_io", "shrmkit.analysis", "shrmkit.render", "shrmkit.cli"]
    assert {"shrmkit.analysis.fit", "shrmkit.analysis.compare"} <= set(PACKAGES)


@pytest.mark.parametrize("package", PACKAGES)
def test_every_public_name_is_declared(package: str) -> None:
    source = _module_path(package).read_text(encoding="utf-8")
    declared = _all_literal(source)
    assert declared is not None, f"{package} declares no __all__"
    assert len(declared) == len(set(declared)), f"{package}.__all__ repeats a name"
    undeclared = sorted(public_names(source) - set(declared))
    assert not undeclared, (
        f"{_module_path(package).relative_to(ROOT)} binds public names missing from __all__: {undeclared} "
        "(declare them, or give them a leading underscore)"
    )


def _constant_documented(module: str, name: str, hops: int = 3) -> bool:
    """A ``#:`` comment just above the assignment of ``name`` in ``module``, or a docstring just
    below it; a name the module imports is followed to where it is defined."""
    path = _module_path(module)
    source = path.read_text(encoding="utf-8")
    lines = source.splitlines()
    body = ast.parse(source).body
    for i, node in enumerate(body):
        if isinstance(node, ast.Assign | ast.AnnAssign):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            if any(isinstance(t, ast.Name) and t.id == name for t in targets):
                above = lines[node.lineno - 2].strip() if node.lineno > 1 else ""
                below = body[i + 1] if i + 1 < len(body) else None
                return above.startswith("#:") or (
                    isinstance(below, ast.Expr) and isinstance(below.value, ast.Constant)
                    and isinstance(below.value.value, str))
        if isinstance(node, ast.ImportFrom) and node.level and hops:
            for alias in node.names:
                if (alias.asname or alias.name) == name:
                    package = module if path.name == "__init__.py" else module.rsplit(".", 1)[0]
                    base = package.split(".")[: len(package.split(".")) - (node.level - 1)]
                    target = ".".join(base + ([node.module] if node.module else []))
                    return _constant_documented(target, alias.name, hops - 1)
    return False


def _has_own_docstring(obj: object) -> bool:
    doc = obj.__doc__ if inspect.isclass(obj) else inspect.getdoc(obj)
    if not doc or not doc.strip():
        return False
    # a dataclass without a docstring gets its signature as __doc__
    return not (inspect.isclass(obj) and doc.startswith(f"{obj.__name__}("))


@pytest.mark.parametrize("package", PACKAGES)
def test_every_declared_name_resolves_and_is_documented(package: str) -> None:
    module = importlib.import_module(package)
    assert module.__doc__ and "internal" in module.__doc__ or package not in PACKAGES[:5], (
        f"{package}'s docstring says which modules are internal")
    sources = _bound_names(_module_path(package).read_text(encoding="utf-8"))
    problems = []
    for name in module.__all__:
        if name == "__version__":
            continue
        try:
            obj = getattr(module, name)
        except AttributeError as err:
            problems.append(f"{name}: does not resolve ({err})")
            continue
        if inspect.ismodule(obj) or inspect.isclass(obj) or inspect.isroutine(obj):
            if not _has_own_docstring(obj):
                problems.append(f"{name}: no docstring")
            continue
        # a constant or type alias: documented where it is assigned (followed from a re-export)
        origin = sources.get(name)
        documented = _constant_documented(origin if origin and not origin.startswith(".") else package, name)
        if not documented:
            problems.append(f"{name}: a constant without a '#:' comment or docstring where it is assigned")
    assert not problems, f"{package}.__all__:\n" + "\n".join(problems)


def test_every_public_package_has_an_api_page() -> None:
    """The docs' API reference (``docs/api/``, built by Sphinx in CI) shows every declaring package:
    a ``.. declared-api::`` directive names it (the top-level package has its own page)."""
    pages = "\n".join(p.read_text(encoding="utf-8") for p in sorted((ROOT / "docs" / "api").glob("*.rst")))
    shown = {line.split("::", 1)[1].strip() for line in pages.splitlines() if line.startswith(".. declared-api::")}
    assert ".. automodule:: shrmkit\n" in pages
    assert set(PACKAGES[1:]) <= shown, sorted(set(PACKAGES[1:]) - shown)
