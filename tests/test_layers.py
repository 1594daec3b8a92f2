"""The package's import graph: one-way layers, no cycles, no hidden imports (DESIGN §1).

Walks every module of ``shrmkit`` as source (nothing is imported) and checks:

- every import of a shrmkit module points down (or across) the stack
  ``brdf_io`` < ``analysis`` < ``render`` < ``cli``;
- no cycle among modules, nor among the sub-packages (folders);
- an import inside a function is only of an optional heavy dependency (VTK, Dask,
  embreex) and carries a comment saying why.
"""

from __future__ import annotations

import ast
import functools
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
LAYERS = {"brdf_io": 0, "analysis": 1, "render": 2, "cli": 3}
#: heavy dependencies a function may import on use (with a comment saying why): the GL stack, Dask,
#: and trimesh and scipy.stats (0.9 s and 0.5 s CPU at start-up, for every verb that never uses them)
LAZY_ALLOWED = ("vtkmodules", "vtk", "pyvista", "dask", "distributed", "embreex", "trimesh", "scipy")
#: our modules that are a heavy dependency's front: the report's plots (matplotlib, ~0.5 s CPU that a report
#: without plots does not pay), and matplotlib.artist itself (the console script's lean import,
#: cli/report/shared_state.py)
LAZY_ALLOWED_MODULES = ("shrmkit.cli.report.plots", "matplotlib.artist")


def _modules() -> dict[str, Path]:
    out = {}
    for folder in LAYERS:
        for path in sorted((ROOT / folder).rglob("*.py")):
            parts = list(path.relative_to(ROOT).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts = parts[:-1]
            out[".".join(["shrmkit", *parts])] = path
    return out


MODULES = _modules()


def _imports(name: str, path: Path) -> list[tuple[str, int, bool]]:
    """(absolute target, line, inside a function) for every import in the module."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    package = name.split(".") if path.name == "__init__.py" else name.split(".")[:-1]
    found: list[tuple[str, int, bool]] = []

    def visit(node: ast.AST, in_function: bool) -> None:
        for child in ast.iter_child_nodes(node):
            inner = in_function or isinstance(child, ast.FunctionDef | ast.AsyncFunctionDef | ast.Lambda)
            if isinstance(child, ast.Import):
                found.extend((alias.name, child.lineno, in_function) for alias in child.names)
            elif isinstance(child, ast.ImportFrom):
                if child.level:
                    base = package[: len(package) - (child.level - 1)]
                    target = ".".join(base + ([child.module] if child.module else []))
                else:
                    target = child.module or ""
                # "from . import x" may name a submodule
                targets = [target]
                for alias in child.names:
                    if f"{target}.{alias.name}" in MODULES:
                        targets.append(f"{target}.{alias.name}")
                found.extend((t, child.lineno, in_function) for t in targets)
            visit(child, inner)

    visit(tree, False)
    return found


@functools.cache
def _graph() -> dict[str, list[tuple[str, int, bool]]]:
    """Every module's imports (:func:`_imports`), parsed on first use, not at collection (1.6 s CPU in
    every xdist worker)."""
    return {name: _imports(name, path) for name, path in MODULES.items()}


def _layer(module: str) -> int | None:
    parts = module.split(".")
    return LAYERS.get(parts[1]) if len(parts) > 1 and parts[0] == "shrmkit" else None


def _folder(module: str) -> str:
    return module if MODULES.get(module, Path()).name == "__init__.py" else module.rsplit(".", 1)[0]


def test_the_walk_sees_the_package() -> None:
    assert {"shrmkit.brdf_io.merl", "shrmkit.analysis.shrm", "shrmkit.render.vtk_renderer",
            "shrmkit.cli.main"} <= set(MODULES)
    assert any(target == "shrmkit.brdf_io.errors" for target, _, _ in _graph()["shrmkit.brdf_io.merl"])


def test_every_import_points_down_the_stack() -> None:
    upward = [
        f"{MODULES[name].relative_to(ROOT)}:{line} imports {target}"
        for name, imports in _graph().items()
        for target, line, _ in imports
        if _layer(target) is not None and _layer(target) > _layer(name)
    ]
    assert not upward, "imports pointing up the stack brdf_io < analysis < render < cli:\n" + "\n".join(upward)


def _cycles(edges: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one node (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []

    def strong(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in edges.get(v, ()):
            if w not in index:
                strong(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(edges):
        if v not in index:
            strong(v)
    return out


def test_no_cycle_between_modules() -> None:
    edges = {name: {t for t, _, _ in imports if t in MODULES and t != name} for name, imports in _graph().items()}
    # a package's __init__ re-exporting its own modules is not a cycle of the code
    for name, targets in edges.items():
        if MODULES[name].name == "__init__.py":
            targets.difference_update({t for t in targets if t.startswith(name + ".")})
    assert not _cycles(edges)


def test_no_cycle_between_folders() -> None:
    edges: dict[str, set[str]] = {}
    for name, imports in _graph().items():
        src = _folder(name)
        for target, _, _ in imports:
            if target in MODULES and _folder(target) != src:
                dst = _folder(target)
                if not (src.startswith(dst + ".") or dst.startswith(src + ".")):
                    edges.setdefault(src, set()).add(dst)
    assert not _cycles(edges)


def test_imports_inside_functions_are_only_lazy_heavy_dependencies() -> None:
    bad = []
    for name, imports in _graph().items():
        lines = MODULES[name].read_text(encoding="utf-8").splitlines()
        for target, line, in_function in imports:
            if not in_function:
                continue
            allowed = target.split(".")[0] in LAZY_ALLOWED or target in LAZY_ALLOWED_MODULES
            commented = "#" in lines[line - 1] or (line > 1 and "#" in lines[line - 2])
            if not (allowed and commented):
                bad.append(f"{MODULES[name].relative_to(ROOT)}:{line} imports {target} inside a function"
                           + ("" if allowed else "") + ("" if commented else " (no comment saying why)"))
    assert not bad, "\n".join(bad)


@pytest.mark.parametrize("folder", sorted(LAYERS))
def test_every_folder_is_a_package(folder: str) -> None:
    for sub in [ROOT / folder, *[p for p in (ROOT / folder).rglob("*") if p.is_dir() and p.name != "__pycache__"]]:
        if any(sub.glob("*.py")):
            assert (sub / "__init__.py").is_file(), sub
