"""Classroom projects (``qropt project``): solvable per seed, checked by an independent brute-force simulation, the
polygons agreeing with the exact analysis, deterministic pages, and the command line's outputs and errors."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from qropt import InvalidParameter, cli
from qropt.classroom import project, render
from tests import brute

CASES = [("whitworth", 7), ("drag-link-slider", 3), ("crank-shaper", 2)]
GRID = 2 * np.pi * np.arange(400_000) / 400_000  # step 1.6e-5 rad


@pytest.fixture(scope="module")
def projects():
    return {kind: project(kind, seed) for kind, seed in CASES}


def brute_task(kind, params) -> tuple[float, float]:
    """(TR, stroke) from the extreme slider positions over a fine crank grid (plain formulas of tests/brute.py)."""
    x = np.real(brute.output(kind, dict(params), GRID))
    i, k = int(np.argmax(x)), int(np.argmin(x))
    a = (GRID[k] - GRID[i]) % (2 * np.pi)
    return max(a, 2 * np.pi - a) / min(a, 2 * np.pi - a), float(x[i] - x[k])


@pytest.mark.parametrize(("kind", "seed"), CASES)
def test_the_solution_meets_the_task_by_brute_force(projects, kind, seed):
    p = projects[kind]
    assert p.kind == kind and p.seed == seed and p.result.status == "optimal"
    params = p.mechanism.params
    assert all(params[k] == v for k, v in p.given.items())  # the given links stayed
    tr, stroke = brute_task(kind, params)
    assert tr == pytest.approx(p.time_ratio, rel=2e-4)
    assert stroke == pytest.approx(p.stroke, rel=1e-6)
    assert math.degrees(p.mechanism.gamma_min().value) >= 15
    # the check can fail: a link 1 % off misses the stroke
    off = {**params, p.find[-1]: params[p.find[-1]] * 1.01}
    assert abs(brute_task(kind, off)[1] - p.stroke) > 1e-3 * p.stroke


@pytest.mark.parametrize(("kind", "seed"), CASES)
def test_the_polygons_equal_the_computer(projects, kind, seed):
    p = projects[kind]
    (vp, ap), (vc, ac) = p.polygon_ram(), p.computer_ram()
    scale = p.omega2 * p.stroke
    assert vp == pytest.approx(vc, abs=1e-9 * scale) and ap == pytest.approx(ac, abs=1e-9 * scale * p.omega2)
    assert abs(vc) + abs(ac) > 0
    for e in p.relative_motion().equations:
        assert e.residual <= 1e-9 * scale * p.omega2


@pytest.mark.parametrize(("kind", "seed"), CASES)
def test_requirement_2_covers_the_band(projects, kind, seed):
    p = projects[kind]
    lo, hi = p.adjust.interval
    trs = [p.reach._tr_at(x) for x in (lo, hi)]
    assert sorted(trs) == pytest.approx(list(p.band), rel=1e-8)
    assert p.reach.time_ratio_range.low <= p.time_ratio <= p.reach.time_ratio_range.high


def test_different_seeds_give_different_tasks():
    for kind in ("crank-shaper", "slider-crank"):
        tasks = [project(kind, s) for s in range(3)]
        keys = {(t.time_ratio, t.stroke, tuple(t.given.values()), t.theta2, t.omega2) for t in tasks}
        assert len(keys) == 3


def test_the_same_seed_gives_the_same_page(projects):
    p = projects["crank-shaper"]
    again = project("crank-shaper", 2)
    assert render(again) == render(p)
    assert render(again, solution=True) == render(p, solution=True)


def test_the_statement_hides_the_solution_and_the_solution_shows_it(projects):
    p = projects["drag-link-slider"]
    statement, solution = render(p), render(p, solution=True)
    body = statement[statement.index("<body>") : statement.index("</body>")]
    assert body in solution  # the statement, then its solution
    assert "Worked solution" not in statement and "Worked solution" in solution
    r3 = f"{p.mechanism.params['r3']:.6g}"
    assert r3 not in statement and r3 in solution
    v, a = p.computer_ram()
    assert f"{v:.6g}" in solution and f"{a:.6g}" in solution
    assert f"{p.time_ratio:.3f}" in statement and f"{p.stroke:.4f}" in statement
    sources = re.findall(r'(?:src|href)="([^"]*)"', solution)
    assert len(sources) >= 4 and all(s.startswith("data:image/png;base64,") for s in sources)


def test_bad_project_arguments():
    with pytest.raises(InvalidParameter, match="unknown project type"):
        project("coupler-slider", 0)
    with pytest.raises(InvalidParameter, match="seed"):
        project("whitworth", -1)
    with pytest.raises(InvalidParameter):
        render("not a project")


def test_the_command_writes_the_page_and_the_solution(tmp_path, capsys):
    page = tmp_path / "project.html"
    assert cli.main(["project", "--type", "crank-shaper", "--seed", "2", "-o", str(page)]) == 0
    assert page.read_text() == render(project("crank-shaper", 2))
    sol = tmp_path / "solution.html"
    assert cli.main(["project", "--type", "crank-shaper", "--seed", "2", "--solution", "-o", str(sol)]) == 0
    assert "Worked solution" in sol.read_text()
    out = capsys.readouterr().out.splitlines()
    assert len(out) == 2 and str(page) in out[0] and str(sol) in out[1]


def test_a_class_set(tmp_path, capsys):
    folder = tmp_path / "class"
    assert cli.main(["project", "--type", "slot-ram-shaper", "--seed", "5", "--count", "3", "-o", str(folder)]) == 0
    files = sorted(f.name for f in folder.iterdir())
    assert files == ["slot-ram-shaper-5.html", "slot-ram-shaper-6.html", "slot-ram-shaper-7.html"]
    assert len(capsys.readouterr().out.splitlines()) == 3


@pytest.mark.parametrize(
    "argv",
    [
        ["--type", "four-bar"],
        ["--type", "nope"],
        ["--count", "-1"],
        ["--count", "0"],
        ["--count", "501"],
        ["--seed", "-3"],
        ["--seed", "x"],
        ["-o", "{tmp}/missing/p.html"],
        ["-o", "{tmp}/p.txt"],
        ["--count", "2", "-o", "{tmp}/set.html"],
        ["--count", "2", "-o", "{tmp}/missing/deeper"],
    ],
)
def test_bad_input_is_one_line_and_a_nonzero_exit(argv, tmp_path, capsys):
    argv = [a.replace("{tmp}", str(tmp_path)) for a in argv]
    assert cli.main(["project", *argv]) != 0
    err = capsys.readouterr().err.strip()
    assert err and len(err.splitlines()) == 1
    assert not list(tmp_path.rglob("*.html"))
