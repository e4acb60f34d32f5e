"""How the docstrings are read for the API reference.

The project's docstrings write mathematics in plain text (``|grad u|``, ``|x_i - b|``)
and NumPy-style types in words (``(n, 2) float array``). Two hooks make that readable by
Sphinx without changing the sources:

- :func:`escape_bars`: a ``|`` outside literals and tables is an absolute value, not a
  reStructuredText substitution, so it is escaped;
- :func:`link_method`: "docs/method.md section N" becomes a link to that section of the
  method page.

:func:`external_reference` keeps the build nitpicky for the project's own names only: a
reference that cannot be resolved is an error when it names something of fem_py,
bem_cpp or coupling (:func:`reexported_reference` first follows a package's re-export
to the defining module), and plain text otherwise (the words of a NumPy type description,
or a name of numpy, PETSc, DOLFINx, ... for which no inventory exists offline).
"""
from __future__ import annotations

import importlib
import re
from typing import Any, TypeVar

from docutils import nodes
from sphinx.application import Sphinx

PACKAGES = ("fem_py", "bem_cpp", "coupling")
_LITERAL = re.compile(r"(``.*?``|`[^`]*`)")
#: "docs/method.md section 6" and the same with the older name of that page
_METHOD_SECTION = re.compile(r"(?:docs/method|METHOD)\.md,? sections? (\d+)")
_METHOD = re.compile(r"(?<![/\w])(?:docs/method|METHOD)\.md")


_TABLE_ROW = re.compile(r"^\s*(\+[-=+]+\+|\|.*\|)\s*$")  # a grid table's border or row


def _escape(line: str) -> str:
    if _TABLE_ROW.match(line):
        return line
    parts = _LITERAL.split(line)
    return "".join(p if i % 2 else re.sub(r"(?<!\\)\|", r"\\|", p) for i, p in enumerate(parts))


def escape_bars(app: Sphinx, what: str, name: str, obj: Any, options: Any, lines: list) -> None:
    """autodoc-process-docstring: escape the bars of plain-text absolute values."""
    in_literal_block = False
    for i, line in enumerate(lines):
        stripped = line.strip()
        if in_literal_block and stripped and not line.startswith((" ", "\t")):
            in_literal_block = False
        if not in_literal_block:
            lines[i] = _escape(line)
        if stripped.endswith("::"):
            in_literal_block = True


def _link(text: str) -> str:
    if _METHOD_SECTION.search(text):
        return _METHOD_SECTION.sub(
            lambda m: f":ref:`{m[0].replace('docs/method.md', 'docs/method.md')} <method-{m[1]}>`",
            text,
        )
    return _METHOD.sub(":doc:`docs/method.md </method>`", text)


def link_method(app: Sphinx, what: str, name: str, obj: Any, options: Any, lines: list) -> None:
    """autodoc-process-docstring: link "docs/method.md section N" (or "docs/method.md section
    N", the name the docstrings used before the site) to that section of the method page,
    and a bare "docs/method.md" to the page."""
    for i, line in enumerate(lines):
        parts = _LITERAL.split(line)
        lines[i] = "".join(p if k % 2 else _link(p) for k, p in enumerate(parts))


def _lookup(target: str) -> Any:
    """The object a dotted name of the project names, or None."""
    parts = target.split(".")
    for i in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:i]))
        except ImportError:
            continue
        try:
            for attr in parts[i:]:
                obj = getattr(obj, attr)
        except AttributeError:
            return None
        return obj
    return None


def reexported_reference(
    app: Sphinx, env: Any, node: nodes.Element, contnode: nodes.Node
) -> nodes.Node | None:
    """missing-reference: a name a package re-exports (``coupling.solvers.solve``) links
    to the documentation of the module that defines it."""
    target = node.get("reftarget", "")
    if node.get("refdomain") != "py" or target.split(".")[0] not in PACKAGES:
        return None
    obj = _lookup(target)
    module, qualname = getattr(obj, "__module__", None), getattr(obj, "__qualname__", None)
    if not module or not qualname or f"{module}.{qualname}" == target:
        return None
    domain = env.get_domain("py")
    return domain.resolve_xref(
        env, node["refdoc"], app.builder, node["reftype"], f"{module}.{qualname}", node, contnode
    )


def external_reference(app: Sphinx, domain: Any, node: nodes.Element) -> bool | None:
    """warn-missing-reference: True (no warning) unless the target is a public name of
    the project (private names and type variables have no page)."""
    if node.get("refdomain") != "py":
        return None
    target = node.get("reftarget", "")
    if target.split(".")[0] not in PACKAGES or any(p.startswith("_") for p in target.split(".")):
        return True
    if isinstance(_lookup(target), TypeVar):
        return True
    return None  # an internal reference that does not resolve: an error
