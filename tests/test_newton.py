"""Continuation by Newton on a neighbour's active set (``qropt.synthesis.newton``): the KKT function's derivatives
against finite differences, the continued optimum against an independent IPOPT solve of the same problem, a hint
that does not fit (another active set, another formulation) falling back to IPOPT with the same answer, and the
hint's life (it never leaves the process with its formulation)."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

import qropt
from problems import chart_crank_rocker as cr
from qropt.studies._chart import Axis, axis_kind, problem_at
from qropt.synthesis import newton
from qropt.synthesis.settings import Settings
from qropt.synthesis.solver import Solver

NEWTON = "Newton on the neighbour's active set"


@pytest.fixture(scope="module")
def row():
    """Problems along one line of the crank-rocker chart (TR 1.05 to 3 at a rocker swing of 60 deg)."""
    p = cr.build()
    axes = [Axis(n, tuple(v), axis_kind(p, n)) for n, v in (cr.X, cr.Y)]
    return p, [problem_at(p, axes, [x, cr.Y[1][5]]) for x in cr.X[1]]


def _warm(solver, problem, prev, free, **kw):
    start = {k: prev.params[k] for k in free}
    return solver.solve(problem, starts_n=0, use_analytic=False, extra_starts=[start], diagnose=False, **kw)


def test_the_kkt_functions_derivatives_are_the_finite_differences(row):
    """The gradient, the rows' Jacobian and the Lagrangian's Hessian Newton uses, at a certified optimum's NLP
    point with random multipliers, against central differences of the objective and rows (step 1e-6)."""
    p, problems = row
    solver = Solver()  # kept: a hint holds its formulation weakly (the Solver owns it)
    r = solver.solve(problems[3])
    h = r.continuation
    form = h.form
    pv = form.param_vector(problems[3], problems[3].targets, h.blocks["samples"], h.blocks["fractions"])
    lam = np.random.default_rng(1).normal(size=h.lam_g.size)
    fun = newton._functions(form, Settings().newton_size)
    f, df, g, J, H = newton._evaluate(fun, h.w, pv, lam)
    step = 1e-6
    for i in range(h.w.size):
        e = np.zeros(h.w.size)
        e[i] = step
        fp, dfp, gp, Jp, _ = newton._evaluate(fun, h.w + e, pv, lam)
        fm, dfm, gm, Jm, _ = newton._evaluate(fun, h.w - e, pv, lam)
        assert df[i] == pytest.approx((fp - fm) / (2 * step), rel=1e-6, abs=1e-7)
        assert J[:, i] == pytest.approx((gp - gm) / (2 * step), rel=1e-6, abs=1e-7)
        grad_l = lambda d, jac: d + jac.T @ lam  # noqa: E731
        assert H[:, i] == pytest.approx((grad_l(dfp, Jp) - grad_l(dfm, Jm)) / (2 * step), rel=1e-5, abs=1e-6)


def test_a_continued_optimum_is_the_independent_solves(row):
    """Along the line, each problem solved from its neighbour's Result (``continue_from``) ends by Newton on the
    neighbour's active set, certified, at the design an independent default solve finds (objective to 1e-9,
    parameters to 1e-7)."""
    p, problems = row
    solver = Solver()
    prev = solver.solve(problems[0])
    used = 0
    for q in problems[1:12]:
        r = _warm(solver, q, prev, p.free, continue_from=prev)
        assert r.status == "optimal", r.message
        used += r.certificate.local == NEWTON
        ref = Solver().solve(q)
        assert r.objective == pytest.approx(ref.objective, rel=1e-9)
        for k in p.free:
            assert r.params[k] == pytest.approx(ref.params[k], rel=1e-7, abs=1e-9)
        assert r.quantities["time_ratio"] == pytest.approx(q.targets["time_ratio"], rel=1e-10)
        prev = r
    assert used == 11  # every step continued by Newton


def test_a_hint_that_does_not_fit_falls_back_to_ipopt(row):
    """A neighbour far away (TR 1.05 continued to 2.55: Newton from there is not verified) and a hint of another
    design (not tried): IPOPT runs, and the answer is the independent solve's."""
    p, problems = row
    solver = Solver()
    far = solver.solve(problems[0])
    r = _warm(solver, problems[30], far, p.free, continue_from=far)
    ref = Solver().solve(problems[30])
    assert r.status == "optimal" and r.certificate.local != NEWTON
    assert r.objective == pytest.approx(ref.objective, rel=1e-9)
    near = solver.solve(problems[29])
    other = _warm(solver, problems[30], far, p.free, continue_from=near)  # a start that is not the hint's design
    assert other.certificate.local != NEWTON
    assert other.objective == pytest.approx(ref.objective, rel=1e-9)


def test_a_corrupted_active_set_is_not_verified(row):
    """Newton from a hint whose multipliers are flipped (each held inequality on its other side) does not return a
    point: every returned run is a verified strict local minimum."""
    p, problems = row
    solver = Solver()
    r = solver.solve(problems[4])
    h = r.continuation
    form = h.form
    pv = form.param_vector(problems[5], problems[5].targets, h.blocks["samples"], h.blocks["fractions"])
    lbx, ubx = form.bounds(problems[5])
    assert newton.correct(form, h, pv, lbx, ubx) is not None
    inequality = form.lbg != form.ubg
    flipped = newton.Hint(h.values, h.w, np.where(inequality, -h.lam_g, h.lam_g), h.lam_x, h.blocks, h.used, form)
    assert np.any(inequality & (h.lam_g != 0))
    assert newton.correct(form, flipped, pv, lbx, ubx) is None


def test_a_hint_stays_in_its_process(row):
    """A Result pickles with its hint's numbers but not its formulation: a hint that crossed a process boundary
    fits no formulation; continue_from takes a Result only."""
    p, problems = row
    solver = Solver()  # kept: a hint holds its formulation weakly (the Solver owns it)
    r = solver.solve(problems[2])
    h = pickle.loads(pickle.dumps(r.continuation))
    assert h.form is None and not h.fits(r.continuation.form, {k: r.params[k] for k in p.free})
    assert np.array_equal(h.w, r.continuation.w)
    with pytest.raises(qropt.ProblemError, match="continue_from"):
        _warm(Solver(), problems[3], r, p.free, continue_from={"r2": 0.1})
