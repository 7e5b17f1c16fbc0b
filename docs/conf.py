"""Sphinx configuration of qropt's documentation site (see docs/README.md).

The Markdown pages in docs/ are read as they are by myst-parser; the API reference (docs/reference/) is written
by autodoc from the docstrings. Nothing is fetched at build time or by the built pages.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))  # the qropt of this work tree, installed or not

import qropt  # noqa: E402

project = "qropt"
author = "qropt contributors"
copyright = "qropt contributors"
release = qropt.__version__
version = release

extensions = ["myst_parser", "sphinx.ext.autodoc"]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "README.md"]  # README.md: how to build, for the repository's readers
# docs/notebook.ipynb is no page (rendering it would need myst-nb, and it has no outputs to show): notebook.md
# describes it and links it, and the site offers it as a download

# the pages link to each other's headings as GitHub does (benchmarks.md#the-dynamic-rows)
myst_heading_anchors = 4

# the docstrings are prose with ``literal`` spans; the signatures carry the type hints as written
autodoc_typehints = "signature"
autodoc_member_order = "bysource"
autodoc_preserve_defaults = True

html_theme = "pydata_sphinx_theme"
html_title = f"qropt {release}"
html_static_path = ["_static"]
html_css_files = ["qropt.css"]
html_show_sourcelink = False
html_copy_source = False
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
    "header_links_before_dropdown": 4,
    "navbar_align": "left",
    "footer_start": ["copyright"],
    "footer_end": ["sphinx-version"],
    "secondary_sidebar_items": ["page-toc"],
}


# -- the docstrings' prose, read as reST --------------------------------------------------------------------------
# qropt's docstrings are plain prose with ``literal`` spans, written to read well in help() and in an editor. Three
# of their habits mean something else in reST, and docutils would stop the -W build on them:
# - ``|x|`` is an absolute value or a norm (|dx/dtheta2|, |s|_inf), not a substitution reference;
# - ``x_`` followed by a non-word character (``z_-min``) is a subscript, not a hyperlink reference;
# - a list starts on the line after its introduction ("...in order:" then "1. ..."), as in Markdown, and the
#   paragraph after it follows its last item directly; reST wants a blank line on both sides.
# The hook below escapes the first two outside ``literal``/`role` spans and literal blocks, and adds those blank
# lines, in qropt's own docstrings only; it changes nothing else, so each docstring renders as help() shows it.

_SPAN = re.compile(r"(``.*?``|:?[\w:.-]*`[^`]*`_{0,2})")
_ITEM = re.compile(r"^(\s*)(?:[-*+]|\d+[.)]|\(\d+\)) \S")
_SUBSCRIPT = re.compile(r"(?<=[A-Za-z0-9])_(?![A-Za-z0-9_`])")


def _escape(text: str) -> str:
    text = text.replace("|", "\\|")
    return _SUBSCRIPT.sub(r"\\_", text)


def _prose_line(line: str, in_literal: bool) -> tuple[str, bool]:
    """The line with ``|`` and subscript ``_`` escaped outside literal spans; whether a ``literal`` span is open
    at its end (a span may wrap onto the next line)."""
    out = []
    rest = line
    if in_literal:  # the end of a span begun on an earlier line
        end = rest.find("``")
        if end < 0:
            return line, True
        out.append(rest[: end + 2])
        rest = rest[end + 2 :]
    parts = _SPAN.split(rest)
    for i, part in enumerate(parts):
        if i % 2:
            out.append(part)
        elif part.count("``") % 2:  # a span opens here and closes on a later line
            head, _, tail = part.partition("``")
            out.append(_escape(head) + "``" + tail)
            return "".join(out), True
        else:
            out.append(_escape(part))
    return "".join(out), False


def _indent(line: str) -> int:
    return len(line) - len(line.lstrip())


def prose_docstring(app, what, name, obj, options, lines: list[str]) -> None:
    if not name.startswith("qropt"):
        return
    result: list[str] = []
    literal_block = None  # the indent of the paragraph that ended with "::" while its literal block lasts
    in_span = False
    list_indent = None  # the indent of the items of the list being read
    for line in lines:
        blank = not line.strip()
        if literal_block is not None:
            if blank or _indent(line) > literal_block:
                result.append(line)
                continue
            literal_block = None
        if blank:
            list_indent = None
            result.append(line)
            continue
        item = _ITEM.match(line)
        previous = result[-1] if result else ""
        if item and previous.strip() and list_indent is None and not in_span:
            result.append("")  # a list right after its introduction
        if item:
            list_indent = len(item.group(1))
        elif list_indent is not None and _indent(line) <= list_indent and not in_span:
            result.append("")  # the paragraph right after a list
            list_indent = None
        text, in_span = _prose_line(line, in_span)
        result.append(text)
        if line.rstrip().endswith("::") and not in_span:
            literal_block = _indent(line)
    lines[:] = result


# -- links out of docs/ ---------------------------------------------------------------------------------------
# A page may link to a file of the repository outside docs/ (benchmarks.md links ../benchmarks/results/results.md),
# which reads well on a forge but is no document of the site: such a link to a file that exists becomes a download
# of that file (MyST's ``path:`` links). A link to a missing file is left as it is, so the build still fails on it.

_OUTSIDE = re.compile(r"\]\((\.\./[^)\s#]+)\)")


def outside_links(app, docname: str, source: list[str]) -> None:
    here = Path(app.env.doc2path(docname)).parent

    def download(match: re.Match) -> str:
        target = (here / match.group(1)).resolve()
        outside = Path(app.srcdir).resolve() not in target.parents
        return f"](path:{match.group(1)})" if outside and target.is_file() else match.group(0)

    source[0] = _OUTSIDE.sub(download, source[0])


def setup(app):
    app.connect("autodoc-process-docstring", prose_docstring)
    app.connect("source-read", outside_links)
