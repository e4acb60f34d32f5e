"""Directives that insert the generated reference tables (:mod:`reference`) into a page.

The Markdown they produce is parsed in place, so the tables take part in the build
like written text (links checked, warnings are errors).
"""
from __future__ import annotations

from typing import Callable

from docutils import nodes
from docutils.statemachine import StringList
from sphinx.application import Sphinx
from sphinx.util.docutils import SphinxDirective

from . import reference


def _directive(make: Callable[..., str]) -> type[SphinxDirective]:
    class Generated(SphinxDirective):
        has_content = False
        optional_arguments = 1

        def run(self) -> list[nodes.Node]:
            for path in (reference.KEYS, reference.EXIT_CODES, reference.ERRORS):
                self.env.note_dependency(str(path))
            container = nodes.container()
            self.state.nested_parse(
                StringList(make(*self.arguments).splitlines(), source=self.get_source_info()[0]),
                self.content_offset,
                container,
            )
            return container.children

    return Generated


def register(app: Sphinx) -> None:
    app.add_directive("fembem-config", _directive(reference.config_markdown))
    app.add_directive("fembem-cli", _directive(reference.cli_markdown))
    app.add_directive("fembem-exit-codes", _directive(reference.exit_codes_markdown))
    app.add_directive("fembem-errors", _directive(reference.errors_markdown))
