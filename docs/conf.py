"""Sphinx configuration of qropt's documentation site (see docs/README.md).

The Markdown pages in docs/ are read as they are by myst-parser; the API reference (docs/reference/) is written
by autodoc from the docstrings; the example notebook's page is the notebook run at build time (docs/README.md).
Nothing is fetched at build time or by the built pages.
"""

from __future__ import annotations

import ast
import contextlib
import io
import json
import re
import sys
import tempfile
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
# docs/notebook.ipynb is no source of its own (.ipynb is no source suffix): docs/tutorials/example-notebook.md shows
# it, run at build time (see "the example notebook" below), and notebook.md links it as a download

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


# -- the example notebook --------------------------------------------------------------------------------------
# docs/notebook.ipynb is kept without outputs. A page whose source has the line ``{notebook} PATH`` in a fenced
# directive (docs/tutorials/example-notebook.md) gets, in its place, the notebook run at build time, in this
# process and with the qropt that autodoc documents: each markdown cell as it is, each code cell as a Python block,
# then what Jupyter would show for it: its printed text and its last expression's value, as that object's
# ``_repr_html_()`` (qropt's views: self-contained HTML with inline SVG) or else its ``repr()``. The cells run in
# order in one namespace, in a temporary directory; a cell that fails stops the build with the cell's number.
# Nothing is installed for this: no kernel, and no outputs stored in git to go stale.

_NOTEBOOK = re.compile(r"^(`{3,}|~{3,})\{notebook\}[ \t]+(\S+)[ \t]*\n\1[ \t]*$", re.M)


def _fence(text: str, info: str) -> str:
    """``text`` in a fenced block (``info`` after the opening fence) longer than any backtick run inside it."""
    ticks = max([3, *(len(run) + 1 for run in re.findall(r"`{3,}", text))])
    return f"{'`' * ticks}{info}\n{text.rstrip()}\n{'`' * ticks}\n"


def _shown(value) -> str:
    """What a notebook shows for a cell's value, as MyST: a qropt view (or any object with ``_repr_html_``) as
    raw HTML, anything else as its repr."""
    html = getattr(value, "_repr_html_", None)
    html = html() if callable(html) else None
    if html:
        return _fence(f'<div class="nb-output">\n{html}\n</div>', "{raw} html")
    return _fence(repr(value), "text")


def notebook_myst(path: Path) -> str:
    """The notebook at ``path`` as MyST: its cells, each code cell followed by what running it shows."""
    notebook = json.loads(path.read_text(encoding="utf-8"))
    namespace = {"__name__": "__main__"}
    parts = []
    with tempfile.TemporaryDirectory() as scratch, contextlib.chdir(scratch):
        for k, cell in enumerate(notebook["cells"]):
            source = "".join(cell["source"])
            if cell["cell_type"] == "markdown":
                parts.append(source.rstrip() + "\n")
                continue
            if cell["cell_type"] != "code" or not source.strip():
                continue
            parts.append(_fence(source, "python"))
            where = f"{path.name}, cell {k + 1}"
            tree = ast.parse(source, where)
            shows = not source.rstrip().endswith(";")  # as in Jupyter, a trailing ";" hides the value
            last = tree.body.pop() if shows and tree.body and isinstance(tree.body[-1], ast.Expr) else None
            printed = io.StringIO()
            try:
                with contextlib.redirect_stdout(printed):
                    exec(compile(tree, where, "exec"), namespace)
                    value = None
                    if last is not None:
                        value = eval(compile(ast.Expression(last.value), where, "eval"), namespace)
            except Exception as error:
                raise RuntimeError(f"{path}: cell {k + 1} (code) fails: {error!r}") from error
            if printed.getvalue():
                parts.append(_fence(printed.getvalue(), "text"))
            if value is not None:
                parts.append(_shown(value))
    return "\n".join(parts)


def notebooks(app, docname: str, source: list[str]) -> None:
    def run(match: re.Match) -> str:
        path = (Path(app.env.doc2path(docname)).parent / match.group(2)).resolve()
        app.env.note_dependency(str(path))  # an edited notebook rebuilds its page
        return notebook_myst(path)

    source[0] = _NOTEBOOK.sub(run, source[0])


def setup(app):
    app.connect("autodoc-process-docstring", prose_docstring)
    app.connect("source-read", outside_links)
    app.connect("source-read", notebooks)
