"""The layout of the library: imports point one way, no private name crosses a module,
no module grows past the size one can read in a sitting.

Layers, lowest first (a module may import its own layer and the layers below):
fem_py and bem_cpp -> coupling.options -> coupling.{distributed, functional, timing} ->
coupling.{problem, manufactured} -> coupling.preconditioners -> coupling.solvers ->
coupling.io -> coupling.app. The research code beside the library (study/ and bench/,
not installed) reads the library and is never imported by it.

Inside a package the subpackages are layered too (``INNER_LAYERS``, one entry per
package), with no exception for imports inside functions; and no module of any package
takes part in an import circle, imports inside functions included.
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
    # bem_cpp inside, one module per layer: the compiled core, then checks, operators, ...
    (
        "bem_cpp._bem",
        "bem_cpp.collectives",
        "bem_cpp.defaults",
        "bem_cpp.dense",
        "bem_cpp.sparse",
        "bem_cpp.surfaces",
        "bem_cpp.polygons",
    ),
    ("bem_cpp.checks",),
    ("bem_cpp.operators",),
    ("bem_cpp.compressed",),
    ("bem_cpp.potentials",),
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

#: The layers inside a package, lowest first (one entry per package). fem_py: the MPI
#: helpers, point-set geometry, facet tags and the geometry spec -> the P1 dofs -> the
#: subdomain partitions -> the meshes of Omega -> the forms -> the boundary map.
INNER_LAYERS = {
    "fem_py": [
        (
            "fem_py.parallel",
            "fem_py.polyline",
            "fem_py.tags",
            "fem_py.spec",
            "fem_py.memory",
            "fem_py.signals",
        ),
        ("fem_py.dofs",),
        ("fem_py.partition",),
        ("fem_py.mesh",),
        ("fem_py.forms",),
        ("fem_py.boundary",),
    ],
}


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


def _inner_layer(module: str) -> int | None:
    package = module.split(".")[0]
    for i, names in enumerate(INNER_LAYERS.get(package, ())):
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
        if other is None or other <= own or module.startswith(name + ".") and name == "bem_cpp":
            continue  # (bem_cpp's __init__ only re-exports its modules)
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


@pytest.mark.parametrize("name,path", MODULES, ids=[m for m, _ in MODULES])
def test_imports_point_down_inside_the_package(name, path):
    package = name.split(".")[0]
    if package not in INNER_LAYERS or name == package:
        return
    own = _inner_layer(name)
    assert own is not None, f"{name} is in no layer of INNER_LAYERS[{package!r}]: add it"
    for module, _, _ in _imports(ast.parse(path.read_text())):
        if module.split(".")[0] != package:
            continue
        other = _inner_layer(module)
        assert other is not None, f"{name} imports {module}, which is in no layer"
        assert other <= own, f"{name} (layer {own}) imports {module} (layer {other})"


def _import_graph() -> dict[str, set[str]]:
    """module -> the project modules it imports (at module level or inside functions)."""
    names = {name for name, _ in MODULES}
    graph = {}
    for name, path in MODULES:
        graph[name] = set()
        for module, imported, _ in _imports(ast.parse(path.read_text())):
            # ``from package import module`` imports the module
            targets = [f"{module}.{n}" for n in imported if f"{module}.{n}" in names]
            graph[name].update(targets or ([module] if module in names else []))
        graph[name].discard(name)
    return graph


def test_no_import_circles():
    graph = _import_graph()
    done: set[str] = set()

    def visit(node: str, path: list[str]) -> None:
        if node in path:
            circle = path[path.index(node) :] + [node]
            raise AssertionError("import circle: " + " -> ".join(circle))
        if node in done:
            return
        for other in sorted(graph[node]):
            visit(other, path + [node])
        done.add(node)

    for node in sorted(graph):
        visit(node, [])
