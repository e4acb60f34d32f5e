"""Sphinx extension of the fembem site: the pages that are generated from the code.

- ``{fembem-config}``: the configuration reference, from ``coupling.options.DEFAULTS``
  (keys and defaults), ``CHOICES`` and the validation code (each key's constraint is the
  message the validation gives for a bad value), with the descriptions of
  docs/guide/keys.md; a key without a description, or a description of no key, fails
  the build.
- ``{fembem-cli}``: the command-line reference, from the argparse parser of
  ``coupling.app.cli``.
- ``{fembem-exit-codes}``: the exit codes, from the ``EXIT_*`` constants of
  ``coupling.app.ending``.
- ``{fembem-errors}``: the one-line errors of bad configurations, produced at build time
  by the validation code.
- docs/api/*.rst: one page per module of fem_py, bem_cpp and coupling, found by walking
  the packages (so moving a module into a subpackage moves its page).
- docs/demos/*.md: one page per demos/demo_*.py, with the script's cells and, after each
  code cell, what it printed and the figures it wrote (the demos run at small sizes,
  ``demo_pages.SMALL``; the runs are cached under _build/demo-runs, keyed by the
  sources).
- MathJax 2.7 from Debian's libjs-mathjax, copied into the build (offline), and
  Debian furo's script made loadable as a classic script.
"""
from __future__ import annotations

import shutil
from pathlib import Path

from sphinx.application import Sphinx
from sphinx.util import logging

from . import api_pages, demo_pages, directives, docstrings

logger = logging.getLogger(__name__)

MATHJAX = Path("/usr/share/javascript/mathjax")  # Debian package libjs-mathjax
#: What the TeX-AMS_SVG configuration loads: the SVG output draws the TeX fonts from
#: JavaScript glyph data (no web fonts to fetch).
MATHJAX_PARTS = (
    "MathJax.js",
    "config/TeX-AMS_SVG.js",
    "extensions",
    "jax/element",
    "jax/input/TeX",
    "jax/output/PreviewHTML",
    "jax/output/SVG/jax.js",
    "jax/output/SVG/config.js",
    "jax/output/SVG/autoload",
    "jax/output/SVG/fonts/TeX",
    "localization/en",
)


def _generate_pages(app: Sphinx) -> None:
    root = Path(app.srcdir).parent
    api_pages.write_api_pages(Path(app.srcdir) / "api", root)
    demo_pages.write_demo_pages(
        Path(app.srcdir) / "demos", root, Path(app.outdir).parent / "demo-runs"
    )


def _copy_mathjax(app: Sphinx) -> None:
    if not (MATHJAX / "MathJax.js").is_file():
        raise RuntimeError(f"{MATHJAX}/MathJax.js not found: install libjs-mathjax (make docs)")
    target = Path(app.outdir) / "_static" / "mathjax"
    for part in MATHJAX_PARTS:
        src, dst = MATHJAX / part, target / part
        if dst.exists():
            continue
        dst.parent.mkdir(parents=True, exist_ok=True)
        if src.is_dir():
            shutil.copytree(src, dst, symlinks=False)
        else:
            shutil.copy2(src, dst)


_FURO_IMPORT = 'import Gumshoe from "./gumshoe-patched.js";'


def _furo_classic_scripts(app: Sphinx) -> None:
    """Debian's furo ships scripts/furo.js unbundled, as an ES module (its first line
    imports gumshoe), but loads it as a classic script: the browser rejects it, and
    modules cannot load from file:// pages anyway. Load gumshoe (a UMD script that
    defines window.Gumshoe) first, and furo.js without its import line (_copy_assets)."""
    if app.config.html_theme == "furo":
        app.add_js_file("scripts/gumshoe-patched.js", priority=199)


def _fix_furo_script(app: Sphinx) -> None:
    script = Path(app.outdir) / "_static" / "scripts" / "furo.js"
    if script.is_file():
        text = script.read_text()
        if text.startswith(_FURO_IMPORT):
            script.write_text(text[len(_FURO_IMPORT) :])


def _copy_assets(app: Sphinx, exception: Exception | None) -> None:
    if exception is None and app.builder.format == "html":
        _fix_furo_script(app)
        _copy_mathjax(app)


def setup(app: Sphinx) -> dict:
    app.connect("builder-inited", _generate_pages)
    app.connect("builder-inited", _furo_classic_scripts)
    app.connect("build-finished", _copy_assets)
    app.connect("autodoc-process-docstring", docstrings.escape_bars)
    app.connect("autodoc-process-docstring", docstrings.link_method)
    app.connect("missing-reference", docstrings.reexported_reference)
    app.connect("warn-missing-reference", docstrings.external_reference)
    directives.register(app)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
