"""The cut-window criterion: (v_max - v_min) / v_mean of the ram's speed over a window of the working stroke.

Oracles: the brute-force kinematics of ``tests.brute`` (plain Cartesian formulas, the speed by the complex step) on a
dense crank grid, the window's edges by brentq on its positions; and the slider-crank's closed-form family of a TR
and stroke (every such design lies on it) swept densely and refined by Brent.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy.optimize import brentq

import qropt
from problems import _bases as problem_bases
from problems import _oracles as oracles
from qropt import cli
from qropt.errors import InvalidParameter, ProblemError, QroptError
from qropt.synthesis import criteria, cut
from tests import brute

GRID = 200_001  # crank angles of the brute-force scan over the turn
TR, STROKE = 1.3, 0.3
CUT = criteria.CRITERIA["cut_speed_variation"]


@pytest.fixture(autouse=True)
def _windows():
    """The windows a test registers are removed after it (the registry is the process's)."""
    before = set(criteria.CRITERIA)
    yield
    for name in set(criteria.CRITERIA) - before:
        criteria.unregister(name)


def brute_variation(kind, p, window, omega2):
    """(v_max - v_min) / v_mean over the window (fractions (f0, f1) of the stroke from the working stroke's start
    dead centre, for the crank's sense) on a dense grid, from brute-force positions alone."""
    theta_max, theta_min, x_max, x_min = brute.dead_centres(kind, p)
    fall = (theta_min - theta_max) % (2 * np.pi)
    # the working (slow) arc, counter-clockwise from lo to hi; the ram's start of it in time for omega2's sense
    lo, hi, x_lo, x_hi = (
        (theta_max, theta_max + fall, x_max, x_min)
        if fall > np.pi
        else (theta_min, theta_max + 2 * np.pi, x_min, x_max)
    )
    hi = lo + (hi - lo) % (2 * np.pi)
    x_start, x_end = (x_lo, x_hi) if omega2 > 0 else (x_hi, x_lo)
    edges = [x_start + f * (x_end - x_start) for f in window]

    def x(t):
        return float(np.real(brute.output(kind, p, t)))

    t_edges = sorted(brentq(lambda t, e=e: x(t) - e, lo, hi, xtol=1e-15) for e in edges)
    th = np.linspace(t_edges[0], t_edges[1], GRID)
    speed = np.abs(np.imag(brute.output(kind, p, th + 1j * brute.STEP)) / brute.STEP)
    mean = abs(edges[1] - edges[0]) / (t_edges[1] - t_edges[0])  # per |omega2|, as the speeds
    return (speed.max() - speed.min()) / mean


CASES = [
    ("slider-crank", {"r2": 0.1, "r3": 0.5, "e": 0.1, "sigma_slider": 1.0}, (0.1, 0.9), 2.0),
    ("slider-crank", {"r2": 0.1, "r3": 0.5, "e": 0.1, "sigma_slider": 1.0}, (0.2, 0.5), -1.0),
    ("crank-shaper", {"r1": 0.3, "r2": 0.12, "r4": 0.6, "r6": 0.4, "h": 0.62, "sigma_slider": 1.0}, (0.05, 0.7), 1.0),
]


@pytest.mark.parametrize(("kind", "p", "window", "omega2"), CASES)
def test_the_exact_value_matches_a_dense_brute_force_grid(kind, p, window, omega2):
    m = qropt.mechanism_type(kind)(**p)
    c = cut.window(window)
    problem = problem_bases.slider_crank(omega2=omega2)  # the criterion reads its omega2 alone
    assert c.value(problem, m) == pytest.approx(brute_variation(kind, p, window, omega2), rel=1e-8)
    # the same window as distances from the start dead centre (the design's stroke times the fractions)
    s = m.stroke()
    d = cut.window(qropt.Window(x=(window[0] * s, window[1] * s), stroke="working"))
    assert d.value(problem, m) == pytest.approx(c.value(problem, m), rel=1e-12)


def test_the_default_window_and_omega2_independence():
    m = qropt.SliderCrank(r2=0.1, r3=0.5, e=0.1)
    p = problem_bases.slider_crank()
    assert (CUT.lo, CUT.hi, CUT.kind) == (0.1, 0.9, "fraction")
    assert CUT.value(p.replace(omega2=7.0), m) == CUT.value(p, m)
    asym = cut.window((0.2, 0.5))  # the crank's sense picks the start dead centre
    assert asym.value(p.replace(omega2=-1.0), m) == pytest.approx(cut.window((0.5, 0.8)).value(p, m), rel=1e-12)


@pytest.mark.parametrize(("window", "omega2"), [((0.1, 0.9), 2.0), ((0.2, 0.5), -2.0)])
def test_the_optimum_matches_a_dense_scan_of_the_closed_form_family(window, omega2):
    c = cut.window(window)
    p = problem_bases.slider_crank(objective=c.objective, omega2=omega2)
    r = qropt.solve(p)
    assert r.status == "optimal" and r.certificate.exact and abs(r.certificate.gap) <= 1e-8
    o = oracles.along(p, oracles.slider_crank_family(TR, STROKE), 0.0501, 0.14999, n=400)
    assert r.objective <= o["objective"] * (1 + 1e-9)  # the scan's Brent ends within its tolerance above
    assert r.objective == pytest.approx(o["objective"], rel=1e-7)
    assert r.mechanism.params["r2"] == pytest.approx(o["params"]["r2"], rel=1e-4)
    assert r.quantities[c.name] == r.objective
    kind = "slider-crank"
    assert r.objective == pytest.approx(brute_variation(kind, r.mechanism.params, window, omega2), rel=1e-8)


def test_a_bound_on_it_holds_at_the_result_and_matches_the_family_with_that_bound():
    bound = 0.45
    p = problem_bases.slider_crank(objective="max_gamma_min", conditions={"max_cut_speed_variation": bound})
    free = qropt.solve(p.replace(conditions={}))
    assert CUT.value(p, free.mechanism) > bound + 0.1  # the bound binds
    r = qropt.solve(p)
    assert r.status == "optimal" and r.certificate.exact
    assert r.quantities["cut_speed_variation"] <= bound * (1 + 1e-9)
    assert r.quantities["cut_speed_variation"] == pytest.approx(bound, rel=1e-9)  # active
    assert brute_variation("slider-crank", r.mechanism.params, (0.1, 0.9), 1.0) <= bound * (1 + 1e-8)
    family = oracles.slider_crank_family(TR, STROKE)

    def margin(t):
        d = family(t)
        if d is None or oracles.score(p.replace(conditions={}), d) is None:
            return -1.0
        return bound - CUT.value(p, p.build({k: d[k] for k in p.free}, {"sigma_slider": 1.0}))

    o = oracles.along(p, family, 0.0501, 0.14999, n=400, boundary=margin)
    assert r.objective == pytest.approx(o["objective"], rel=1e-7)


def test_design_pareto_and_the_command_line_take_it(capsys):
    cmp = qropt.design(TR, STROKE, types=["slider-crank"], objective="min_cut_speed_variation")
    row = cmp.rows[0]
    assert row.success and row.criteria["cut_speed_variation"] == pytest.approx(0.3811906442474, rel=1e-9)
    p = problem_bases.slider_crank()
    front = qropt.pareto(p, objectives=("min_cut_speed_variation", "max_gamma_min"), n=3)
    assert front.criteria == ("cut_speed_variation", "gamma_min") and len(front.values) == 3
    (v0, g0), *_, (v1, g1) = front.values
    assert v0 == pytest.approx(0.3811906442474, rel=1e-6) and v1 > v0 and g1 > g0  # an end: a nudged for b
    assert all(r.quantities["cut_speed_variation"] == v for r, (v, _) in zip(front.points, front.values, strict=True))
    assert cli.main(["design", "--tr", "1.3", "--stroke", "0.3", "--types", "slider-crank", "--objective",
                     "min_cut_speed_variation", "--json"]) == 0  # fmt: skip
    out = json.loads(capsys.readouterr().out)
    assert "cut_speed_variation" in json.dumps(out)


def test_bad_windows_and_uses_are_refused_by_name():
    for bad in ((0.9, 0.1), (-0.1, 0.5), (0.2, 1.2), (0.3, 0.3), "middle", (0.1,), (True, 0.5), (0.1, math.nan)):
        with pytest.raises(InvalidParameter, match="cut window"):
            cut.window(bad)
    for bad in (
        qropt.Window(x=(0.0, 0.1)),
        qropt.Window(theta2=(0.0, 1.0)),
        qropt.Window(x=(-0.1, 0.1), stroke="working"),
    ):
        with pytest.raises(InvalidParameter, match="cut window"):
            cut.window(bad)
    with pytest.raises(InvalidParameter, match="registered already"):
        cut.window((0.3, 0.7), name="cut_speed_variation")
    with pytest.raises(QroptError):  # a criterion of the slider's speed: not of a four-bar's follower angle
        qropt.Problem(
            mechanism="FourBar",
            free={"r2": (0.1, 1.0), "r3": (0.5, 3.0), "r4": (0.5, 3.0)},
            fixed={"r1": 2.0, "sigma": 1.0},
            targets={"time_ratio": 1.2, "swing": 0.8},
            objective="min_cut_speed_variation",
        )
    far = cut.window(qropt.Window(x=(0.1, 0.5), stroke="working"))  # past a 0.3 stroke
    m = qropt.SliderCrank(r2=0.1, r3=0.5, e=0.1)
    with pytest.raises(InvalidParameter, match="past the stroke"):
        far.value(problem_bases.slider_crank(), m)
    r = qropt.solve(problem_bases.slider_crank(objective=far.objective))
    assert r.status != "optimal"
    with pytest.raises(ProblemError):
        criteria.unregister("cut_speed_variation")  # built in


def test_a_window_that_does_not_fit_every_design_stays_out_of_other_problems_results():
    """A window of distances registered in this process (longer than the task's stroke here) is reported only by
    the problems that use it: a design and a solve by other objectives neither compute nor fail on it."""
    from qropt.studies._design import type_problem

    long = cut.window(qropt.Window(x=(0.03, 5.0), stroke="working"))
    row = qropt.design(1.5, 0.3, types=["slider-crank"]).rows[0]
    assert row.result.success and row.criteria[long.name] is None
    assert row.criteria["cut_speed_variation"] is not None  # the registered fractions fit every design
    r = qropt.solve(type_problem("slider-crank", 1.5, 0.3, objective="max_gamma_min"))
    assert r.success and long.name not in r.quantities and "cut_speed_variation" in r.quantities
