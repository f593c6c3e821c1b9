"""Sphinx configuration of the hysteresis-toolkit documentation.

Why Sphinx (and not MkDocs): the docstrings are numpydoc-style reStructuredText, which Sphinx's
autodoc/autosummary read natively (with the bundled ``napoleon`` extension: no extra
dependency), so the API pages are generated from the code at every build and follow it; the
scientific Python stack (NumPy, SciPy, numba) documents itself this way, so cross-references
and conventions are familiar; and ``sphinx-build -W`` turns every warning (a broken reference, a
malformed docstring) into a failure, which the test suite runs (``tests/test_docs.py``).
"""

from __future__ import annotations

import os
import shutil
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # document the source tree next to this file
# autosummary writes a stub per module into api/generated and never deletes one: a stub left
# from a module that was moved or removed breaks the next `-W` build. Start from none.
shutil.rmtree(Path(__file__).resolve().parent / "api" / "generated", ignore_errors=True)

from hysteresis import __version__  # noqa: E402

project = "hysteresis-toolkit"
author = "hysteresis-toolkit contributors"
copyright = "2026, hysteresis-toolkit contributors (MIT License)"
version = release = __version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
]
autosummary_generate = True
autosummary_imported_members = False
# document each object once, on the page of the module that defines it (a package's __all__
# re-exports would otherwise be documented twice and make cross-references ambiguous)
autodoc_default_options = {"members": True, "show-inheritance": True, "ignore-module-all": True}
autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_typehints_format = "short"
napoleon_google_docstring = False
napoleon_numpy_docstring = True
napoleon_use_rtype = False
# "Attributes" sections as :ivar: fields, so a documented property is not described twice
napoleon_use_ivar = True

# ":ivar alpha:" links the name "alpha", which several classes define (Relay, Preisach models):
# Sphinx then reports an ambiguous target. The link is cosmetic; every other warning stays fatal.
suppress_warnings = ["ref.python"]

templates_path: list[str] = []
exclude_patterns = ["_build", "gallery", "**/*.md", "_generated"]
source_suffix = {".rst": "restructuredtext"}
html_theme = "alabaster"
html_static_path: list[str] = []
html_theme_options = {"description": "Hysteresis operators and forced oscillators"}


def _write_cli_help(app) -> None:  # noqa: ANN001 - sphinx application
    """``hyst COMMAND --help`` of every command, generated from the parser at build time, so the
    CLI page cannot drift from the code."""
    import argparse

    from analysis.cli import build_parser

    os.environ["COLUMNS"] = "96"
    out = Path(app.srcdir) / "_generated"
    out.mkdir(exist_ok=True)
    parser = build_parser()
    (out / "hyst.txt").write_text(parser.format_help())
    action = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    for name, sub in action.choices.items():
        (out / f"hyst_{name}.txt").write_text(sub.format_help())


def _full_length_underlines(app, what, name, obj, options, lines) -> None:  # noqa: ANN001
    """Lengthen a section underline that is shorter than its title (a cosmetic slip that
    docutils reports as an error; the text is unchanged)."""
    for i in range(1, len(lines)):
        mark = lines[i].strip()
        title = lines[i - 1].strip()
        if title and len(mark) >= 3 and set(mark) <= set("-=~^") and len(mark) < len(title):
            indent = lines[i][: len(lines[i]) - len(lines[i].lstrip())]
            lines[i] = indent + mark[0] * len(title)


def setup(app) -> None:  # noqa: ANN001
    app.connect("builder-inited", _write_cli_help)
    app.connect("autodoc-process-docstring", _full_length_underlines, priority=400)
