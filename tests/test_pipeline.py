"""The search as a declared pipeline (``qropt.synthesis.search``): a strategy and a dynamic criterion of one's own in
one file each, a custom pipeline, results that do not depend on what ran before or on the order of the types, and
the structural checks (the Solver never calls its own solve; generic search code names no criterion)."""

from __future__ import annotations

import ast
import json
import math
import pathlib
import subprocess
import sys
import time
import types

import numpy as np
import pytest

import qropt
from benchmarks.tasks import LOADS, MASSES, OMEGA2
from qropt import ProblemError, Solver
from qropt.studies._design import TYPES, design, type_problem
from qropt.synthesis import criteria, minimax, search, starts
from qropt.synthesis.search import Settings, diagnosis
from qropt.synthesis.search.local_solves import LocalSolves
from tests.toy_strategy import GridStarts

ROOT = pathlib.Path(__file__).resolve().parent.parent
SYNTHESIS = ROOT / "qropt" / "synthesis"
KW = {"masses": MASSES, "loads": LOADS, "omega2": OMEGA2}


def test_a_strategy_in_one_file_runs_in_a_custom_pipeline():
    """``Solver(pipeline=...)``: the default pipeline with its starts phase replaced by the toy's grid starts and
    the local solves. The solve is certified from the grid's starts alone (no closed forms, no atlas, no Sobol
    points: the Result's stats name the strategies that ran) and reaches the default solve's optimum."""
    problem = type_problem("slider-crank", 1.6, 0.3)
    default = Solver().solve(problem)
    phase = search.Phase((GridStarts(), LocalSolves()))
    custom = [phase if isinstance(s, search.Phase) else s for s in search.DEFAULT]
    r = Solver(pipeline=custom, atlas=False).solve(problem, use_analytic=False)
    assert default.status == r.status == "optimal", r.message
    assert r.stats["origin"] == "grid"
    assert "grid starts" in r.stats["strategies"] and "Sobol multi-start" not in r.stats["strategies"]
    assert r.objective == pytest.approx(default.objective, rel=1e-9)
    m = r.mechanism
    assert (m.time_ratio(), m.stroke()) == pytest.approx((1.6, 0.3), rel=1e-9)


def test_a_pipeline_is_a_list_of_strategies_and_must_make_a_result():
    with pytest.raises(ProblemError, match="pipeline is a list of strategies"):
        Solver(pipeline="fast")
    with pytest.raises(ProblemError, match="accepts"):
        Solver(pipeline=[object()])
    with pytest.raises(ProblemError, match="made no Result"):
        Solver(pipeline=[GridStarts()]).solve(type_problem("crank-shaper", 1.6, 0.3))
    with pytest.raises(ProblemError, match="positive int"):
        Settings(evolution_generations=0)
    with pytest.raises(ProblemError, match="Settings are"):
        Solver(settings={"no_such": 1})
    s = Solver(settings=Settings(thin=5))
    assert Solver(**s.options()).settings == s.settings  # a worker's Solver has the same settings


def _accepted(problem, plan) -> list[str]:
    return [s.name for s in (*search.DEFAULT, *search.STARTS) if s.accepts(problem, plan)]


def test_a_dynamic_criterion_in_one_file_gets_the_searches_the_shipped_ones_get():
    """A user's copy of the peak torque (tests/toy_dynamic_criterion.py): every strategy that accepts the shipped
    criterion's problem accepts its problem (the guarded multi-start, the evolution, the SQP on the exact peak among
    them), and a solve by it (a shortened evolution) gives the shipped criterion's row to the last bit."""
    from tests import toy_dynamic_criterion  # registers peak_drive_torque

    shipped = type_problem("crank-shaper-rod", 1.6, 0.3, objective="min_peak_torque", **KW)
    toy = type_problem("crank-shaper-rod", 1.6, 0.3, objective="min_" + toy_dynamic_criterion.DRIVE.name, **KW)
    plan = starts.plan(shipped, True, True)
    assert _accepted(toy, plan) == _accepted(shipped, plan)
    assert {"transmission guard", "differential evolution"} <= set(_accepted(toy, plan))
    assert minimax.applies(toy)
    short = Settings(evolution_generations=5, descent_evals=100)
    solver = Solver(starts_n=2, settings=short, evolutions=1)  # a short search, with the evolution
    a, b = solver.solve(shipped), solver.solve(toy)
    assert a.status == b.status and a.success, (a.message, b.message)
    assert b.objective == a.objective and b.params == a.params
    assert "transmission guard" in b.certificate.global_claim and "differential evolution" in b.message


def _rows(cmp) -> dict:
    return {r.type: [r.result.status, float(r.result.objective).hex(), dict(r.result.params)] for r in cmp.rows}


def test_a_design_is_the_same_in_a_fresh_process_after_other_solves_and_in_another_order():
    """``design(1.5, 0.3)``: the same rows, to the last bit, in a fresh process, in this one after other solves, and
    with the types asked for in reverse order."""
    code = (
        "import json, qropt; c = qropt.design(1.5, 0.3); print(json.dumps({r.type: [r.result.status, "
        "float(r.result.objective).hex(), dict(r.result.params)] for r in c.rows}))"
    )
    fresh = json.loads(subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout)
    qropt.design(2.0, 0.5)
    qropt.design(1.2, 0.1, objective="min_peak_accel")
    after = _rows(design(1.5, 0.3))
    backwards = _rows(design(1.5, 0.3, types=list(reversed(TYPES))))
    assert after == fresh
    assert backwards == fresh


def _functions(path):
    return [n for n in ast.walk(ast.parse(path.read_text())) if isinstance(n, ast.FunctionDef)]


def test_the_solver_never_calls_its_own_solve():
    """No module of the synthesis calls a Solver's ``solve`` (``self.solve``, ``solver.solve``): a strategy that
    needs another problem solved runs the pipeline through ``Context.sub``."""
    calls = []
    for path in SYNTHESIS.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "solve":
                receiver = ast.unparse(node.func.value)
                if receiver in ("self", "solver", "self.solver", "context.solver"):
                    calls.append(f"{path.name}:{node.lineno} {receiver}.solve")
    assert calls == []


GENERIC = ["search", "solver.py", "multistart.py", "starts.py", "local.py", "formulation.py", "backends.py"]
GENERIC += ["evolution.py", "descents.py", "minimax.py", "newton.py", "atlas.py"]


def test_no_criterion_name_in_generic_search_code():
    """The strategies read the criteria's capabilities (``guard``, ``quantity``, ``grid_value``), never a name: no
    string in the generic synthesis modules is a criterion's name, objective or bound."""
    names = {criteria.SIZE_OBJECTIVE}
    for c in criteria.CRITERIA.values():
        names |= {c.name, c.objective, c.bound}
    found = []
    for part in GENERIC:
        for path in [SYNTHESIS / part] if part.endswith(".py") else sorted((SYNTHESIS / part).glob("*.py")):
            for node in ast.walk(ast.parse(path.read_text())):
                if isinstance(node, ast.Constant) and isinstance(node.value, str) and node.value in names:
                    found.append(f"{path.name}:{node.lineno} {node.value!r}")
    assert found == []


def test_a_bound_beyond_its_own_optimum_ends_the_solve_before_its_starts():
    """The crank-rocker slider at TR 2.373 reaches a transmission angle of 14.63 deg at most (its max_gamma_min,
    which the atlas holds). By that criterion under a 30 deg bound the solve is infeasible before any start,
    in the diagnosis's words, which the pipeline without the check gives after its starts have failed; under a
    10 deg bound the check passes and the search runs."""
    from qropt.synthesis.search.reach import BoundsInReach

    p = type_problem("crank-rocker-slider", 2.373, 2.3207, objective="max_gamma_min", conditions={"gamma_min": 0.5236})
    quick = Solver().solve(p)
    assert quick.status == "infeasible" and "(14.63 deg)" in quick.message, quick.message
    assert quick.stats["strategies"] == ["plan", "bounds in reach"] and quick.stats["starts"] == 0
    without = Solver(starts_n=1, pipeline=[s for s in search.DEFAULT if not isinstance(s, BoundsInReach)])
    slow = without.solve(p)
    assert slow.status == "infeasible" and slow.message == quick.message
    assert "bounds in reach" not in slow.stats["strategies"] and slow.stats["starts"] > 0
    r = Solver(starts_n=1).solve(p.replace(conditions={"gamma_min": math.radians(10)}))
    assert r.status == "optimal" and r.mechanism.gamma_min().value >= math.radians(10) - 1e-9, r.message
    assert "bounds in reach" in r.stats["strategies"]  # passed: the search goes on (from the atlas without it)
    assert "without its bound gamma_min" in r.certificate.global_claim


def test_each_default_strategy_is_one_module_with_a_name():
    """One module per strategy in qropt/synthesis/search/, each strategy named, every name distinct."""
    stages = [*search.DEFAULT, *search.STARTS]
    named = [s for s in stages if not isinstance(s, search.Phase)]
    assert all(isinstance(s, search.Strategy) for s in stages)
    assert len({s.name for s in named}) == len(named) and all(s.name for s in named)
    by_module: dict = {}
    for s in named:
        by_module.setdefault(type(s).__module__, []).append(s.name)
    shared = {k: v for k, v in by_module.items() if len(v) > 1}
    assert shared == {"qropt.synthesis.search.diagnosis": ["failed", "diagnosis"]}  # the two ends of a failed solve


def test_a_time_limit_is_kept_and_the_claim_says_what_it_left_out():
    """``solve(..., time_limit=8)`` on a row that takes minutes (the coupler slider by peak torque): it returns
    within 10 % of the limit, with a design checked by exact evaluation or a failure that says so, and the claim
    names the strategies the limit left out (the evolution among them)."""
    p = type_problem("coupler-slider", 1.5, 0.3, objective="min_peak_torque", **KW)
    t = time.perf_counter()
    r = Solver().solve(p, time_limit=8.0)
    took = time.perf_counter() - t
    assert took <= 8.0 * 1.1, took
    assert "differential evolution" in r.stats["skipped"]
    assert "the time limit (8 s) left out: " in r.message
    if r.success:
        assert "differential evolution" in r.certificate.global_claim.split("left out: ")[1]
        assert (r.mechanism.time_ratio(), r.mechanism.stroke()) == pytest.approx((1.5, 0.3), rel=1e-8)
    else:
        assert r.status == "failed" and "within the time limit" in r.message


def test_a_time_limit_that_does_not_bind_changes_nothing():
    problem = type_problem("drag-link-slider", 1.8, 0.4)
    a, b = Solver().solve(problem), Solver().solve(problem, time_limit=600)
    assert (a.status, a.objective, a.params, a.message) == (b.status, b.objective, b.params, b.message)
    assert "skipped" not in b.stats
    assert _rows(design(1.5, 0.3, time_limit=600)) == _rows(design(1.5, 0.3))


@pytest.mark.parametrize("bad", [0, -1.0, math.nan, math.inf, "10", True])
def test_a_time_limit_is_a_positive_number_of_seconds(bad):
    with pytest.raises(ProblemError, match="time_limit"):
        Solver().solve(type_problem("slider-crank", 1.5, 0.3), time_limit=bad)
    with pytest.raises(ProblemError, match="time_limit"):
        design(1.5, 0.3, time_limit=bad)


def test_where_designs_exist_but_no_start_certifies_one_the_diagnosis_answers_by_descents():
    """The crank shaper with a rod by peak bearing force at TR 2.373, 2.3207 m under 30 deg: the NLP's optima lie
    beyond designs whose output turns back inside a stroke, so no start certifies one. The diagnosis's descents on
    the exact objective (one evolution, few generations here) give a ``feasible`` design, checked by exact analysis:
    the targets, the bound, and the peak bearing force against a dense grid of the inverse dynamics."""
    problem = type_problem(
        "crank-shaper-rod", 2.373, 2.3207, objective="min_peak_bearing_force", conditions={"gamma_min": 0.5236}, **KW
    )
    solver = Solver(
        settings=Settings(evolution_generations=2, evolution_population=4, evolution_keep=1, descent_evals=200)
    )
    context = search.Context(solver, dict(problem.targets), 8, 0, solver.max_rounds)
    r = diagnosis._descents(context, problem, [], "4 starts: why", lambda: {"t_total": 0.0})
    assert r.status == "feasible" and "(4 starts: why)" in r.message, r.message
    m = r.mechanism
    assert (m.time_ratio(), m.stroke()) == pytest.approx((2.373, 2.3207), rel=1e-9)
    assert m.gamma_min().value >= 0.5236 - 1e-9
    theta = np.linspace(0.0, 2 * np.pi, 20_001)
    d = m.dynamics(theta, OMEGA2, masses=MASSES, loads=LOADS)
    grid = max(np.hypot(*f.T).max() for k, f in d.joint_forces.items() if k != "slide")
    assert grid <= r.objective <= grid * (1 + 1e-4)
    assert r.stats["t_total"] == 0.0 and r.stats["origin"] == "descent"
    assert diagnosis._descents(context, problem, [], "", dict, evolved=True) is None  # the solve's own evolution ran
    assert diagnosis._descents(search.Context(Solver(evolution=False), {}, 8, 0, 5), problem, [], "", dict) is None


def test_a_failure_counts_its_starts_by_how_they_ended():
    """``diagnosis.reasons``: the commonest reasons first, each with its count, the design a reason names as 'its
    design' (so that the same reason at two designs is one)."""
    ends = [
        "CrankShaper(r1=1, r2=2) breaks: a crank-shaper needs crank r2 < centres r1",
        "CrankShaper(r1=3, r2=4) breaks: a crank-shaper needs crank r2 < centres r1",
        "the NLP's dead centres are local, not the global extremes",
        "",
        "CrankShaper(r1=5, r2=4): the output reverses 2 times a turn",
    ]
    cands = [
        types.SimpleNamespace(info={"reason": w}, statuses=["Maximum_Iterations_Exceeded"], converged=False)
        for w in ends
    ]
    tol = {"feasibility": 1e-9, "gap": 1e-9}
    open_ = {"ok": True, "gap": 1e-3}
    cands.append(types.SimpleNamespace(info=open_, statuses=["Solve_Succeeded"], converged=True, residuals={}))
    missed = {"time_ratio (exact)": 1e-3, "stroke (exact)": 0.0}
    cands.append(
        types.SimpleNamespace(info={"ok": True}, statuses=["Solve_Succeeded"], converged=True, residuals=missed)
    )
    assert diagnosis.reasons(cands, tol, shown=5) == (
        "2 starts: its design breaks: a crank-shaper needs crank r2 < centres r1; "
        "1 start: Maximum_Iterations_Exceeded; "
        "1 start: converged where the NLP's value and the exact one still differ (the exchange did not close); "
        "1 start: converged where time_ratio (exact) is not met; "
        "1 start: its design: the output reverses 2 times a turn"
    )
    assert diagnosis.reasons(cands, tol, shown=1) == (
        "2 starts: its design breaks: a crank-shaper needs crank r2 < centres r1"
    )
