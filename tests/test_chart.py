"""Design charts (qropt.chart): cells against independent searches (the classical crank-rocker construction swept
densely, the slider-crank's stroke triangle and a brute-force simulation), a 2-worker Dask LocalCluster against
the in-process chart, infeasible cells with their reasons, branch jumps and switches, and bad input."""

from __future__ import annotations

import csv
import importlib
import math
import time

import numpy as np
import pytest

from problems import _oracles as oracles
from qropt import Problem, Solver, solve
from qropt.cli import main
from qropt.errors import ChartError
from qropt.studies._chart import Cell, Chart
from qropt.studies._chart_run import chart
from qropt.studies._continuation import _Tile
from qropt.synthesis import analytic
from qropt.synthesis.solver import DEFAULT
from tests import brute

ROOT = __import__("pathlib").Path(__file__).resolve().parents[1]
TR = (1.2, 1.5, 1.8, 2.1)
SWING = tuple(math.radians(d) for d in (45, 60, 75))
SAME = ("status", "objective", "params", "method", "why", "source", "jump", "switched")


def problem(name):
    return importlib.import_module(f"problems.{name}").build()


@pytest.fixture(scope="module")
def rocker():
    """A 4 x 3 crank-rocker chart in tiles of 2 x 2 with a check at every other cell: continuation and checks."""
    return chart(
        problem("chart_crank_rocker"), ("time_ratio", TR), ("swing", SWING), tile=(2, 2), check=2, progress=False
    )


@pytest.fixture(scope="module")
def cluster():
    """A 2-worker LocalCluster (one thread each) for the whole file: its scheduler's address."""
    from distributed import LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0") as c:
        yield c.scheduler_address


def family_best(p, tr, swing):
    """The oracle: the classical construction (every design with this TR and swing) swept and refined."""
    cell = p.replace(targets={"time_ratio": tr, "swing": swing})

    def design(pos):
        d = analytic.crank_rocker_design(tr, swing, 1.0, pos)
        return None if d is None else {"r2": d.r2, "r3": d.r3, "r4": d.r4}

    return oracles.along(cell, design, 0.002, 0.498, n=300)["objective"]


def test_crank_rocker_chart_matches_the_classical_family(rocker):
    p = rocker.problem
    assert rocker.shape == (3, 4) and rocker.mask("certified").all()
    assert rocker.stats["continued"] > 0 and rocker.stats["full"] > 0  # both ways of solving a cell were used
    for i, j in ((0, 0), (1, 1), (2, 2), (3, 0), (3, 2)):
        c = rocker.cell(i, j)
        assert c.quantities["time_ratio"] == pytest.approx(TR[i], abs=1e-9)
        assert c.quantities["swing"] == pytest.approx(SWING[j], abs=1e-9)
        best = family_best(p, TR[i], SWING[j])
        assert c.objective >= best - 1e-9, (i, j, c)  # the oracle refines to 1e-13 along a family of every design
        assert c.objective == pytest.approx(best, abs=1e-7), (i, j, c)
    c = rocker.cell(2, 1)  # the transmission angle by an independent simulation of the four-bar
    assert brute.gamma_min("four-bar", {**c.params, "sigma": -1.0}) == pytest.approx(c.objective, abs=1e-8)


def test_grid_result_and_mask(rocker):
    g = rocker.grid()
    assert g.shape == (3, 4) and np.all(np.diff(g, axis=1) < 0)  # gamma_min falls with the time ratio
    assert np.allclose(rocker.grid("r3/r1"), rocker.grid("r3")) and np.allclose(rocker.grid("gamma_min"), g)
    r = rocker.result(1.5, math.radians(60))
    assert r.objective == g[1, 1] and r.params == rocker.cell(1, 1).params and r.mechanism is not None
    assert rocker.mask("continued").sum() + rocker.mask("full").sum() == 12
    for bad, words in (
        (lambda: rocker.grid("bogus"), "unknown chart quantity"),
        (lambda: rocker.result(1.55, SWING[0]), "not a chart value"),
        (lambda: rocker.result(1.5), "give the swing value"),
        (lambda: rocker.mask("odd"), "unknown chart flag"),
    ):
        with pytest.raises(ChartError, match=words):
            bad()


def test_a_chart_on_dask_workers_refuses_a_backend_they_would_not_have(rocker):
    """Workers build their Solvers from ``Solver.options()``: a backend given to the Solver would be dropped, so the
    chart says so before it starts a cluster."""
    from qropt.synthesis.backends import Ipopt, Scipy

    for solver in (Solver(backend=Scipy()), Solver(backend=Ipopt({"ipopt.max_iter": 100}))):
        with pytest.raises(ChartError, match="chart in this process"):
            chart(rocker.problem, ("time_ratio", TR), ("swing", SWING), progress=False, workers=2, solver=solver)


def test_local_cluster_gives_the_in_process_answers(rocker, cluster):
    far = chart(
        rocker.problem, ("time_ratio", TR), ("swing", SWING), tile=(2, 2), check=2, progress=False, scheduler=cluster
    )
    assert "Dask cluster" in far.stats["scheduler"] and far.stats["tiles"] == 4
    for a, b in zip(rocker.cells, far.cells, strict=True):
        assert [getattr(a, k) for k in SAME] == [getattr(b, k) for k in SAME]
    assert far.cell(3, 2).result.objective == rocker.cell(3, 2).objective  # rebuilt from the worker's dictionary


def test_local_cluster_of_workers_started_by_the_chart():
    p = problem("chart_crank_rocker")
    here = chart(p, ("time_ratio", (1.3, 1.4)), ("swing", SWING[:2]), progress=False)
    local = chart(p, ("time_ratio", (1.3, 1.4)), ("swing", SWING[:2]), workers=2, progress=False)
    assert local.stats["scheduler"] == "local cluster of 2 worker processes"
    for a, b in zip(here.cells, local.cells, strict=True):
        assert [getattr(a, k) for k in SAME] == [getattr(b, k) for k in SAME]


def _largest_time_ratio(r2, stroke):
    """The largest TR of an offset slider-crank with crank r2 and this stroke, written out independently: the
    dead centres are the extended and folded rod positions; r3 from the stroke by brentq for each offset e."""
    from scipy.optimize import brentq

    best = 1.0
    for e in np.linspace(0.0, 10.0, 4001)[1:]:

        def travel(r3, e=e):
            return math.sqrt((r3 + r2) ** 2 - e * e) - math.sqrt((r3 - r2) ** 2 - e * e) - stroke

        lo, hi = r2 + e + 1e-12, 1e4
        if travel(lo) < 0 or travel(hi) > 0:
            continue
        r3 = brentq(travel, lo, hi, xtol=1e-14)
        t_max, t_min = math.asin(e / (r3 + r2)), math.pi + math.asin(e / (r3 - r2))
        a = (t_min - t_max) % (2 * math.pi)
        best = max(best, max(a, 2 * math.pi - a) / min(a, 2 * math.pi - a))
    return best


def test_slider_crank_chart_is_the_closed_form_family(tmp_path):
    p = problem("chart_slider_crank")
    tr, crank = (1.2, 1.45, 1.7), (0.2, 0.32, 0.44)
    ch = chart(p, ("time_ratio", tr), ("r2", crank), progress=False)
    bad = ch.mask("infeasible")
    assert bad.tolist() == [[False, False, True], [False] * 3, [False] * 3]  # TR 1.7 is out of reach of r2 = 0.2
    c = ch.cell(2, 0)  # reported with its reason, never dropped
    assert c.status == "infeasible" and "no design: the closed form that gives every design" in c.message
    assert _largest_time_ratio(0.2, 1.0) < 1.7 < _largest_time_ratio(0.44, 1.0)  # independently: out of reach
    assert math.isnan(ch.grid()[0, 2]) and c.why == "closed form"
    for i, j in ((0, 0), (1, 1), (2, 2), (0, 2)):
        c = ch.cell(i, j)
        d = analytic.slider_crank_design(tr[i], 1.0, crank[j])[0]  # the stroke triangle, e > 0
        assert c.params["r3"] == pytest.approx(d.r3, rel=1e-10) and c.params["e"] == pytest.approx(d.e, rel=1e-10)
        t_max, t_min, x_max, x_min = brute.dead_centres("slider-crank", c.params)
        assert brute.time_ratio(t_max, t_min) == pytest.approx(tr[i], abs=1e-9)
        assert x_max - x_min == pytest.approx(1.0, abs=1e-9)
        assert brute.gamma_min("slider-crank", c.params) == pytest.approx(c.objective, abs=1e-8)
    family = oracles.slider_crank_family(1.45, 1.0)  # r2 walks every design of TR 1.45 and stroke 1
    free_crank = p.replace(fixed={}, free={**p.free, "r2": (0.2, 0.499)}, targets={"time_ratio": 1.45, "stroke": 1.0})
    best = oracles.along(free_crank, family, 0.2, 0.499)
    assert best["objective"] is not None
    assert np.nanmax(ch.grid()[:, 1]) <= best["objective"] + 1e-12  # the chart's column lies on that family
    ch.to_csv(tmp_path / "sc.csv")
    with open(tmp_path / "sc.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == 9 and rows[2]["status"] == "infeasible" and "closed form" in rows[2]["message"]


def test_a_jump_of_branch_is_flagged():
    """The smallest crank-rocker slider leaves one branch (r4 near 0.43) for another (r4 = 0.15) between TR 1.42
    and 1.39: continuing down from TR 1.43, IPOPT lands on the other branch, and the chart says so."""
    p = problem("crank_rocker_slider_size")
    tr = (1.43, 1.42, 1.39, 1.38)
    ch = chart(p, ("time_ratio", tr), progress=False)
    assert [c.jump for c in ch.cells] == [False, False, True, False]
    c = ch.cell(2)
    assert c.why == "jump" and c.needed_full and c.source == (1, 0) and c.method == "full"
    # independently: the default solve at each TR; r4 drops to its bound in one step between 1.42 and 1.39
    designs = [solve(p, targets={"time_ratio": t}) for t in tr]
    for k, r in enumerate(designs):
        assert ch.cell(k).objective == pytest.approx(r.objective, abs=1e-9)
    r4 = [r.params["r4"] for r in designs]
    assert r4[1] > 0.4 and r4[2] == pytest.approx(p.free["r4"][0], abs=1e-9)
    assert r4[1] - r4[2] > 10 * max(abs(r4[0] - r4[1]), abs(r4[2] - r4[3]))


def test_a_better_branch_taking_over_is_flagged():
    """A check cell whose neighbour holds the task's worse local optimum: continuing from it stays on that
    branch, the check's full solve finds the better one, and the cell keeps it and says so."""
    p = problem("crank_rocker_slider_gamma")
    worse = solve(p, targets={"stroke": 0.1093}).local_optima[1]
    assert worse.status == "local_optimum"
    tile = _Tile(
        {"problem": p.to_dict(), "x": ["stroke", [0.1093, 0.1]], "y": None, "block": [0, 2, 0, 1], "check": 1},
        DEFAULT,
        None,
    )
    tile.cells[(0, 0)] = Cell.of(0, 0, worse, "full")
    tile.solve_cell((1, 0))
    c = tile.cells[(1, 0)]
    assert c.switched and c.method == "full" and c.why == "check" and not c.jump
    best = solve(p, targets={"stroke": 0.1})
    assert c.objective == pytest.approx(best.objective, abs=1e-9)
    cont = solve(
        p, targets={"stroke": 0.1}, starts_n=0, use_analytic=False, extra_starts=[{k: worse.params[k] for k in p.free}]
    )
    assert cont.success and c.objective > cont.objective + 1e-5  # what continuing alone would have reported


def test_continuation_across_a_branch_takeover_ends_on_the_better_branch():
    """From stroke 0.1286 down, the better branch changes near 0.097: the chart's cell at 0.09 holds the full
    solve's optimum, reached through a flagged full solve (a jump or a check)."""
    p = problem("crank_rocker_slider_gamma")
    ch = chart(p, ("stroke", (0.1286, 0.1093, 0.09)), check=1, progress=False)
    c = ch.cell(2)
    assert c.method == "full" and c.why in ("jump", "check")
    assert c.objective == pytest.approx(solve(p, targets={"stroke": 0.09}).objective, abs=1e-9)


def test_cli_writes_the_chart(tmp_path, capsys):
    files = [tmp_path / n for n in ("c.png", "c.csv", "c.json")]
    args = [
        "chart",
        str(ROOT / "problems" / "chart_crank_rocker.py"),
        "--x",
        "time_ratio",
        "1.2:1.5:3",
        "--y",
        "swing",
        "50deg,60deg",
        "--plot",
        str(files[0]),
        "--csv",
        str(files[1]),
        "--json",
        str(files[2]),
    ]
    assert main(args) == 0
    out = capsys.readouterr().out
    assert "6 cells in" in out and "6 certified" in out and "best at time_ratio 1.2, swing 50" in out
    assert files[0].read_bytes()[:4] == b"\x89PNG"
    back = Chart.from_json(files[2])
    assert back.shape == (2, 3) and back.cell(1, 1).result.params == back.cell(1, 1).params
    assert back.grid()[0, 0] == pytest.approx(
        math.radians(float(out.split("objective ")[1].split("..")[1][:7])), abs=1e-5
    )


@pytest.mark.parametrize(
    "x, y, options, words",
    [
        (("bogus", (1.2, 1.3)), None, {}, "unknown chart axis 'bogus'"),
        (("r2", (0.2, 0.3)), None, {}, "'r2' is free in the problem"),
        (("time_ratio", (1.2,)), None, {}, "at least 2 values"),
        (("time_ratio", (1.2, 1.5, 1.4)), None, {}, "increasing or decreasing"),
        (("time_ratio", (0.5, 1.5)), None, {}, "time_ratio = 0.5 on the chart's axis"),
        (("time_ratio", (1.2, 1.5)), ("time_ratio", (1.2, 1.5)), {}, "both 'time_ratio'"),
        (("time_ratio", (1.2, 1.5)), None, {"workers": 0}, "workers must be an integer >= 1"),
        (("time_ratio", (1.2, 1.5)), None, {"workers": 1.5}, "workers must be an integer >= 1"),
        (("time_ratio", (1.2, 1.5)), None, {"scheduler": "tcp://h:1", "workers": 2}, "size of a local cluster"),
        (("time_ratio", (1.2, 1.5)), None, {"tile": (0, 2)}, "tile size must be"),
        (("time_ratio", (1.2, 1.5)), None, {"scheduler": 8786}, "scheduler is None, 'local'"),
    ],
)
def test_bad_input_raises_chart_errors(x, y, options, words):
    with pytest.raises(ChartError, match=words):
        chart(problem("chart_crank_rocker"), x, y, progress=False, **options)


def test_bad_input_is_one_line_on_the_command_line(capsys):
    file = str(ROOT / "problems" / "chart_crank_rocker.py")
    t = time.perf_counter()
    assert (
        main(["chart", file, "--x", "time_ratio", "1.2:1.5:3", "--y", "none", "--scheduler", "tcp://127.0.0.1:9"]) == 1
    )
    assert time.perf_counter() - t < 60  # it gives up (CONNECT_TIMEOUT 5 s) rather than hang
    for args, code in (
        (["--x", "stroke", "1:2:3"], 1),
        (["--x", "time_ratio", "1:2"], 2),
        (["--x", "time_ratio", "1.2:1.5:3", "--workers", "0"], 1),
        (["--y", "swing"], 2),
    ):
        assert main(["chart", file, *args]) == code
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 5 and "cannot reach the Dask scheduler" in err[0] and "unknown chart axis 'stroke'" in err[1]
    assert all(line.startswith("qropt:") for line in err)


def test_a_problem_is_required():
    with pytest.raises(ChartError, match="chart takes a qropt.Problem"):
        chart({"mechanism": "FourBar"}, ("time_ratio", (1.2, 1.3)))
    assert isinstance(problem("chart_slider_crank"), Problem)
