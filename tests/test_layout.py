"""The layout of the library: imports point one way, no private name crosses a module,
no module grows past the size one can read in a sitting.

Layers, lowest first (a module may import its own layer and the layers below):
fem_py and bem_cpp -> coupling.options -> coupling.{distributed, functional, timing} ->
coupling.{problem, manufactured} -> coupling.preconditioners -> coupling.solvers ->
coupling.io -> coupling.app. The research code beside the library (study/ and bench/,
not installed) reads the library and is never imported by it.
"""
from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("fem_py", "bem_cpp", "coupling")
MAX_LINES = 600
#: the research code beside the library: it imports the library, never the other way
RESEARCH = ("study", "bench")

LAYERS = [
    ("fem_py", "bem_cpp"),
    ("coupling.options",),
    ("coupling.distributed", "coupling.functional", "coupling.timing"),
    ("coupling.problem", "coupling.manufactured"),
    ("coupling.preconditioners",),
    ("coupling.solvers",),
    ("coupling.adapt",),
    ("coupling.io",),
    ("coupling.app",),
]
#: (importing module, imported package) pairs allowed upwards, inside functions only
LAZY_UPWARDS: set[tuple[str, str]] = set()


def _modules() -> list[tuple[str, Path]]:
    out = []
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob("*.py")):
            parts = path.relative_to(ROOT).with_suffix("").parts
            name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
            out.append((name, path))
    return out


def _layer(module: str) -> int | None:
    if module in PACKAGES:  # a package's own __init__ imports nothing of its own
        return 0
    for i, names in enumerate(LAYERS):
        if any(module == n or module.startswith(n + ".") for n in names):
            return i
    return None


def _imports(tree: ast.AST):
    """(imported module, names, inside a function) for every import of the project's code."""
    functions = [
        n for n in ast.walk(tree) if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef))
    ]
    nested = {id(n) for f in functions for n in ast.walk(f) if n is not f}
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            yield node.module, [a.name for a in node.names], id(node) in nested
        elif isinstance(node, ast.Import):
            for alias in node.names:
                yield alias.name, [], id(node) in nested


MODULES = _modules()


@pytest.mark.parametrize("name,path", MODULES, ids=[m for m, _ in MODULES])
def test_imports_point_down(name, path):
    own = _layer(name)
    assert own is not None, f"{name} is in no layer of tests/test_layout.py: add it"
    for module, _, lazy in _imports(ast.parse(path.read_text())):
        other = _layer(module)
        if other is None or other <= own:
            continue
        allowed = lazy and any(
            name == a and (module == b or module.startswith(b + ".")) for a, b in LAZY_UPWARDS
        )
        assert allowed, f"{name} (layer {own}) imports {module} (layer {other})"


@pytest.mark.parametrize("name,path", MODULES, ids=[m for m, _ in MODULES])
def test_library_never_imports_the_research_code(name, path):
    for module, _, _ in _imports(ast.parse(path.read_text())):
        top = module.split(".")[0]
        assert top not in RESEARCH, f"{name} imports {module}: the library cannot use {top}/"


@pytest.mark.parametrize("name,path", MODULES, ids=[m for m, _ in MODULES])
def test_no_private_names_across_modules(name, path):
    for module, names, _ in _imports(ast.parse(path.read_text())):
        if _layer(module) is None or module == name:
            continue
        private = [n for n in names if n.startswith("_")]
        assert not private, f"{name} imports private names {private} from {module}"


@pytest.mark.parametrize("name,path", MODULES, ids=[m for m, _ in MODULES])
def test_module_size(name, path):
    lines = len(path.read_text().splitlines())
    assert lines <= MAX_LINES, f"{name} has {lines} lines (at most {MAX_LINES}): split it"
