"""The API reference pages: one per public module of fem_py, bem_cpp and coupling.

The module list is found at build time by walking the packages' folders, so a module
moved into a subpackage moves its page and a new module gets one. Private modules
(a name part starting with ``_``) and ``__main__`` scripts are left out.
"""
from __future__ import annotations

from pathlib import Path

PACKAGES = ("fem_py", "bem_cpp", "coupling")


def public_modules(root: Path, package: str) -> list[str]:
    """Dotted names of the public modules of ``package`` (a folder of ``root``), sorted."""
    base = root / package
    names = []
    for path in sorted(base.rglob("*.py")):
        rel = path.relative_to(root).with_suffix("")
        parts = list(rel.parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        if any(p.startswith("_") for p in parts):
            continue
        # only folders that are packages (an __init__.py all the way down)
        folders = [root.joinpath(*rel.parts[:i]) for i in range(1, len(rel.parts))]
        if all((f / "__init__.py").is_file() for f in folders):
            names.append(".".join(parts))
    return sorted(names)


def _page(module: str, children: list[str]) -> str:
    title = f"``{module}``"
    lines = [title, "=" * len(title), "", f".. automodule:: {module}", ""]
    if children:
        lines += [".. toctree::", "   :maxdepth: 1", ""]
        lines += [f"   {child}" for child in children]
        lines.append("")
    return "\n".join(lines)


def write_api_pages(target: Path, root: Path) -> list[str]:
    """Write target/<module>.rst for every public module and target/index.rst; files
    of modules that no longer exist are removed. Returns the module names."""
    target.mkdir(parents=True, exist_ok=True)
    modules = [m for p in PACKAGES for m in public_modules(root, p)]
    wanted = {f"{m}.rst" for m in modules} | {"index.rst"}
    for old in target.glob("*.rst"):
        if old.name not in wanted:
            old.unlink()
    for module in modules:
        depth = module.count(".") + 1
        children = [m for m in modules if m.startswith(module + ".") and m.count(".") == depth]
        _write_if_changed(target / f"{module}.rst", _page(module, children))
    top = ["API reference", "=============", ""]
    top += [
        "The public Python API, from the NumPy-style docstrings. The packages in the order",
        "the data flows through them: ``fem_py`` (the DOLFINx side), ``bem_cpp`` (the",
        "boundary element library) and ``coupling`` (the coupled problem, its solvers and",
        "the application). The module list is generated from the packages at build time.",
        "",
        ".. toctree::",
        "   :maxdepth: 1",
        "",
    ]
    top += [f"   {p}" for p in PACKAGES]
    _write_if_changed(target / "index.rst", "\n".join(top) + "\n")
    return modules


def _write_if_changed(path: Path, text: str) -> None:
    """Sphinx rebuilds a page whose file changed; leave unchanged files alone."""
    if not path.is_file() or path.read_text() != text:
        path.write_text(text)
