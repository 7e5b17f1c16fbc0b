"""A crank counterweight left free (``Counterweight.balancing``): synthesis chooses its mass and angle with the
links. Checked against an independent route: along the crank-shaper's closed-form family, the best counterweight
of each design is a convex problem (the shaking force is affine in the counterweight's first moment), solved by
cvxpy on a grid and evaluated exactly."""

from __future__ import annotations

import math

import numpy as np
import pytest

import qropt
from qropt.studies._design import type_problem
from qropt.synthesis import analytic

RADIUS, MAX_MASS = 0.1, 30.0
LOADS = qropt.Loads(1000.0)


def _masses(counterweight=None):
    return qropt.Masses.steel(4e-4, 20.0, counterweight=counterweight)


def _balancing(kind):
    """The type's task TR 1.5, stroke 0.3 m by min_shaking_force, its counterweight left to the solve."""
    return type_problem(
        kind,
        1.5,
        0.3,
        objective="min_shaking_force",
        masses=_masses(qropt.Counterweight.balancing(RADIUS, MAX_MASS)),
        loads=LOADS,
        omega2=10.0,
    )


def _best_counterweight(m, omega2):
    """The least peak shaking force of design m over every counterweight of at most MAX_MASS at RADIUS: the
    shaking force is S0 + u Su + v Sv in the counterweight's first moment (u, v) (superposition of the exact
    dynamics with unit moments), its peak over a 720-angle grid is minimised by an SOCP, and the peak of the
    chosen counterweight is then found exactly."""
    import cvxpy as cp

    t = np.linspace(0.0, 2 * np.pi, 720, endpoint=False)
    unit = qropt.Counterweight(1.0 / RADIUS, RADIUS, 0.0)

    def shaking(cw):
        return m.dynamics(t, omega2, masses=_masses(cw), loads=LOADS).shaking_force

    s0 = shaking(None)
    su, sv = shaking(unit) - s0, shaking(unit.with_moment(0.0, 1.0)) - s0
    u, v, top = cp.Variable(), cp.Variable(), cp.Variable()
    cons = [cp.norm(s0 + u * su + v * sv, axis=1) <= top, cp.norm(cp.hstack([u, v])) <= MAX_MASS * RADIUS]
    cp.Problem(cp.Minimize(top), cons).solve(solver="CLARABEL")
    cw = unit.with_moment(float(u.value), float(v.value))
    return m.dynamic_extremes(omega2, masses=_masses(cw), loads=LOADS).peak_shaking_force.value, cw


def test_a_balanced_crank_shaper_is_the_best_of_a_family_scan_with_the_best_counterweight_of_each_design():
    p = _balancing("crank-shaper")
    r = qropt.solve(p)
    assert r.status in ("optimal", "acceptable"), r.message
    cw = r.counterweight
    assert cw is not None and not cw.free and 0 < cw.mass <= MAX_MASS * (1 + 1e-9) and cw.radius == RADIUS
    exact = r.mechanism.dynamic_extremes(10.0, masses=_masses(cw), loads=LOADS).peak_shaking_force.value
    assert r.objective == pytest.approx(exact, rel=1e-9)  # the certificate evaluates the chosen counterweight
    k = analytic.crank_shaper_ratio(1.5)
    scan = []
    for r1 in np.geomspace(0.015 / k, 1.5, 120):  # r2 = k r1 inside its bounds
        scan.append(_best_counterweight(qropt.CrankShaper(r1=r1, r2=k * r1, r4=0.3 / (2 * k)), 10.0)[0])
    assert r.objective <= min(scan) * (1 + 1e-9)
    assert r.objective == pytest.approx(min(scan), rel=2e-3)
    unbalanced = qropt.solve(p.replace(masses=_masses()))
    assert r.objective < 0.9 * unbalanced.objective  # balancing helps here, by more than 10 %


def test_a_counterweight_balances_the_gravity_torque():
    """With gravity, a counterweight changes the crank torque (its weight's moment about O2): the balanced
    min_peak_torque design is better than the unbalanced one, and its value is the exact analysis'."""
    loads = qropt.Loads(1000.0, gravity=9.81)
    p = type_problem("crank-shaper", 1.5, 0.3, objective="min_peak_torque", masses=_masses(), loads=loads, omega2=10.0)
    plain = qropt.solve(p)
    free = qropt.solve(p.replace(masses=_masses(qropt.Counterweight.balancing(RADIUS, MAX_MASS))))
    assert plain.success and free.success, (plain.message, free.message)
    assert free.objective < plain.objective
    m = free.mechanism
    assert free.objective == pytest.approx(
        m.dynamic_extremes(10.0, masses=_masses(free.counterweight), loads=loads).peak_torque.value, rel=1e-9
    )


def test_the_chosen_counterweight_is_in_the_result_and_its_dictionary():
    p = _balancing("slider-crank")
    r = qropt.solve(p)
    assert r.success, r.message
    back = qropt.Result.from_dict(r.to_dict())
    assert back.counterweight == r.counterweight
    assert "counterweight:" in r.summary() and "kg at 0.1 m" in r.summary()
    with pytest.raises(qropt.ProblemError, match="counterweight"):
        qropt.Result.from_dict({**r.to_dict(), "counterweight": {"mass": -1.0, "radius": 0.1}})


def test_a_free_counterweight_is_data_and_is_refused_where_nothing_chooses_it():
    cw = qropt.Counterweight.balancing(RADIUS, MAX_MASS)
    masses = _masses(cw)
    assert qropt.Masses.from_dict(masses.to_dict()) == masses
    m = qropt.CrankShaper(r1=0.3, r2=0.1, r4=0.5)
    with pytest.raises(qropt.InvalidParameter, match="free"):
        m.dynamics([0.0, 1.0], 10.0, masses=masses)
    with pytest.raises(qropt.InvalidParameter, match="largest mass"):
        qropt.Counterweight.balancing(RADIUS, 0.0)
    fixed = cw.with_moment(-1.0, 0.0)
    assert (fixed.mass, fixed.angle, fixed.free) == (pytest.approx(10.0), pytest.approx(math.pi), False)
