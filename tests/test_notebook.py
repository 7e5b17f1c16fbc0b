"""Notebook representations (``_repr_html_``): the example notebook runs and every displayed object renders; each of
the six classes shows its key numbers as the library computes them, inline SVG whose links meet at their joints,
nothing external, escaped text, within a size cap."""

from __future__ import annotations

import ast
import dataclasses
import json
import math
import re
import sys
import xml.etree.ElementTree as ET
from html import escape as html_escape
from pathlib import Path

import pytest

import qropt
from problems import chart_crank_rocker
from qropt import Problem, family, solve
from qropt.dynamics.model import Counterweight
from qropt.examples import paper_mechanism, paper_problem
from qropt.io import drawing
from qropt.io.notebook import MAX_ROWS, mechanism_html, mechanism_svg
from qropt.mechanisms import FourBar
from qropt.synthesis.result import Result

ROOT = Path(__file__).resolve().parent.parent
NOTEBOOK = ROOT / "docs" / "notebook.ipynb"
EVIL = "<script>alert('x')</script> & co"
SVG = "{http://www.w3.org/2000/svg}"


def svgs(html: str) -> list:
    """Every inline SVG of the HTML, parsed as XML (so each is well-formed)."""
    return [ET.fromstring(s) for s in re.findall(r"<svg\b.*?</svg>", html, re.S)]


def self_contained(html: str, cap: int) -> None:
    assert isinstance(html, str)
    assert "<svg" in html
    assert len(html) < cap, len(html)
    low = html.lower()
    for bad in ("<script", "<link", "<iframe", "<img", "src=", "href=", "url(", "@import", "javascript:"):
        assert bad not in low, bad
    assert not re.search(r"""(src|href)\s*=\s*["']?https?://""", low)
    assert not re.search(r"\bid\s*=", low)  # no element ids: several outputs in one page cannot clash
    svgs(html)


def escaped(html: str) -> None:
    assert EVIL not in html and "<script" not in html
    assert "&lt;script&gt;alert(&#x27;x&#x27;)&lt;/script&gt; &amp; co" in html


# ---- the objects (built once: a few seconds in all) -------------------------------------------------------------
@pytest.fixture(scope="module")
def result():
    return solve(paper_problem())


@pytest.fixture(scope="module")
def comparison():
    return qropt.design(1.5, 0.3, types=["slider-crank", "crank-shaper"])


@pytest.fixture(scope="module")
def front():
    p = Problem(
        "CrankRockerSlider",
        fixed={"r1": 0.3, "r2": 0.1, "r6": 0.5},
        free={"r3": (0.15, 0.6), "r4": (0.15, 0.45), "r5": (0.02, 0.45)},
        targets={"time_ratio": 1.2, "stroke": 0.15},
        name=EVIL,
    )
    return qropt.pareto(p, ("max_gamma_min", "min_size"), n=4)


def chart_problem(name=""):
    return chart_crank_rocker.build().replace(name=name)  # the problems/ file the chart docs use


@pytest.fixture(scope="module")
def chart():
    return qropt.chart(chart_problem(EVIL), ("time_ratio", [1.5, 2.0]), ("swing", [math.radians(60), math.radians(90)]))


@pytest.fixture(scope="module")
def fam():
    p = Problem(
        "DragLinkSlider",
        fixed={"r2": 0.225, "r4": 0.275, "r5": 0.15, "r6": 0.3},
        free={"r1": (0.02, 0.2), "r3": (0.05, 0.6)},
        targets={"time_ratio": 1.5},
        name=EVIL,
    )
    return family(p)


# ---- (a) the example notebook --------------------------------------------------------------------------------
def test_the_example_notebook_runs_and_every_cell_shows_html(tmp_path, monkeypatch):
    nb = json.loads(NOTEBOOK.read_text())
    assert nb["nbformat"] == 4
    code = [c for c in nb["cells"] if c["cell_type"] == "code"]
    assert len(code) >= 4
    monkeypatch.chdir(tmp_path)
    namespace = {"__name__": "__notebook__"}
    shown = []
    for k, cell in enumerate(code):
        assert cell["outputs"] == [] and cell["execution_count"] is None, "stored outputs"
        source = "".join(cell["source"])
        tree = ast.parse(source)
        last = tree.body.pop() if tree.body and isinstance(tree.body[-1], ast.Expr) else None
        exec(compile(tree, f"notebook cell {k}", "exec"), namespace)
        assert last is not None, f"code cell {k} does not end with an object to show"
        obj = eval(compile(ast.Expression(last.value), f"notebook cell {k}", "eval"), namespace)
        html = obj._repr_html_()
        self_contained(html, 60_000)
        shown.append(type(obj).__name__)
    assert {"DragLinkSlider", "Result", "Comparison", "Front"} <= set(shown)
    r = namespace["r"]
    assert r.status == "optimal" and r.params["r3"] == pytest.approx(0.2504281217548, abs=1e-12)
    assert f"{math.degrees(r.objective):.6g} deg" in r._repr_html_()  # 27.0082 deg
    assert [row.type for row in namespace["c"].rows][0] == "crank-shaper"


# ---- (b) the six classes -------------------------------------------------------------------------------------
def joints_meet_links(root) -> None:
    """Every link of a mechanism picture ends at a drawn joint or pivot (its ends are joint centres)."""
    centres = [(float(c.get("cx")), float(c.get("cy"))) for c in root.iter(f"{SVG}circle")]
    centres += [(float(r.get("x")) + 4, float(r.get("y")) + 4) for r in root.iter(f"{SVG}rect")]
    links = [p for p in root.iter(f"{SVG}polyline") if p.get("stroke-width") == "3" and p.get("stroke-linecap")]
    assert links
    for p in links:
        ends = [tuple(map(float, xy.split(","))) for xy in p.get("points").split()]
        assert len(ends) == 2
        for x, y in ends[:1]:  # the first end is a joint; the second a joint or a slot lever's far end
            assert min(math.hypot(x - a, y - b) for a, b in centres) < 0.15, (x, y)


def test_mechanism(monkeypatch):
    m = paper_mechanism()
    html = m._repr_html_()
    self_contained(html, 20_000)
    d, g = m.dead_centres(), m.gamma_min()
    for text in (
        "DragLinkSlider (drag-link-slider)",
        f"{m.time_ratio():.6g} (slow / fast)",
        f"{m.stroke():.6g} m",
        f"{math.degrees(g.value):.6g} deg",
        f"{math.degrees(d.theta_max):.3f} deg (x_max {d.x_max:.6g} m)",
        f"{math.degrees(d.theta_min):.3f} deg (x_min {d.x_min:.6g} m)",
        f"r3 = {m.params['r3']:.6g} m",
        "sigma = -1",
    ):
        assert text in html, text
    assert "27.0082 deg" in html and "256.386 deg" in html  # the paper's design, as README and seeds.md state
    (root,) = svgs(html)
    joints_meet_links(root)
    names = {t.text for t in root.iter(f"{SVG}text")}
    assert set(m.positions([0.0]).points) <= names  # every joint named
    # the output's path over a turn reaches both dead centres (x in px: margin + (x - x_min of the picture) * scale)
    shapes = drawing.at(drawing.scene(m), math.radians(100))
    x0, x1, _, _ = drawing.bounds(shapes)
    one = mechanism_svg(m, math.radians(100))
    path = next(p for p in svgs(one)[0].iter(f"{SVG}polyline") if p.get("stroke-opacity"))
    xs = [float(xy.split(",")[0]) for xy in path.get("points").split()]
    scale = (float(svgs(one)[0].get("width")) - 44) / (x1 - x0)
    assert (max(xs) - min(xs)) / scale == pytest.approx(m.stroke(), abs=0.2 / scale)
    assert "theta2 = 200 deg" in mechanism_html(m, math.radians(200))


def test_a_follower_and_a_mechanism_without_dead_centres():
    m = FourBar(r1=1.0, r2=0.3, r3=1.0, r4=0.9)
    html = m._repr_html_()
    self_contained(html, 20_000)
    assert f'swing</th><td style="text-align:left;padding:1px 4px">{math.degrees(m.stroke()):.6g} deg' in html
    assert f"{m.time_ratio():.6g} (slow / fast)" in html and "1.21198 (slow / fast)" in html
    drag = FourBar(r1=0.3, r2=1.0, r3=1.0, r4=1.0)  # a drag-link: the follower turns fully, no dead centres
    html = drag._repr_html_()
    self_contained(html, 20_000)
    assert "time ratio</th>" in html and "n/a (" in html


def test_result(result):
    html = result._repr_html_()
    self_contained(html, 30_000)
    q = result.quantities
    for text in (
        ">optimal</span>",
        f"{result.objective:.10g} rad = {math.degrees(result.objective):.6g} deg (gamma_min)",
        f"r3 = {result.params['r3']:.6g} m",
        f"{q['peak_accel']:.6g} m/s^2 at omega2 = 1 rad/s",
        "by enumeration: eqs. (7)-(13) give every r3 for the TR; r5 = stroke/2",
        f'local optima</th><td style="text-align:left;padding:1px 4px">{len(result.local_optima)}<',
    ):
        assert text in html, text
    joints_meet_links(svgs(html)[0])
    cw = dataclasses.replace(result, counterweight=Counterweight(2.5, 0.05, math.pi))._repr_html_()
    assert "2.5 kg at 0.05 m, 180 deg from the crank pin" in cw
    failed = Result(status="failed", message=EVIL)._repr_html_()
    assert failed.count("<svg") == 0 and ">failed</span>" in failed
    escaped(failed)


def test_comparison(comparison):
    html = comparison._repr_html_()
    self_contained(html, 60_000)
    rows = comparison.rows
    assert [r.type for r in rows] == ["crank-shaper", "slider-crank"]
    body = re.findall(r"<tr>(.*?)</tr>", html)[1:]
    for k, r in enumerate(rows):
        cells = re.findall(r"<td[^>]*>(.*?)</td>", body[k])
        assert cells[:4] == [str(k + 1), r.type, "optimal", f"{math.degrees(r.criteria['gamma_min']):.4g}"]
        assert cells[5] == f"{r.criteria['peak_accel']:.4g}"
    assert rows[1].criteria["gamma_min"] == pytest.approx(math.radians(27.46), abs=1e-4)  # README's table
    assert html.count("<svg") == len(rows)
    for root in svgs(html):
        joints_meet_links(root)
    bad = dataclasses.replace(rows[1], type=EVIL, result=Result(status="infeasible", message="none"), reason=EVIL)
    shown = dataclasses.replace(comparison, rows=(rows[0], bad))._repr_html_()
    escaped(shown)
    assert shown.count("<svg") == 1  # a row without a design has no picture


def test_front(front):
    html = front._repr_html_()
    self_contained(html, 40_000)
    escaped(html)
    assert "gamma_min [deg]</text>" in html and "sum [m]</text>" in html  # axes with units
    for va, vb in front.values:
        assert f'<td style="padding:1px 6px;border-bottom:1px solid #ddd;text-align:right">{math.degrees(va):.6g}<' in (
            html
        )
        assert f">{vb:.6g}<" in html
    assert front.values[0][0] == pytest.approx(0.76047, abs=1e-5)  # README's end of the front
    (root,) = svgs(html)
    assert len([c for c in root.iter(f"{SVG}circle")]) == len(front.points)


def test_chart(chart):
    html = chart._repr_html_()
    self_contained(html, 40_000)
    escaped(html)
    assert "swing [deg]</text>" in html and "time ratio</text>" in html and "best gamma_min [deg]" in html
    g = chart.grid()
    assert g[0, 0] == pytest.approx(0.519395, abs=1e-6)  # README's cell
    for c in chart.cells:
        assert f">{math.degrees(g[c.j, c.i]):.6g}<" in html
    (root,) = svgs(html)
    cells = [r for r in root.iter(f"{SVG}rect") if r.find(f"{SVG}title") is not None]
    assert len(cells) == len(chart.cells)
    tip = f"time ratio 1.5, swing [deg] 60: best gamma_min [deg] {math.degrees(g[0, 0]):.5g}"  # 29.759
    assert tip in [r.find(f"{SVG}title").text for r in cells]


def test_a_long_table_shows_its_first_rows():
    ch5 = qropt.chart(
        chart_problem(), ("time_ratio", [1.4, 1.5, 1.6, 1.7, 1.8]), ("r1", [0.8, 0.9, 1.0, 1.1, 1.2])
    )  # 25 cells
    html = ch5._repr_html_()
    self_contained(html, 40_000)
    assert f"... {25 - MAX_ROWS} more (of 25)" in html
    assert "r1 [m]</text>" in html


def test_family(fam):
    html = fam._repr_html_()
    self_contained(html, 40_000)
    escaped(html)
    assert "r1 [m]</text>" in html and "r3 [m]</text>" in html
    (fold,) = fam.folds
    assert fold["r1"] == pytest.approx(0.11069804738, abs=1e-10)  # README's fold
    assert f"fold 1: r1 = {fold['r1']:.6g} m" in html
    n = len(fam.points())
    assert f"{MAX_ROWS} of {n} points" in html
    for e in fam.ends:
        assert html_escape(e.reason[:60]) in html
    first = fam.points()[0]
    assert f">{first.params['r3']:.6g}<" in html
    (root,) = svgs(html)
    assert root.find(f"{SVG}polyline") is not None


def test_the_explorer_needs_its_extra_and_shows_why_parameters_fail(monkeypatch):
    from qropt.errors import QroptError
    from qropt.io.explorer import MissingExtra, explore, view

    monkeypatch.setitem(sys.modules, "ipywidgets", None)  # as if not installed
    with pytest.raises(MissingExtra, match=re.escape('pip install "qropt[notebook]"')):
        explore(paper_mechanism())
    assert issubclass(MissingExtra, QroptError)
    with pytest.raises(QroptError, match="mechanism"):
        explore("DragLinkSlider")
    m = paper_mechanism()
    assert view(type(m), dict(m.params), "m") == m._repr_html_()
    bad = view(type(m), {**m.params, "r3": 0.01}, "m")  # not a drag-link: the message, escaped, no picture
    assert "drag-link (r1 shortest, s + l &lt;= p + q)" in bad and "<svg" not in bad


def test_the_explorer_follows_its_sliders():
    pytest.importorskip("ipywidgets")  # the test extra installs it
    from qropt import DragLinkSlider
    from qropt.io.explorer import explore

    m = paper_mechanism()
    box = explore(m)
    sliders = {s.description.split()[0]: s for s in box.children[:-1]}
    assert set(sliders) == {"r1", "r2", "r3", "r4", "r5", "r6", "h"}  # the branch signs have no slider
    out = box.children[-1]

    def shown(tr):  # the time ratio as the view shows it
        return f">{tr:.6g} (slow / fast)<"

    assert shown(m.time_ratio()) in out.value
    sliders["r3"].value = 0.3
    moved = DragLinkSlider(**{**m.params, "r3": 0.3})
    assert shown(moved.time_ratio()) in out.value and shown(m.time_ratio()) not in out.value
    sliders["r3"].value = sliders["r3"].min  # no drag-link any more: the page says why
    assert "<svg" not in out.value and "drag-link" in out.value
