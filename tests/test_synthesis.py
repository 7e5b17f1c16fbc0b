"""Synthesis: the paper's task, random closed-form tasks for every type (cold multi-start), dense-grid
global checks for every objective, and infeasible, degenerate and malformed problems."""

from __future__ import annotations

import importlib
import math

import numpy as np
import pytest
from scipy.optimize import brentq, minimize_scalar

import qropt
from qropt import ProblemError, Solver, solve
from qropt.synthesis import analytic
from tests import brute
from tests.synth_tasks import TASKS

N_TASKS = 8


def load(name):
    return importlib.import_module(f"problems.{name}").build()


# ---- the paper's design task --------------------------------------------------------------------
def test_paper_task_both_solutions_and_the_right_one_for_each_objective():
    roots = [s.r3 for s in analytic.drag_link_r3(1.5, 0.1, 0.225, 0.275)]
    best = solve(load("paper_drag_link"))
    assert best.status == "optimal" and best.success
    found = sorted(o.params["r3"] for o in best.local_optima)
    assert len(found) == 2 and np.allclose(found, roots, atol=1e-9, rtol=0)
    assert best.params["r3"] == pytest.approx(roots[1], abs=1e-9)  # the larger true gamma_min
    assert best.params["r5"] == pytest.approx(0.15, abs=1e-9)
    assert best.objective == pytest.approx(math.radians(27.008204639), abs=1e-10)
    small = solve(load("paper_drag_link_min_size"))
    assert small.params["r3"] == pytest.approx(roots[0], abs=1e-9)
    assert small.objective == pytest.approx(0.1 + 0.225 + roots[0] + 0.275 + 0.15 + 0.3, abs=1e-9)
    for r in (best, small):  # independent TR and stroke from the brute-force simulator
        t = brute.dead_centres("drag-link-slider", r.params)
        assert brute.time_ratio(t[0], t[1]) == pytest.approx(1.5, abs=1e-9)
        assert t[2] - t[3] == pytest.approx(0.3, abs=1e-9)
        assert r.max_violation < 1e-9 and r.certificate.gap <= 1e-8
        assert r.quantities["grashof"] == "drag-link"


def test_result_is_a_fresh_record():
    r = solve(load("paper_drag_link"), starts_n=0)
    with pytest.raises(AttributeError):
        r.status = "x"
    assert set(r.params) == {"r1", "r2", "r3", "r4", "r5", "r6", "h", "sigma", "sigma_slider"}
    assert r.mechanism.time_ratio() == pytest.approx(1.5, abs=1e-12)
    assert {"time_ratio", "stroke", "gamma_min", "peak_accel", "grashof"} <= set(r.quantities)
    assert r.stats["t_total"] > 0 and r.stats["iterations"] > 0
    assert all(o.local_optima == () for o in r.local_optima)


def test_new_targets_reuse_the_nlp():
    solver = Solver()
    p = load("paper_drag_link")
    solver.solve(p, starts_n=0)
    n = solver.formulations
    assert n > 0
    r = solver.solve(p, starts_n=0, targets={"time_ratio": 1.8, "stroke": 0.25})
    assert solver.formulations == n
    assert r.quantities["time_ratio"] == pytest.approx(1.8, abs=1e-9)
    assert r.params["r3"] == pytest.approx(max(s.r3 for s in analytic.drag_link_r3(1.8, 0.1, 0.225, 0.275)), abs=1e-9)


def test_the_nlps_of_the_last_two_dynamic_tasks_are_kept():
    """A dynamic NLP bakes its masses, loads and omega2 in: a Solver that solves under many loads keeps the NLPs of
    the last two dynamic tasks (its memory bounded) and every kinematic one, builds a dropped task's again and gives
    it the same design."""
    from qropt.studies._design import type_problem

    solver = Solver()
    kw = {"objective": "min_peak_torque", "masses": qropt.Masses.bars(2.0, 10.0), "omega2": 10.0}
    tasks = [type_problem("crank-shaper", 1.5, 0.3, loads=qropt.Loads(f), **kw) for f in (500.0, 600.0, 700.0)]
    first = solver.solve(tasks[0])
    one = solver.formulations
    solver.solve(type_problem("crank-shaper", 1.5, 0.3))
    kinematic = solver.formulations - one
    assert one > 0 and kinematic > 0
    solver.solve(tasks[1])
    assert solver.formulations == 2 * one + kinematic
    solver.solve(tasks[2])  # the first task's NLPs dropped
    assert solver.formulations == 2 * one + kinematic
    again = solver.solve(tasks[0])
    assert solver.formulations == 2 * one + kinematic
    assert (again.status, again.objective, again.params) == (first.status, first.objective, first.params)


# ---- random tasks with closed-form answers, cold multi-start ----------------------------------------
@pytest.mark.parametrize("kind", list(TASKS))
def test_cold_multistart_reaches_the_analytic_optimum(kind):
    rng = np.random.default_rng(2026)
    for _ in range(N_TASKS):
        problem, answer = TASKS[kind](rng)
        r = solve(problem, use_analytic=False)
        assert r.success, (kind, dict(problem.fixed), dict(problem.targets), r.message)
        for k, v in answer.items():
            assert r.params[k] == pytest.approx(v, abs=1e-8), (kind, k, dict(problem.fixed), dict(problem.targets))


# ---- every objective against an independent dense search --------------------------------------------
def _refine_max(f, grid):
    vals = np.array([f(x) for x in grid])
    i = int(np.nanargmax(vals))
    lo, hi = grid[max(i - 1, 0)], grid[min(i + 1, len(grid) - 1)]
    r = minimize_scalar(lambda x: -f(x), bounds=(lo, hi), method="bounded", options={"xatol": 1e-12})
    return max(-r.fun, vals[i])


def _slider_family(tr, s, r2):
    """Offset slider-crank with crank r2 (the stroke triangle, written here): params with e > 0."""
    phi = (tr - 1) * math.pi / (tr + 1)
    k = 1 - math.cos(phi)
    low = (-4 * r2 * k + math.sqrt(16 * r2 * r2 * k * k - 8 * k * (4 * r2 * r2 - s * s))) / (4 * k)
    return {"r2": r2, "r3": low + r2, "e": (low + 2 * r2) * low * math.sin(phi) / s, "sigma_slider": 1.0}


def test_max_gamma_min_is_global():
    # slider-crank family (1 free dimension at fixed TR and stroke): dense scan of r2
    r = solve(load("slider_crank_gamma"))
    f = lambda r2: brute.gamma_min("slider-crank", _slider_family(1.3, 0.3, r2))  # noqa: E731
    ref = _refine_max(f, np.linspace(0.0501, 0.1499, 400))
    assert r.objective == pytest.approx(ref, abs=1e-8)
    # classical crank-rocker family: dense scan along the construction
    r = solve(load("crank_rocker_classic"))

    def g(pos):
        d = analytic.crank_rocker_design(1.25, math.radians(50), 1.0, pos)
        return brute.gamma_min("four-bar", {**d._asdict(), "sigma": -1.0})

    ref = _refine_max(g, np.linspace(0.005, 0.495, 400))
    assert r.objective == pytest.approx(ref, abs=1e-8)
    # paper: two isolated designs
    r = solve(load("paper_drag_link"))
    ref = max(brute.gamma_min("drag-link-slider", o.params) for o in r.local_optima)
    assert r.objective == pytest.approx(ref, abs=1e-10)


def test_min_size_is_global():
    r = solve(load("paper_drag_link_min_size"))
    roots = [s.r3 for s in analytic.drag_link_r3(1.5, 0.1, 0.225, 0.275)]
    assert r.objective == pytest.approx(min(1.05 + x for x in roots), abs=1e-9)
    r = solve(load("crank_shaper_size"))
    k = math.sin((1.6 - 1) * math.pi / (1.6 + 1) / 2)
    assert r.objective == pytest.approx(0.4 / (2 * k), abs=1e-9)  # the lever, forced by TR and stroke
    # slider-crank, smallest r2 + r3 along its family with gamma_min >= 30 deg (without a transmission
    # bound the infimum lies on the singular boundary r3 = r2 + e, where the rod stands vertical)
    bound = math.radians(30)
    p = load("slider_crank_gamma").replace(objective="min_size", size="sum", conditions={"gamma_min": bound})
    r = solve(p)
    assert r.success and r.quantities["gamma_min"] >= bound - 1e-9

    def margin(x):
        return brute.gamma_min("slider-crank", _slider_family(1.3, 0.3, x)) - bound

    def size(x):
        d = _slider_family(1.3, 0.3, x)
        return d["r2"] + d["r3"]

    grid = np.linspace(0.0501, 0.14999, 1000)
    m = np.array([margin(x) for x in grid])
    cands = [size(x) for x, v in zip(grid, m, strict=True) if v >= 0]
    cands += [size(brentq(margin, grid[i], grid[i + 1], xtol=1e-15)) for i in np.flatnonzero(np.diff(np.sign(m)))]
    assert r.objective == pytest.approx(min(cands), abs=1e-8)


def test_min_peak_accel_is_global():
    r = solve(load("whitworth_accel"))
    p = {"r1": 0.1, "r2": 0.2, "r5": 0.15, "h": 0.0, "sigma_slider": 1.0}

    def peak(r6):
        th = np.linspace(0, 2 * np.pi, 20001)
        x = lambda t: np.real(brute.output("whitworth", {**p, "r6": r6}, t))  # noqa: E731
        h = 1e-4
        return np.max(np.abs(x(th + h) - 2 * x(th) + x(th - h)) / h**2) * 100.0

    grid = np.linspace(0.2, 0.6, 41)
    best = min(peak(v) for v in grid)
    assert r.params["r6"] == pytest.approx(0.6, abs=1e-9)
    assert r.objective <= best * (1 + 1e-6) and r.objective == pytest.approx(best, rel=1e-5)
    # paper mechanism, least peak acceleration at 10 rad/s: the better of its two designs
    q = load("paper_drag_link").replace(objective="min_peak_accel", omega2=10.0)
    r = solve(q)
    peaks = sorted(o.quantities["peak_accel"] for o in r.local_optima)
    assert len(peaks) == 2 and r.objective == pytest.approx(peaks[0], abs=1e-9)
    assert r.objective == pytest.approx(55.332539438, abs=1e-6)
    # slider-crank family, least peak acceleration along r2 (dense, brute-force second differences)
    s = load("slider_crank_gamma").replace(objective="min_peak_accel")
    r = solve(s)

    def pk(r2):
        d = _slider_family(1.3, 0.3, r2)
        th = np.linspace(0, 2 * np.pi, 4001)
        x = lambda t: np.real(brute.output("slider-crank", d, t))  # noqa: E731
        return np.max(np.abs(x(th + 1e-4) - 2 * x(th) + x(th - 1e-4)) / 1e-8)

    grid = [x for x in np.linspace(0.0501, 0.14999, 300) if _slider_family(1.3, 0.3, x)["e"] <= 0.6]
    assert r.objective <= min(pk(x) for x in grid) * (1 + 1e-5)


# ---- infeasible, degenerate, malformed ------------------------------------------------------------------
def test_a_time_ratio_beyond_the_sampled_range_is_said_with_the_range_not_claimed_infeasible():
    """No closed form applies (r3 free over an interval): the range is sampled, so the answer is 'failed' with
    the range, never 'infeasible' (a sampled range proves nothing beyond it; the all-free slider-crank's ended
    at TR 1.545 where a design with TR 2.479 exists, test_a_design_beyond_the_sampled_range_is_found)."""
    p = load("paper_drag_link").replace(free={"r3": (0.15, 0.4), "r5": (0.01, 0.5)}, targets={"time_ratio": 1.2})
    r = solve(p)
    assert r.status == "failed" and not r.success and r.mechanism is None
    lo, hi = r.reachable["time_ratio"]
    # independent: dense scan of the paper's eq. (5) over the Grashof interval
    r3 = np.linspace(0.15 + 1e-9, 0.4 - 1e-9, 200001)
    tr = np.array([analytic.paper_time_ratio(0.1, 0.225, x, 0.275) for x in r3[::100]])
    assert lo == pytest.approx(1.4298489, abs=1e-6) and lo == pytest.approx(tr.min(), abs=1e-6)
    assert hi == pytest.approx(tr.max(), abs=1e-3)
    assert "time_ratio 1.2 is below the sampled range 1.42985" in r.message


def test_a_design_beyond_the_sampled_range_is_found():
    """The all-free slider-crank's sampled TR range ended at 1.545; a design with TR 2.479 exists (gamma_min
    3.45 deg) and the solve finds it, checked by brute force."""
    from qropt.studies._design import type_problem

    r = solve(type_problem("slider-crank", 2.479, 0.2952))
    assert r.status == "optimal", r.message
    p = {k: r.params[k] for k in ("r2", "r3", "e")} | {"sigma_slider": r.params["sigma_slider"]}
    th_max, th_min, x_max, x_min = brute.dead_centres("slider-crank", p)
    assert brute.time_ratio(th_max, th_min) == pytest.approx(2.479, rel=1e-6)
    assert x_max - x_min == pytest.approx(0.2952, rel=1e-6)
    assert brute.gamma_min("slider-crank", p) == pytest.approx(r.objective, abs=1e-6)


def test_contradictory_targets_are_infeasible():
    p = load("crank_shaper_size").replace(free={"r2": (0.01, 0.05), "r4": (0.1, 2.0)})
    r = solve(p)
    assert r.status == "infeasible" and "time_ratio 1.6 is above the reachable" in r.message


@pytest.mark.parametrize(
    "changes, fragment",
    [
        ({"free": {}}, "no free parameter"),
        ({"free": {"r3": (0.4, 0.2), "r5": (0.01, 0.5)}}, "empty or contradictory"),
        ({"free": {"r3": (0.0, 0.4), "r5": (0.01, 0.5)}}, "positive lower bound"),
        ({"free": {"r3": (0.1, 0.4), "r9": (0.01, 0.5)}}, "unknown or non-continuous parameter 'r9'"),
        ({"free": {"r3": (0.1, 0.4), "r1": (0.01, 0.5)}}, "both fixed and free"),
        ({"targets": {"time_ratio": 0.8}}, "time_ratio is slow/fast >= 1"),
        ({"targets": {"swing": 1.0}}, "unknown target 'swing'"),
        ({"targets": {}}, "no target"),
        ({"objective": "max_speed"}, "unknown objective"),
        ({"conditions": {"grashof": "crank-rocker"}}, "is a drag-link by definition"),
        ({"conditions": {"gamma_min": 2.0}}, "gamma_min bound must be in [0, pi/2)"),
        ({"mechanism": "Shaper9000"}, "unknown mechanism type"),
        ({"fixed": {"r1": -0.1, "r2": 0.225, "r4": 0.275, "r6": 0.3}}, "fixed length r1 must be positive"),
        ({"fixed": {"r1": 0.1, "r2": 0.225, "r6": 0.3}}, "['r4'] are neither fixed nor free"),
    ],
)
def test_malformed_problems_raise_before_any_solve(changes, fragment):
    with pytest.raises(ProblemError) as info:
        load("paper_drag_link").replace(**changes)
    assert fragment in str(info.value)


def test_gamma_min_condition_is_respected():
    p = load("paper_drag_link").replace(objective="min_size", conditions={"gamma_min": math.radians(20)})
    r = solve(p)
    assert r.params["r3"] == pytest.approx(max(s.r3 for s in analytic.drag_link_r3(1.5, 0.1, 0.225, 0.275)), abs=1e-9)
    # 30 deg: both designs with TR 1.5 and stroke 0.3 (27.0 and 9.1 deg) fall short
    r = solve(p.replace(conditions={"gamma_min": math.radians(30)}))
    best = max(
        p.build({"r3": s.r3, "r5": 0.15}, {"sigma": -1.0, "sigma_slider": 1.0}).gamma_min().value
        for s in analytic.drag_link_r3(1.5, 0.1, 0.225, 0.275)
    )
    assert r.status == "infeasible" and "gamma_min 0.523599 rad (30.00 deg) is beyond reach" in r.message
    assert r.reachable["gamma_min"][1] == pytest.approx(best, abs=1e-9) and math.degrees(best) < 30


def test_solver_failure_is_a_status_not_an_exception():
    r = solve(load("paper_drag_link"), starts_n=1, use_analytic=False, max_rounds=1, seed=3)
    assert r.status in ("optimal", "infeasible", "failed") and isinstance(r.message, str) and r.message


# ---- typed results and honest certificates ------------------------------------------------------------------
def test_result_round_trips_through_strict_json_and_prints_short():
    import json

    r = solve(load("paper_drag_link"))
    text = json.dumps(r.to_dict(), allow_nan=False)
    back = qropt.Result.from_dict(json.loads(text))
    assert back.status == r.status and back.params == r.params and back.objective == r.objective
    assert back.certificate == r.certificate and len(back.local_optima) == len(r.local_optima)
    assert back.mechanism == r.mechanism
    assert len(repr(r).splitlines()) <= 15
    bad = solve(load("paper_drag_link"), targets={"time_ratio": 9.0})
    assert bad.status == "infeasible" and not bad.success
    json.dumps(bad.to_dict(), allow_nan=False)
    assert len(repr(bad).splitlines()) <= 15


def test_statuses_and_global_claims():
    r = solve(load("paper_drag_link"))
    assert r.status == "optimal" and [o.status for o in r.local_optima] == ["optimal", "local_optimum"]
    assert r.certificate.global_claim.startswith("by enumeration")
    cold = solve(load("paper_drag_link"), use_analytic=False)
    assert cold.certificate.global_claim.startswith("best of") and "starts" in cold.certificate.global_claim
    assert cold.params["r3"] == pytest.approx(r.params["r3"], abs=1e-9)
    assert set(qropt.STATUSES) == {"optimal", "local_optimum", "acceptable", "feasible", "infeasible", "failed"}


def test_min_size_certificate_compares_two_sources():
    p = load("paper_drag_link_min_size")
    r = solve(p, use_analytic=False)
    c = r.certificate
    assert c.nlp is not None and c.certified == pytest.approx(r.mechanism.size("sum"), abs=1e-15)
    assert c.gap == pytest.approx(abs(c.certified - c.nlp), abs=1e-15) and c.gap <= 1e-8


def test_a_result_does_not_depend_on_earlier_solves():
    names = ["whitworth_accel", "slider_crank_gamma", "paper_drag_link_footprint"]
    fresh = {n: Solver().solve(load(n)) for n in names}
    shared = Solver()
    for n in names[::-1] + names:
        r = shared.solve(load(n))
        assert r.params == fresh[n].params and r.objective == fresh[n].objective


def test_local_runs_that_miss_every_design_do_not_make_a_problem_infeasible():
    """The coupler slider at TR 2.967, stroke 0.0908 m by min_peak_accel: the default solve finds no design (its
    local runs end at iteration limits or at points the exact evaluation refuses), yet designs exist (IPOPT with
    more iterations finds one, checked here by brute force). The result says 'failed', never 'infeasible'."""
    from qropt.studies._design import type_problem

    p = type_problem("coupler-slider", 2.967, 0.0908, objective="min_peak_accel")
    r = solve(p)
    assert r.status != "infeasible", r.message
    found = Solver(ipopt_options={"ipopt.max_iter": 200}).solve(p)
    assert found.success, found.message
    _, _, _, _, tr, stroke, _ = brute.sixbar_cycle("coupler-slider", dict(found.params))
    assert tr == pytest.approx(2.967, rel=1e-6) and stroke == pytest.approx(0.0908, rel=1e-6)
    if not r.success:
        assert "none was proved absent" in r.message or "a design meeting" in r.message
