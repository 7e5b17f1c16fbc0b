"""Designs on the targets without the NLP (``qropt.synthesis.evolution``): the evolution's designs lie on the
targets, its root search meets the TR exactly, and its descent on the exact objective reaches the optimum the
solver certifies by another route."""

from __future__ import annotations

import math

import numpy as np
import pytest

from benchmarks.tasks import LOADS, MASSES, OMEGA2
from qropt import solve
from qropt.studies._design import type_problem
from qropt.synthesis import descents, evolution
from qropt.synthesis.criteria import objective_of
from qropt.synthesis.search import Settings
from qropt.synthesis.search.descended import descended

SHORT = Settings(evolution_generations=20, descent_evals=200)  # a short evolution, short descents
FEW = Settings(evolution_generations=10, descent_evals=100)  # shorter still

KW = {"objective": "min_peak_torque", "masses": MASSES, "loads": LOADS, "omega2": OMEGA2}


def _exact(problem, d):
    m = problem.build(d, {k: b[0] for k, b in problem.branches.items()})
    return m.time_ratio(), m.stroke(), objective_of(problem, m)


def test_the_evolution_hands_on_designs_on_the_targets():
    """Each design within the TR window, at the stroke, inside the box, best first by the exact objective; the
    root search meets the TR to 1e-12; the descent stays on the targets, ends no worse than where it began and
    reaches the design the solver's family walk certifies (the slider-crank by peak torque: its least lies on a
    one-parameter family, which the evolution does not use)."""
    problem = type_problem("slider-crank", 1.3, 0.2, **KW)
    assert evolution.applies(problem)
    found = evolution.evolve(problem, 20, seed=3, keep=3)
    assert found
    values = []
    for d in found:
        tr, stroke, v = _exact(problem, d)
        assert abs(math.log(tr / 1.3)) <= Settings().evolution_window
        assert stroke == pytest.approx(0.2, rel=1e-12)
        assert evolution.outside(problem, d) == 0.0
        values.append(v)
    assert values == sorted(values)
    on = evolution.on_targets(problem, found[0])
    tr, stroke, start = _exact(problem, on)
    assert tr == pytest.approx(1.3, rel=1e-12) and stroke == pytest.approx(0.2, rel=1e-12)
    value, d = evolution.descend(problem, on, evals=200)
    tr, stroke, v = _exact(problem, d)
    assert tr == pytest.approx(1.3, rel=1e-12) and stroke == pytest.approx(0.2, rel=1e-12)
    assert v == pytest.approx(value, rel=1e-12) and v <= start
    # two routes to one optimum: the family walk's certified design and the descent on the exact objective
    assert v == pytest.approx(solve(problem).objective, rel=1e-8)


def test_what_the_evolution_needs():
    """A TR and a stroke target, a free crank and free scale; a fixed length stops it."""
    problem = type_problem("drag-link-slider", 1.5, 0.3, **KW)
    assert evolution.applies(problem)
    fixed = problem.replace(fixed={"r1": 0.1}, free={k: v for k, v in problem.free.items() if k != "r1"})
    assert not evolution.applies(fixed)


def test_a_solve_without_a_design_from_its_passes_starts_from_descents():
    """Where neither the multi-start nor its guarded pass certifies a design (here: no Sobol starts and no closed
    forms), the solve starts local runs from descents on the exact objective, certifies the design they reach and
    says so in its claim. Shortened (20 generations, 200 evaluations a descent)."""
    from qropt import Solver

    problem = type_problem("crank-shaper-rod", 1.6, 0.3, **KW)
    r = Solver(starts_n=0, settings=SHORT, evolutions=1).solve(problem, use_analytic=False, diagnose=False)
    assert r.status in ("optimal", "acceptable"), r.message
    assert "differential evolution of 20 generations" in r.certificate.global_claim
    free = {k: r.params[k] for k in problem.free}
    m = problem.build(free, {k: r.params[k] for k in problem.branches})
    tr, stroke, v = m.time_ratio(), m.stroke(), objective_of(problem, m)
    assert tr == pytest.approx(1.6, rel=1e-8) and stroke == pytest.approx(0.3, rel=1e-8)
    assert v == pytest.approx(r.objective, rel=1e-9)


def test_a_descents_end_stands_as_a_feasible_design_where_no_start_certifies():
    """Where no local solve certifies a design (here IPOPT gets no iteration), the best descent's end is the
    result: status 'feasible', its targets met exactly (checked by brute force over a fine crank grid), its
    objective exact (a dense grid of the Newton-Euler torque comes within 1e-4 below it), no optimality claimed
    (a Nelder-Mead end); with ``Solver(sqp=True)`` the SQP on the exact peak descends it further and its ``local``
    states first-order stationarity (tests/test_minimax.py checks such an end)."""
    from qropt import Result, Solver
    from tests import brute

    problem = type_problem("crank-shaper-rod", 1.6, 0.3, **KW)
    none = {"starts_n": 0, "ipopt_options": {"ipopt.max_iter": 0}, "settings": SHORT, "evolutions": 1}
    r = Solver(**none).solve(problem, use_analytic=False, diagnose=False)
    assert r.status == "feasible" and r.success, r.message
    assert "not certified" in r.message and r.certificate.local.startswith("none")
    assert "differential evolution of 20 generations, 0 certified" in r.certificate.global_claim
    assert r.local_optima == () and r.stats["origin"] == "descent"
    grid = np.linspace(0.0, 2 * np.pi, 200_001)
    x = np.real(brute.output("crank-shaper", dict(r.params), grid))
    i, k = int(np.argmax(x)), int(np.argmin(x))
    a = (grid[k] - grid[i]) % (2 * np.pi)
    assert max(a, 2 * np.pi - a) / min(a, 2 * np.pi - a) == pytest.approx(1.6, rel=1e-4)
    assert x[i] - x[k] == pytest.approx(0.3, rel=1e-8)
    torque = np.abs(r.mechanism.dynamics(grid[::10], OMEGA2, masses=MASSES, loads=LOADS).torque)
    assert torque.max() <= r.objective * (1 + 1e-9) and torque.max() == pytest.approx(r.objective, rel=1e-4)
    back = Result.from_dict(r.to_dict())
    assert back.status == "feasible" and back.objective == r.objective
    sqp = Solver(**none, sqp=True)
    assert Solver(**sqp.options()).sqp is True
    polished = sqp.solve(problem, use_analytic=False, diagnose=False)
    assert polished.status == "feasible" and polished.objective <= r.objective * (1 + 1e-12)
    assert polished.certificate.local.startswith("first-order stationary"), polished.certificate.local
    # without the evolution (Solver(evolution=False)) the same solve has no design and says why
    off = Solver(**none, evolution=False)
    assert Solver(**off.options()).evolution is False  # the options rebuild an equal Solver (a worker's)
    r = off.solve(problem, use_analytic=False, diagnose=False)
    assert r.status == "failed" and "evolution" not in r.message, r.message


def test_the_evolution_options_are_true_or_false():
    from qropt import ProblemError, Solver

    with pytest.raises(ProblemError, match="evolution is True or False"):
        Solver(evolution="no")
    with pytest.raises(ProblemError, match="sqp is True or False"):
        Solver(sqp=1)
    for bad in (0, 1.5, True, "2"):
        with pytest.raises(ProblemError, match=r"evolutions is None \(by the problem\) or an integer >= 1"):
            Solver(evolutions=bad)


def test_more_evolutions_add_their_ends_to_the_first_ones():
    """``Solver(evolutions=2)`` runs the evolution from seeds 0 and 1: the first is the one evolution of
    ``Solver(evolutions=1)``, so with no certified design (IPOPT gets no iteration) its best end is at least as
    good, and better where the second seed's basin is; the claim names both seeds. Shortened (10 generations, 100
    evaluations)."""
    from qropt import Solver

    problem = type_problem("crank-shaper-rod", 1.6, 0.3, **KW)
    kw = {"starts_n": 0, "ipopt_options": {"ipopt.max_iter": 0}, "settings": FEW}
    one = Solver(**kw, evolutions=1).solve(problem, use_analytic=False, diagnose=False)
    two = Solver(**kw, evolutions=2)
    assert Solver(**two.options()).evolutions == 2  # the options rebuild an equal Solver (a worker's)
    r = two.solve(problem, use_analytic=False, diagnose=False)
    assert one.status == r.status == "feasible", (one.message, r.message)
    assert "2 differential evolutions (seeds 0-1) of 10 generations" in r.certificate.global_claim
    assert r.objective <= one.objective * (1 + 1e-12)
    second = descents.descended(problem, 20, 1, settings=FEW)
    assert r.objective <= second[0].value * (1 + 1e-12)


def test_the_four_bar_driven_rows_run_four_evolutions_by_default(monkeypatch):
    """``Solver()`` (evolutions None) runs ``evolution.count`` evolutions: four for the rows of seven and eight free
    parameters, none for the others; a default solve's claim names the four seeds, an explicit count overrides it.
    Shortened (5 generations, 50 evaluations a descent, IPOPT given no iteration, no SQP)."""
    from qropt import Solver
    from qropt.studies._design import TYPES
    from qropt.synthesis import minimax

    counts = {k: evolution.count(type_problem(k, 1.6, 0.3, **KW)) for k in TYPES}
    assert counts == {k: 4 if k in ("crank-rocker-slider", "drag-link-slider", "coupler-slider") else 0 for k in TYPES}
    monkeypatch.setattr(minimax, "polish", lambda problem, design, steps=None, settings=None: None)
    problem = type_problem("crank-rocker-slider", 1.6, 0.3, **KW)
    short = Settings(evolution_generations=5, descent_evals=50)
    kw = {"starts_n": 0, "ipopt_options": {"ipopt.max_iter": 0}, "settings": short}
    assert Solver(**kw).evolutions is None and Solver(**kw).evolutions_of(problem) == 4
    assert Solver(**Solver(**kw).options()).evolutions is None  # a worker's Solver decides the same way
    r = Solver(**kw).solve(problem, use_analytic=False, diagnose=False)
    assert "4 differential evolutions (seeds 0-3) of 5 generations" in r.certificate.global_claim, r.message
    r = Solver(**kw, evolutions=1).solve(problem, use_analytic=False, diagnose=False)
    assert "after a differential evolution of 5 generations" in r.certificate.global_claim, r.message


def test_a_descents_end_stands_only_where_it_beats_every_certified_design():
    """The certified optimum (the slider-crank's least peak torque, by its family walk) keeps its place against the
    descents' ends, which reach it but not below; against a certified design 20 % worse, the best end stands,
    'feasible', with the certified designs as its local optima."""
    import dataclasses

    from qropt import Solver

    problem = type_problem("slider-crank", 1.3, 0.2, **KW)
    s = Solver()
    r = s.solve(problem)
    assert r.status == "optimal"
    ends = descents.descended(problem, 20, seed=3, keep=2, evals=300)
    assert ends and ends[0].value >= r.objective * (1 - 1e-9)
    assert descended(s, problem, r, ends, "") is r
    worse = dataclasses.replace(r, objective=r.objective * 1.2, local_optima=())
    stood = descended(s, problem, worse, ends, "")
    assert stood.status == "feasible" and stood.objective == pytest.approx(ends[0].value, rel=1e-12)
    assert [x.status for x in stood.local_optima] == ["local_optimum"]
    assert stood.local_optima[0].objective == worse.objective


_TURNS_BACK = {  # where the SQP on the exact peak ended: the coupler slider by peak torque at TR 2.848, 0.834 m
    "r1": 2.9931518200422618,
    "r2": 0.809781580903104,
    "r3": 1.433493973390875,
    "r4": 3.303357589771022,
    "r5": 1.3112728693395832,
    "r6": 1.707383429667817,
    "h": 0.6052913935756883,
    "beta": 0.6211700864647173,
}


def test_a_descents_end_whose_ram_turns_back_inside_a_stroke_does_not_stand():
    """This end of the SQP on the exact peak (under a 30 deg bound) meets TR and stroke, 1585.63 N m, below the
    certified 1585.96: its ram turns back inside the rising stroke by 1.0e-5 of its travel, which ``dead_centres``
    takes as a dwell (``cycle.DWELL``): a descent on exact values walks into that tolerance. A dense grid of the
    ram's positions shows the turn back, ``dwells`` counts it, and the end does not stand."""
    from qropt import Solver
    from qropt.examples import paper_mechanism
    from qropt.kinematics.cycle import DWELL
    from qropt.synthesis.certificate import objective_value, quantities

    p = type_problem("coupler-slider", 2.848, 0.834, **KW, conditions={"gamma_min": math.radians(30)})
    m = p.build(_TURNS_BACK, {"sigma": -1.0, "sigma_slider": 1.0})
    assert (m.time_ratio(), m.stroke(), m.dead_centres().reversals) == pytest.approx((2.848, 0.834, 1), rel=1e-9)
    t = np.linspace(0.0, 2 * np.pi, 2_000_001)
    x = m.positions(t).x
    turns = np.nonzero(np.diff(np.sign(np.diff(x))))[0]  # where the ram's motion changes direction
    assert turns.size == 4  # the two dead centres and a turn back and forth
    back = np.abs(np.diff(x[turns])).min()  # m: the shortest travel between two of them
    assert 0 < back < DWELL * m.stroke() and back > 0.5 * DWELL * m.stroke()
    assert m.dwells() == 1 and paper_mechanism().dwells() == 0
    value = objective_value(p, quantities(p, m))
    assert value == pytest.approx(1585.6258, abs=1e-4)  # N m
    assert descended(Solver(), p, None, [evolution.End(value, _TURNS_BACK, "")], "how", {}) is None
