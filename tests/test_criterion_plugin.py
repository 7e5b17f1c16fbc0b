"""A criterion added in one file (tests/toy_criterion.py) reaches every consumer: solve, design, pareto,
family.best, the CLI's choices and flags, and Result's repr and quantities."""

from __future__ import annotations

import numpy as np
import pytest

import qropt
from problems import _bases as problem_bases
from problems import _oracles as oracles
from qropt import cli
from qropt.synthesis import criteria
from tests import toy_criterion  # noqa: F401 - registers the criterion 'crank'


def test_the_criterion_is_registered_once_with_its_names():
    c = criteria.CRITERIA["crank"]
    assert (c.objective, c.bound, c.flag) == ("min_crank", "max_crank", "--max-crank")
    assert "min_crank" in criteria.objectives() and criteria.bounds()["max_crank"] is c
    with pytest.raises(qropt.ProblemError, match="clashes"):
        criteria.register(type(c)())


def smallest_crank(p):
    """Independent: along the slider-crank's closed-form family (r2 walks it), the smallest r2 that is a design."""
    family = oracles.slider_crank_family(1.3, 0.3)
    ok = [t for t in np.geomspace(0.05, 0.3, 400) if (d := family(t)) and oracles.score(p.replace(objective=None), d)]
    return min(ok)


def test_solve_minimises_it_and_the_result_reports_it():
    p = problem_bases.slider_crank(objective="min_crank")
    r = qropt.solve(p)
    assert r.status == "optimal" and r.objective == r.params["r2"] == r.quantities["crank"]
    least = smallest_crank(p)
    assert r.objective <= least * (1 + 1e-9) and r.objective == pytest.approx(least, rel=0.01)  # the scan's step
    assert "crank=" in repr(r) and "crank" in r.to_dict()["quantities"]


def test_its_bound_holds_exactly():
    p = problem_bases.slider_crank(objective="max_gamma_min")
    free = qropt.solve(p)
    cap = 0.5 * (free.params["r2"] + qropt.solve(p.replace(objective="min_crank")).objective)
    r = qropt.solve(p.replace(conditions={"max_crank": cap}))
    assert r.status == "optimal" and r.params["r2"] == pytest.approx(cap, rel=1e-9)  # active at the optimum
    assert r.objective < free.objective and r.residuals["max_crank bound (exact)"] <= 1e-12


def test_design_pareto_and_family_best_take_it():
    c = qropt.design(1.5, 0.3, objective="min_crank", types=["slider-crank", "crank-shaper"], bounds={"r2": (0.1, 1.5)})
    cranks = [row.criteria["crank"] for row in c.rows if row.success]
    assert len(cranks) == 2 and cranks == sorted(cranks)
    assert all(row.result.objective == row.criteria["crank"] for row in c.rows if row.success)
    kw = {"objective": "min_crank", "types": ["slider-crank", "crank-shaper"], "bounds": {"r2": (0.1, 1.5)}}
    assert [r.result.objective for r in qropt.design(1.5, 0.3, workers=2, **kw).rows] == [
        r.result.objective for r in c.rows
    ]  # worker processes know it too (a pool started before it was registered is started anew)
    front = qropt.pareto(problem_bases.slider_crank(), ("max_gamma_min", "min_crank"), n=3)
    assert front.criteria == ("gamma_min", "crank") and len(front.points) >= 2
    fam = qropt.family(problem_bases.slider_crank())
    best = fam.best("min_crank")
    assert best.status == "optimal"
    assert best.objective == pytest.approx(qropt.solve(problem_bases.slider_crank(objective="min_crank")).objective)


def test_the_cli_offers_it(capsys):
    commands = cli.parser()._subparsers._group_actions[0].choices
    synth = {a.dest: a for a in commands["synth"]._actions}
    design = commands["design"]
    assert "min_crank" in synth["objective"].choices
    assert "min_crank" in {a.dest: a for a in design._actions}["objective"].choices
    assert "--max-crank" in design.format_help()
