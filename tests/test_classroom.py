"""Classroom projects (``qropt project``): solvable per seed, checked by an independent brute-force simulation, the
polygons agreeing with the exact analysis, deterministic pages, a statement that names no seed (a code keyed by the
instructor's secret), the class set's key leading to each solution, the printed page (margins, deliverables,
marks, blanks), the existing mechanism's figure (labels apart, a sensible frame), and the command line's outputs
and errors."""

from __future__ import annotations

import csv
import math
import re

import numpy as np
import pytest

from qropt import InvalidParameter, cli
from qropt.classroom import project, render
from qropt.classroom.project import MARKS, headline, statement_code
from tests import brute

SECRET = "correct horse battery"

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


def without_pictures(page: str) -> str:
    return re.sub(r"data:image/png;base64,[A-Za-z0-9+/=]+", "", page)


def test_the_statement_names_no_seed(projects):
    seed = 4321
    keyed = project("crank-shaper", seed, SECRET)
    for p in (keyed, projects["whitworth"]):  # a class's statement and an open one
        page = without_pictures(render(p, due="2027-01-15"))
        assert not re.search(r"seed|default_rng|rng|redraw", page, re.I)
        assert "<!--" not in page
        assert re.fullmatch(r"[A-Z2-7]{4}-[A-Z2-7]{4}", p.code) and p.code in page
        assert p.code.replace("-", "") != str(p.seed)
    assert not re.search(rf"(?<![\d.]){seed}(?![\d])", without_pictures(render(keyed)))
    # the seed's digits are on the worked solution (the marker's page), with the code
    solution = render(keyed, solution=True)
    assert f"seed {seed}" in solution and keyed.code in solution


def test_a_secret_keys_the_draws_and_the_codes():
    open_, keyed = project("crank-shaper", 4), project("crank-shaper", 4, SECRET)
    other = project("crank-shaper", 4, SECRET + "!")
    # without the secret, trying seeds finds neither the task nor the code
    tasks = {(p.time_ratio, p.stroke, tuple(p.given.values())) for p in (open_, keyed, other)}
    assert len(tasks) == 3 and len({open_.code, keyed.code, other.code}) == 3
    assert keyed.code == statement_code("crank-shaper", 4, SECRET) == project("crank-shaper", 4, SECRET).code
    assert render(project("crank-shaper", 4, SECRET)) == render(keyed)
    for bad in ("short", "  padded secret", b"bytes secret", 12345678):
        with pytest.raises(InvalidParameter, match="secret"):
            project("crank-shaper", 4, bad)


def test_the_printed_page(projects):
    p = projects["whitworth"]
    page = render(p, due="2027-01-15")
    assert "@page{size:A4;margin:18mm}" in page
    assert "break-inside:avoid" in page and "@media print" in page
    assert "Due</th><td>2027-01-15" in page and "Name</th>" in page and "Student number</th>" in page
    assert "Due</th><td><span class=blank>" in render(p)  # no date: a blank to write it in
    assert "<h2>Deliverables</h2>" in page and "<h2>Marks</h2>" in page
    total = sum(m for *_, m in MARKS)
    assert total == 100 and f"<th>Total</th><th></th><th>{total}</th>" in page
    for part, _, marks in MARKS:
        assert f"<td>{part}</td>" in page and f"<td>{marks}</td>" in page
    with pytest.raises(InvalidParameter, match="YYYY-MM-DD"):
        render(p, due="next Friday")


@pytest.mark.parametrize(("kind", "seed"), [("whitworth", 11), ("slider-crank", 11), ("drag-link-slider", 11)])
def test_the_figure_has_its_labels_apart_and_a_sensible_frame(kind, seed):
    from qropt.classroom.project import MAX_ASPECT, MIN_ASPECT, _current_figure
    from qropt.io import plots

    fig = _current_figure(project(kind, seed))
    try:
        ax = fig.axes[0]
        (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
        assert MIN_ASPECT - 1e-9 <= (y1 - y0) / (x1 - x0) <= MAX_ASPECT + 1e-9
        w, h = fig.get_size_inches()
        assert 0.4 <= h / w <= 1.0
        fig.canvas.draw()
        renderer = fig.canvas.get_renderer()
        boxes = [t.get_window_extent(renderer) for t in ax.texts]
        assert len(boxes) >= 3  # O2, A and C at least
        for i, a in enumerate(boxes):
            for b in boxes[i + 1 :]:
                assert not a.overlaps(b), [t.get_text() for t in ax.texts]
    finally:
        plots.plt.close(fig)


def read_key(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def test_a_class_set_and_its_key(tmp_path, capsys):
    folder = tmp_path / "class"
    argv = ["project", "--type", "slot-ram-shaper", "--seed", "5", "--count", "3", "-o", str(folder)]
    assert cli.main([*argv, "--secret", SECRET, "--due", "2027-01-15", "--solution"]) == 0
    rows = read_key(folder / "key.csv")
    assert [int(r["seed"]) for r in rows] == [5, 6, 7] and {r["secret"] for r in rows} == {SECRET}
    names = {r["file"] for r in rows} | {r["solution_file"] for r in rows} | {"key.csv"}
    assert sorted(f.name for f in folder.iterdir()) == sorted(names)
    for r in rows:
        assert r["file"] == f"slot-ram-shaper-{r['code']}.html" and r["code"] != r["seed"]
        statement = (folder / r["file"]).read_text()
        assert r["code"] in statement and "2027-01-15" in statement
        assert not re.search(r"seed", without_pictures(statement), re.I)
        # the key's row leads to the solution: the project drawn again from it has the row's task and numbers
        p = project(r["type"], int(r["seed"]), r["secret"])
        assert p.code == r["code"] and f"{p.time_ratio:.3f}" in statement and f"{p.stroke:.4f}" in statement
        assert float(r["time_ratio"]) == p.time_ratio and float(r["stroke"]) == p.stroke
        for k, v in headline(p).items():
            assert float(r[k]) == pytest.approx(v, rel=1e-9, abs=1e-12)
        solution = (folder / r["solution_file"]).read_text()
        assert solution == render(p, solution=True, due="2027-01-15")
        assert f"{p.mechanism.params['r2']:.6g}" in solution and f"seed {r['seed']}" in solution
        assert r["solution_command"].endswith(f"--solution -o {r['solution_file']}")
    out = capsys.readouterr().out.splitlines()
    assert len(out) == 7 and "key written to" in out[-1]


def test_a_class_set_makes_its_own_secret(tmp_path, capsys):
    folder = tmp_path / "class"
    assert cli.main(["project", "--type", "crank-shaper", "--seed", "1", "--count", "2", "-o", str(folder)]) == 0
    rows = read_key(folder / "key.csv")
    assert len(rows) == 2 and len(rows[0]["secret"]) >= 20 and rows[0]["secret"] == rows[1]["secret"]
    assert sorted(f.name for f in folder.iterdir()) == sorted([r["file"] for r in rows] + ["key.csv"])
    p = project("crank-shaper", 1, rows[0]["secret"])
    assert (folder / rows[0]["file"]).read_text() == render(p)
    # the secret from the key writes the solutions later, the statements unchanged
    again = ["project", "--type", "crank-shaper", "--seed", "1", "--count", "2", "-o", str(folder)]
    assert cli.main([*again, "--secret", rows[0]["secret"], "--solution"]) == 0
    assert read_key(folder / "key.csv") == rows
    assert (folder / rows[0]["solution_file"]).read_text() == render(p, solution=True)
    capsys.readouterr()


def test_one_statement_with_its_key(tmp_path, capsys):
    page, key = tmp_path / "project.html", tmp_path / "key.csv"
    argv = ["project", "--type", "whitworth", "--seed", "7", "-o", str(page), "--key", str(key)]
    assert cli.main(argv) == 0
    (row,) = read_key(key)
    assert row["file"] == "project.html" and row["solution_file"] == "project-solution.html"
    assert page.read_text() == render(project("whitworth", 7, row["secret"]))
    assert cli.main(["project", "--type", "whitworth", "--seed", "7", "-o", str(tmp_path / "open.html")]) == 0
    assert not (tmp_path / "open-key.csv").exists() and len(list(tmp_path.iterdir())) == 3  # no key unless asked
    capsys.readouterr()


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
        ["--count", "2", "-o", "{tmp}/set", "--due", "next Friday"],
        ["--due", "2027-02-30"],
        ["--count", "2", "-o", "{tmp}/set", "--secret", "short"],
        ["--secret", " padded secret"],
        ["--secret", ""],
        ["--key", "{tmp}/key.txt"],
        ["--count", "2", "-o", "{tmp}/set", "--key", "{tmp}/missing/key.csv"],
    ],
)
def test_bad_input_is_one_line_and_a_nonzero_exit(argv, tmp_path, capsys):
    argv = [a.replace("{tmp}", str(tmp_path)) for a in argv]
    assert cli.main(["project", *argv]) != 0
    err = capsys.readouterr().err.strip()
    assert err and len(err.splitlines()) == 1 and "Traceback" not in err
    assert not list(tmp_path.rglob("*.html")) and not list(tmp_path.rglob("*.csv"))
