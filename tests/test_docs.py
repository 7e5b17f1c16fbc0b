"""Every ```python block of README.md and of every docs/*.md page runs: the blocks of one file in order, in one
namespace, from a temporary directory (a block whose preceding line or first comment says it runs from the
repository root runs there, with the root on ``sys.path``). A line ``expr  # value`` whose comment starts with a
number, a quoted string, or a tuple or list of them is checked after the line runs: a number to the digits shown
(``0.2504281...`` means the shown digits are a prefix), a string exactly. A comment that is prose is not checked.
Every image the pages show exists and is a PNG."""

from __future__ import annotations

import ast
import math
import numbers
import os
import re
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parent.parent
PAGES = [
    ROOT / "README.md",
    *sorted((ROOT / "docs").glob("*.md")),
    *sorted((ROOT / "docs" / "tutorials").glob("*.md")),
]
NUMBER = r"(?<![\w.])[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?(?:\.\.\.)?(?![\w.])"
TOKEN = re.compile(rf"""('[^']*'|"[^"]*")|({NUMBER})""")  # a quoted string (left as it is) or a number
ROOT_MARK = re.compile(r"repository root", re.I)


@dataclass(frozen=True)
class Shown:
    """A number as a page prints it: ``text`` holds its digits (and ``...`` when they are a prefix)."""

    text: str

    @property
    def prefix(self) -> bool:
        return self.text.endswith("...")

    @property
    def value(self) -> float:
        return float(self.text.removesuffix("..."))

    @property
    def step(self) -> float:
        """One unit in the last digit shown (0 for an integer shown in full)."""
        digits = self.text.removesuffix("...").lstrip("+-")
        mantissa, _, exponent = digits.lower().partition("e")
        decimals = len(mantissa.partition(".")[2])
        if not decimals and not exponent and not self.prefix:
            return 0.0
        return 10.0 ** (int(exponent or 0) - decimals)

    def matches(self, actual: float) -> bool:
        if isinstance(actual, bool) or not isinstance(actual, numbers.Real):
            return False
        actual = float(actual)
        if self.prefix:  # the shown digits begin the value's: |shown| <= |actual| < |shown| + step
            return abs(actual - self.value) < self.step * (1 + 1e-9) and math.copysign(1, actual) * self.value >= 0
        return abs(actual - self.value) <= self.step * (1 + 1e-9) + 1e-12 * abs(self.value)


def expected(comment: str):
    """The value a comment states (numbers as ``Shown``), or None when the comment is prose: the longest start
    of the comment, ending at a space, a ': ' or a '; ' (where a unit or prose may begin: ``88.709 N m``,
    ``(163.45..., 86.67...) N m, deg``) or at its end, that reads as a value."""
    text = comment.strip()
    if not re.match(r"""[-+\d.'"(\[]""", text):
        return None
    ends = [m.start() for m in re.finditer(r"\s|:\s|;\s", text)] + [len(text)]
    for end in sorted(ends, reverse=True):
        value = _value(text[:end].strip().rstrip(",;"))
        if value is not None:
            return value
    return None


def _value(text: str):
    marked = TOKEN.sub(lambda m: m.group(1) or f"Shown({m.group(2)!r})", text)
    try:
        tree = ast.parse(marked, mode="eval")
    except SyntaxError:
        return None
    for node in ast.walk(tree):
        allowed = (ast.Expression, ast.Tuple, ast.List, ast.Constant, ast.Load, ast.Call, ast.Name)
        if not isinstance(node, allowed) or (isinstance(node, ast.Name) and node.id != "Shown"):
            return None
        if isinstance(node, ast.Constant) and not isinstance(node.value, str):
            return None  # a bare True, None or ... is not a value the checker compares
    return eval(compile(tree, "<comment>", "eval"), {"__builtins__": {}, "Shown": Shown})


def agrees(actual, want) -> bool:
    if isinstance(want, Shown):
        if not isinstance(actual, numbers.Real):
            try:
                actual = np.asarray(actual, dtype=float)
            except (TypeError, ValueError):
                return False
            if actual.size != 1:
                return False
            actual = actual.item()
        return want.matches(actual)
    if isinstance(want, str):
        return actual == want or (not isinstance(actual, str) and str(actual) == want)
    if isinstance(want, tuple | list):
        try:
            items = list(actual)
        except TypeError:
            return False
        return len(items) == len(want) and all(agrees(a, w) for a, w in zip(items, want, strict=True))
    return actual == want


@dataclass
class Block:
    page: Path
    line: int  # the line of the page where the code starts
    code: str
    at_root: bool


def blocks(page: Path) -> list[Block]:
    text = page.read_text()
    out = []
    for m in re.finditer(r"```python\n(.*?)```", text, re.S):
        line = text.count("\n", 0, m.start()) + 2
        before = text[: m.start()].rstrip("\n").rpartition("\n")[2]
        comments = [c for c in (ln.partition("#")[2] for ln in m.group(1).splitlines()) if c]
        at_root = bool(ROOT_MARK.search(before) or (comments and ROOT_MARK.search(comments[0])))
        out.append(Block(page, line, m.group(1), at_root))
    return out


def checks(code: str) -> dict[int, str]:
    """Statement end line -> the comment that states its value: the comment on that line, or else the comment
    lines right below it (a value too long for one line)."""
    lines = code.splitlines()
    tree = ast.parse(code)
    out = {}
    for stmt in tree.body:
        if not isinstance(stmt, ast.Expr | ast.Assign):
            continue
        end = stmt.end_lineno
        inline = _comment(lines[end - 1])
        if inline is None and end < len(lines) and lines[end].strip().startswith("#"):
            inline = lines[end].strip()[1:]
        if inline is not None:
            out[end] = inline
    return out


def _comment(line: str) -> str | None:
    """The comment of a code line (a '#' outside any string literal)."""
    quote = None
    for i, ch in enumerate(line):
        if quote:
            quote = None if ch == quote else quote
        elif ch in "'\"":
            quote = ch
        elif ch == "#":
            return line[i + 1 :] if line[:i].strip() else None
    return None


def run_block(block: Block, namespace: dict, tmp: Path) -> int:
    """Run one block statement by statement; returns how many stated values it checked."""
    os.chdir(ROOT if block.at_root else tmp)
    tree = ast.parse(block.code)
    wanted = checks(block.code)
    checked = 0
    for stmt in tree.body:
        where = f"{block.page.name}:{block.line + stmt.lineno - 1}"
        source = ast.get_source_segment(block.code, stmt)
        if isinstance(stmt, ast.Expr):
            value = eval(compile(ast.Expression(stmt.value), where, "eval"), namespace)
        else:
            exec(compile(ast.Module([stmt], []), where, "exec"), namespace)
            value = None
            if isinstance(stmt, ast.Assign) and len(stmt.targets) == 1 and isinstance(stmt.targets[0], ast.Name):
                value = namespace[stmt.targets[0].id]
        comment = wanted.get(stmt.end_lineno)
        want = expected(comment) if comment is not None and isinstance(stmt, ast.Expr | ast.Assign) else None
        if want is not None:
            assert agrees(value, want), f"{where}: {source.strip()} is {value!r}, the page says {comment.strip()}"
            checked += 1
    return checked


@pytest.mark.parametrize("page", [p for p in PAGES if blocks(p)], ids=lambda p: p.relative_to(ROOT).as_posix())
def test_python_blocks_run(page, tmp_path, monkeypatch):
    found = blocks(page)
    monkeypatch.syspath_prepend(str(ROOT))
    monkeypatch.chdir(tmp_path)
    namespace = {"__name__": "__docs__"}
    for block in found:
        run_block(block, namespace, tmp_path)
    for name in [m for m in sys.modules if m == "problems" or m.startswith("problems.")]:
        del sys.modules[name]  # the next page imports the repository's problem files afresh


def test_pages_have_python_examples():
    assert sum(len(blocks(p)) for p in PAGES) >= 10


def images(page: Path) -> list[Path]:
    return [(page.parent / m).resolve() for m in re.findall(r"!\[[^\]]*\]\(([^)\s]+)\)", page.read_text())]


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.relative_to(ROOT).as_posix())
def test_images_exist_and_are_png(page):
    for path in images(page):
        assert path.is_file(), f"{page.name} shows {path}, which is missing: run python docs/make_images.py"
        with path.open("rb") as f:
            assert f.read(8) == b"\x89PNG\r\n\x1a\n", path
        assert path.stat().st_size > 1000, path


def test_make_images_draws_every_image_shown():
    script = (ROOT / "docs" / "make_images.py").read_text()
    for page in PAGES:
        for path in images(page):
            assert path.name in script, f"{page.name} shows {path.name}, which docs/make_images.py does not draw"


@pytest.mark.parametrize(
    ("comment", "actual", "ok"),
    [
        (" 0.2504281217548...", 0.25042812175489, True),
        (" 0.2504281217548...", 0.2504281217558, False),
        (" 27.0082 (the true gamma_min)", 27.00823, True),
        (" 27.0082", 27.0092, False),
        (" 'optimal', 0.2504281..., 0.15", ("optimal", 0.25042812, 0.15), True),
        (
            " [(0.25042812..., 'optimal'), (0.15434448..., 'local_optimum')]",
            [(0.250428121, "optimal"), (0.154344489, "local_optimum")],
            True,
        ),
        (" 2, [0.1543445, 0.2504281]", (2, [0.15434448, 0.25042812]), True),
        (" 1177", 1178, False),
        (" 1.2e-07", 1.24e-07, True),
        (" -1.073402", -1.0734021, True),
        (" 'by enumeration: eqs. (7)-(13) give every r3'", "by enumeration: eqs. (7)-(13) give every r3", True),
        (" '-x' (for omega2 > 0)", "-x", True),
        (" [0.529649]", np.array([0.52964869]), True),
        (" 88.709 N m", 88.7091, True),
        (" 88.709 N m", 90.2, False),
        (" (163.451..., 86.673...) N m, deg", (163.4512, 86.6731), True),
        (" (163.451..., 86.673...) N m, deg", (163.4512, 86.6631), False),
        (" ('optimal', 114.694...) N m: the smallest lever", ("optimal", 114.6949), True),
        (" (22, 180) kg, deg", (22, 181), False),
    ],
)
def test_the_checker_reads_stated_values(comment, actual, ok):
    assert agrees(actual, expected(comment)) is ok


@pytest.mark.parametrize(
    "comment", [" exact time_ratio, stroke, ...", " Result(status='optimal', ...): at most 15 lines", " a note", ""]
)
def test_the_checker_leaves_prose(comment):
    assert expected(comment) is None
