"""Directives that insert the generated reference tables (:mod:`reference`) into a page.

The Markdown they produce is parsed in place, so the tables take part in the build
like written text (links checked, warnings are errors).
"""
from __future__ import annotations

from typing import Callable

from docutils import nodes
from docutils.statemachine import StringList
from sphinx.application import Sphinx
from sphinx.util import logging
from sphinx.util.docutils import SphinxDirective

from . import reference

logger = logging.getLogger(__name__)


def _directive(make: Callable[..., str]) -> type[SphinxDirective]:
    class Generated(SphinxDirective):
        has_content = False
        optional_arguments = 1

        def run(self) -> list[nodes.Node]:
            if make is reference.cli_markdown and self.arguments:
                seen = _cli_pages(self.env)
                seen.setdefault(self.env.docname, set()).add(self.arguments[0])
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


def _cli_pages(env) -> dict[str, set[str]]:
    if not hasattr(env, "fembem_cli_commands"):
        env.fembem_cli_commands = {}
    return env.fembem_cli_commands


def _purge(app: Sphinx, env, docname: str) -> None:
    _cli_pages(env).pop(docname, None)


def _merge(app: Sphinx, env, docnames, other) -> None:
    _cli_pages(env).update(_cli_pages(other))


def _every_command_documented(app: Sphinx, env) -> None:
    """The command-line reference must show every subcommand of the parser."""
    shown = set().union(*_cli_pages(env).values())
    missing = [c for c in reference.cli_commands() if c not in shown]
    if missing:
        logger.warning(
            "the command-line reference lacks `fembem %s`: add a ```{fembem-cli} <command>``` "
            "section to docs/guide/cli.md",
            ", ".join(missing),
        )


def register(app: Sphinx) -> None:
    app.connect("env-purge-doc", _purge)
    app.connect("env-merge-info", _merge)
    app.connect("env-check-consistency", _every_command_documented)
    app.add_directive("fembem-config", _directive(reference.config_markdown))
    app.add_directive("fembem-cli", _directive(reference.cli_markdown))
    app.add_directive("fembem-exit-codes", _directive(reference.exit_codes_markdown))
    app.add_directive("fembem-errors", _directive(reference.errors_markdown))
