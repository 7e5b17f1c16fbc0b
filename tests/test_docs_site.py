"""The documentation site (docs/README.md): its API reference documents every public name and module, and it
builds with Sphinx with warnings as errors (a missing page, heading or reference, and a docstring that is not
valid reST, are all warnings), offline, into pages whose internal links resolve and that load nothing from
elsewhere: no ``<link>``, ``<script>``, ``<img>`` (or other embedded resource) and no stylesheet
``@import``/``url()``/``@font-face`` with an address of another host. The example notebook (docs/notebook.ipynb,
kept without outputs) is a tutorial page with what each of its cells shows, run as the site is built (docs/conf.py)."""

from __future__ import annotations

import html
import importlib.util
import json
import os
import pkgutil
import re
import subprocess
import sys
import time
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urldefrag

import pytest

import qropt

ROOT = Path(__file__).resolve().parent.parent
DOCS = ROOT / "docs"
REFERENCE = DOCS / "reference"
NOTEBOOK = DOCS / "notebook.ipynb"
# ``.. autoclass:: qropt.Solver`` in reST, ```{autoclass} qropt.Solver`` in MyST
DIRECTIVE = re.compile(r"^\s*(?:\.\.\s+|```\{)(auto\w+)(?:::|\})\s+([\w.]+)", re.M)
EXTERNAL = re.compile(r"^\s*(?:[a-z][a-z0-9+.-]*:)?//", re.I)  # http://, https://, //host (not data: or file:)


def reference_directives() -> list[tuple[str, str]]:
    """(directive, target) of every autodoc directive in docs/reference/."""
    found = []
    for page in sorted(REFERENCE.rglob("*")):
        if page.suffix in (".rst", ".md"):
            found += DIRECTIVE.findall(page.read_text(encoding="utf-8"))
    return found


def public_modules() -> set[str]:
    """qropt's modules and packages none of whose name's parts starts with an underscore."""
    names = {"qropt"}
    for info in pkgutil.walk_packages(qropt.__path__, "qropt."):
        if not any(part.startswith("_") for part in info.name.split(".")):
            names.add(info.name)
    return names


def test_the_reference_documents_every_public_name():
    documented = {target.removeprefix("qropt.") for kind, target in reference_directives() if kind != "automodule"}
    documented = {name for name in documented if "." not in name}  # qropt.NAME, not qropt.module.NAME
    missing = [name for name in qropt.__all__ if name not in documented]
    assert not missing, f"docs/reference/api.rst does not document these names of qropt.__all__: {missing}"
    extra = sorted(documented - set(qropt.__all__))
    assert not extra, f"docs/reference/api.rst documents qropt.NAME for names not in qropt.__all__: {extra}"


def test_the_reference_has_every_public_module():
    documented = {target for kind, target in reference_directives() if kind == "automodule"}
    missing = sorted(public_modules() - documented)
    assert not missing, (
        "docs/reference/ has no automodule for these public modules (add each to its package's page in "
        f"docs/reference/modules/): {missing}"
    )
    stale = sorted(documented - public_modules())
    assert not stale, f"docs/reference/ documents modules that are not public modules of qropt: {stale}"


def test_the_link_checker_reads_pages():
    page = Page()
    page.feed(
        '<link rel="stylesheet" href="https://cdn.example/x.css"><script src="_static/a.js"></script>'
        '<img src="//cdn.example/p.png"><a href="api.html#qropt.Solver">x</a><a href="https://x.org">y</a>'
        '<span id="here"></span><img src="data:image/png;base64,AAAA">'
    )
    assert page.external == ["link https://cdn.example/x.css", "img //cdn.example/p.png"]
    assert page.links == ["_static/a.js", "api.html#qropt.Solver"]
    assert "here" in page.ids


class Page(HTMLParser):
    """The ids of a built page, its same-site links (href and src), and the addresses of other hosts from which
    it would load something (a stylesheet, a script, an image, a frame, a font preload...)."""

    LOADS = {"link": "href", "script": "src", "img": "src", "iframe": "src", "source": "src", "embed": "src"}

    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.ids: set[str] = set()
        self.links: list[str] = []
        self.external: list[str] = []

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        if attrs.get("id"):
            self.ids.add(attrs["id"])
        if tag == "a" and attrs.get("name"):
            self.ids.add(attrs["name"])
        for key in ("href", "src", "srcset"):
            value = (attrs.get(key) or "").strip()
            if not value:
                continue
            if EXTERNAL.match(value):
                if self.LOADS.get(tag) == key or key == "srcset":
                    self.external.append(f"{tag} {value}")
            elif not re.match(r"^(?:mailto|data|javascript|tel):", value, re.I) and key != "srcset":
                self.links.append(value)


def check_links(site: Path) -> tuple[list[str], list[str]]:
    """(broken same-site links, external loads) over every built page."""
    pages: dict[Path, Page] = {}
    for path in sorted(site.rglob("*.html")):
        if "_static" in path.relative_to(site).parts:  # the theme's copied templates, no pages
            continue
        page = Page()
        page.feed(path.read_text(encoding="utf-8"))
        pages[path.resolve()] = page
    broken, external = [], []
    for path, page in pages.items():
        where = path.relative_to(site.resolve()).as_posix()
        external += [f"{where}: {load}" for load in page.external]
        for link in page.links:
            url, fragment = urldefrag(link)
            url = unquote(url.split("?", 1)[0])
            target = (path.parent / url).resolve() if url else path
            if target.is_dir():
                target = target / "index.html"
            if not target.exists():
                broken.append(f"{where}: {link} (no file {target})")
            elif fragment and target.suffix == ".html" and unquote(fragment) not in pages[target].ids:
                broken.append(f"{where}: {link} (no id {fragment!r} in {target.name})")
    return broken, external


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    """The site built as docs/README.md says, warnings as errors, into a temporary directory."""
    if importlib.util.find_spec("sphinx") is None:
        pytest.skip('Sphinx is not installed (pip install ".[docs]" or ".[test]" installs it)')
    out = tmp_path_factory.mktemp("site")
    html, doctrees = out / "html", out / "doctrees"
    env = {**os.environ, "PYTHONDONTWRITEBYTECODE": "1"}
    command = [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-b", "html", "-d", str(doctrees)]
    start = time.monotonic()
    run = subprocess.run(
        [*command, str(DOCS), str(html)], cwd=ROOT, env=env, capture_output=True, text=True, timeout=600
    )
    assert run.returncode == 0, f"the site does not build ({time.monotonic() - start:.0f} s):\n{run.stderr[-6000:]}"
    return html


def test_the_site_builds_with_every_part(site):
    index = (site / "index.html").read_text(encoding="utf-8")
    for part in ("tutorials/index.html", "how-to/index.html", "reference/index.html", "explanation/index.html"):
        assert part in index, f"the index links no {part}"
    for page in sorted(DOCS.glob("*.md")):
        if page.name != "README.md":
            assert (site / page.with_suffix(".html").name).is_file(), f"docs/{page.name} is not in the site"
    api = (site / "reference" / "api.html").read_text(encoding="utf-8")
    missing = [name for name in qropt.__all__ if f'id="qropt.{name}"' not in api]
    assert not missing, f"the built reference has no entry for {missing}"


def test_the_sites_links_resolve_and_nothing_is_loaded_from_elsewhere(site):
    broken, external = check_links(site)
    assert not broken, "links that lead nowhere:\n" + "\n".join(broken[:50])
    assert not external, "the pages load from other hosts:\n" + "\n".join(external[:50])
    for sheet in sorted(site.rglob("*.css")):
        text = sheet.read_text(encoding="utf-8", errors="replace")
        addresses = re.findall(
            r"""(?:@import\s+(?:url\()?|url\()\s*['"]?((?:[a-z][a-z0-9+.-]*:)?//[^'")\s]+)""", text, re.I
        )
        assert not addresses, f"{sheet.relative_to(site)} loads {addresses[:5]}"


def test_the_example_notebook_is_a_tutorial_page_with_its_outputs(site):
    assert "example-notebook.html" in (site / "tutorials" / "index.html").read_text(encoding="utf-8")
    page = (site / "tutorials" / "example-notebook.html").read_text(encoding="utf-8")
    code = [cell for cell in json.loads(NOTEBOOK.read_text(encoding="utf-8"))["cells"] if cell["cell_type"] == "code"]
    outputs = re.findall(r'<div class="nb-output">(.*?)\n</div>', page, re.S)
    assert len(outputs) == len(code), f"{len(code)} code cells, {len(outputs)} outputs on the page"
    assert all("<svg" in output for output in outputs), "an output without its picture"
    assert all("<table" in output for output in outputs[1:]), "a result, comparison or front without its table"
    text = html.unescape(re.sub(r"<[^>]+>", "", page))
    for cell in code:  # each cell's code is shown too
        line = max("".join(cell["source"]).splitlines(), key=len)
        assert line in text, line
    for shown in ("1.5 (slow / fast)", "Result: optimal", "27.0082 deg", "crank-shaper", "non-dominated"):
        assert shown in text, shown
    assert "{notebook}" not in page


@pytest.fixture(scope="module")
def conf():
    """docs/conf.py as a module (its notebook runner)."""
    if importlib.util.find_spec("sphinx") is None:
        pytest.skip('Sphinx is not installed (pip install ".[docs]" or ".[test]" installs it)')
    spec = importlib.util.spec_from_file_location("qropt_docs_conf", DOCS / "conf.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def notebook(tmp_path: Path, *cells: tuple[str, str]) -> Path:
    path = tmp_path / "n.ipynb"
    path.write_text(json.dumps({"cells": [{"cell_type": t, "metadata": {}, "source": s} for t, s in cells]}))
    return path


def test_the_notebook_runner_shows_what_jupyter_shows(conf, tmp_path):
    text = conf.notebook_myst(
        notebook(
            tmp_path,
            ("markdown", "# Title\n\nSome `code`."),
            ("code", "x = 2\nprint('printed', x)\nx * 21"),
            ("code", "x;"),  # a trailing ";" shows nothing
            ("code", "open('written', 'w').close()\ns = '````'\ns"),
            ("code", "from qropt.examples import paper_mechanism\npaper_mechanism()"),
        )
    )
    assert text.startswith("# Title\n\nSome `code`.\n")
    assert "```python\nx = 2\nprint('printed', x)\nx * 21\n```\n" in text
    assert "```text\nprinted 2\n```\n" in text and "```text\n42\n```\n" in text
    assert "```python\nx;\n```\n\n`````python" in text  # and no output
    assert "`````text\n'````'\n`````\n" in text  # a fence longer than any inside
    assert not (tmp_path / "written").exists()  # the cells run in a temporary directory
    assert text.count('```{raw} html\n<div class="nb-output">\n<div class="qropt-nb qropt-nb-mechanism"') == 1


def test_the_notebook_runner_stops_on_a_failing_cell(conf, tmp_path):
    path = notebook(tmp_path, ("code", "x = 1"), ("markdown", "text"), ("code", "1 / 0"))
    with pytest.raises(RuntimeError, match=r"n.ipynb: cell 3 \(code\) fails: ZeroDivisionError"):
        conf.notebook_myst(path)
