"""General loads in the synthesis NLP (forces at joints and body points in each direction kind, torques on bodies,
windows and tables, a gravity vector, point masses at joints): its torque, shaking force and bearing loads at a
random design of every type equal the exact analysis's, and a solve under them is certified against a dense scan
of a closed-form family."""

from __future__ import annotations

import math

import numpy as np
import pytest

import qropt
from qropt import Force, Loads, Masses, Torque, Window
from qropt.dynamics.inverse import linkage_of
from qropt.errors import ProblemError
from qropt.studies._design import type_problem
from qropt.synthesis import analytic, criteria
from tests.test_dynamic_criteria import KINDS, MASSES, _at_random_design, _criterion_rows, _stroke_loads

ALL = (*KINDS, "slot-ram-shaper")


def _names(m):
    """(turning bodies, joints on non-block bodies, the output joint, the ram's x range (x_min, span))."""
    bodies = linkage_of(m).bodies()
    turning = [b.name for b in bodies if b.kind not in ("ram", "yoke", "block")]
    joints = sorted({j for b in bodies for j in b.joints if b.kind != "block"})
    d = m.dead_centres()
    return turning, joints, m.output_joint(), (d.x_min, d.x_max - d.x_min)


def _general(m, windows=True) -> Loads:
    """Every kind of force and torque on the design's bodies, with a gravity vector; ``windows``: x and theta2
    windows and tables too (else windows of a stroke only)."""
    turning, joints, out, (x0, span) = _names(m)
    forces = [
        Force(out, 300.0, "against", "working"),
        Force(joints[1], 50.0, (0.3, -1.0), "always"),
        Force((turning[-1], 0.1, 0.05), 80.0, "against", "return" if not windows else Window(theta2=(1.0, 4.0))),
    ]
    torques = [Torque(turning[0], 5.0, "return")]
    if windows:
        forces += [
            Force(
                out,
                ((x0 + 0.2 * span, 100.0), (x0 + span, 400.0)),
                "slide",
                Window(x=(x0 + 0.1 * span, x0 + 0.7 * span), stroke="return"),
            ),
            Force(joints[0], ((0.5, 10.0), (3.0, 60.0)), (1.0, 0.0), against="theta2"),
        ]
        torques += [Torque(turning[-1], ((1.0, 2.0), (5.0, -3.0)), against="theta2")]
    return Loads(forces=forces, torques=torques, gravity=(2.0, -9.0))


def _masses(m) -> Masses:
    _, _, out, _ = _names(m)
    return MASSES.replace(points={"A": 0.7, out: 3.0})


@pytest.mark.parametrize("kind", ALL)
def test_the_nlp_states_the_exact_torque_shaking_and_bearing_loads_under_general_loads(kind):
    p, m, f, w, pv, th, _ = _at_random_design(kind, "min_peak_torque", 5, _general, _masses)
    n = th.size
    exact = m.dynamics(th, 7.0, masses=p.masses, loads=p.loads)
    assert np.abs(exact.torque - m.dynamics(th, 7.0, masses=MASSES).torque).max() > 1.0  # the loads count
    e = _criterion_rows(f, w, pv)
    assert e[0 : 2 * n : 2] == pytest.approx(exact.torque, rel=1e-9, abs=1e-9 * np.abs(exact.torque).max())
    p, m, f, w, pv, th, _ = _at_random_design(kind, "min_shaking_force", 5, _general, _masses)
    s2 = np.sum(m.dynamics(th, 7.0, masses=p.masses, loads=p.loads).shaking_force ** 2, axis=1)
    assert _criterion_rows(f, w, pv)[:n] == pytest.approx(s2, rel=1e-9, abs=1e-9 * s2.max())
    p, m, f, w, pv, th, _ = _at_random_design(kind, "min_peak_bearing_force", 5, _general, _masses)
    want = _stroke_loads(m, n, p.loads, p.masses)
    got = _criterion_rows(f, w, pv)[: want.size].reshape(want.shape)
    assert np.sort(got, axis=1) == pytest.approx(np.sort(want, axis=1), rel=1e-9, abs=1e-9 * want.max())


@pytest.mark.parametrize("kind", ["crank-shaper", "coupler-slider"])
def test_the_nlps_rms_torque_is_the_exact_one_under_loads_on_a_stroke(kind):
    """The RMS torque's quadrature over each stroke (the exact one's rule: the loads switch only at the dead
    centres, where the strokes end)."""
    import casadi

    p, m, f, w, pv, *_ = _at_random_design(kind, "min_rms_torque", 7, lambda m: _general(m, False), _masses)
    value = float(casadi.Function("f", [f.w_sym, f.p_sym], [f.f_sym])(w, pv))
    c = criteria.of("min_rms_torque")
    assert c.from_nlp(value, 7.0) == pytest.approx(c.value(p, m), rel=1e-9)


def _family_scan(p, c, n=400, refine=4) -> float:
    """The best of the crank-shapers along the family of the task (r2 = k r1, r4 = s / 2k), exactly: n along r1's
    range, then n / 4 between the best one's neighbours, ``refine`` times."""
    k = analytic.crank_shaper_ratio(1.5)

    def value(r1):
        q = {"r1": r1, "r2": k * r1, "r4": 0.3 / (2 * k)}
        if all(p.free[name][0] <= v <= p.free[name][1] for name, v in q.items()):
            return c.value(p, qropt.CrankShaper(**q))
        return math.inf

    r1 = np.geomspace(*p.free["r1"], n)
    best = math.inf
    for _ in range(refine + 1):
        values = [value(v) for v in r1]
        i = int(np.argmin(values))
        best = min(best, values[i])
        r1 = np.linspace(r1[max(i - 1, 0)], r1[min(i + 1, r1.size - 1)], n // 4)
    return best


def test_a_cutting_force_stated_as_a_force_gives_the_shorthands_optimum():
    kw = dict(masses=MASSES, omega2=10.0)
    short = qropt.solve(type_problem("crank-shaper", 1.5, 0.3, objective="min_peak_torque", loads=Loads(800.0), **kw))
    loads = Loads(forces=[Force("C", 800.0, "against", "working")])
    general = qropt.solve(type_problem("crank-shaper", 1.5, 0.3, objective="min_peak_torque", loads=loads, **kw))
    assert short.status == general.status == "optimal", (short.message, general.message)
    assert general.objective == pytest.approx(short.objective, rel=1e-9)


@pytest.mark.parametrize("objective", ["min_peak_torque", "min_rms_torque", "min_shaking_force"])
def test_the_optimum_under_general_loads_is_the_best_of_a_dense_scan(objective):
    """Gravity along the stroke (a vertical machine), a forming force over part of the return stroke's travel,
    a spring-like force of fixed direction at the crank pin, a point mass at the crank pin: the certified optimum
    is at least as good as 800 designs along the crank-shaper's family (a scan and four refinements about its
    best), evaluated exactly, and within 1e-6."""
    windows = objective != "min_rms_torque"
    loads = Loads(
        forces=[
            Force("C", 600.0, "against", "working"),
            Force("A", 150.0, (0.0, -1.0), "always"),
            *([Force("C", 900.0, "slide", Window(theta2=(2.0, 3.0)))] if windows else []),
        ],
        gravity=(-9.81, 0.0),
    )
    masses = MASSES.replace(points={"A": 1.5})
    p = type_problem("crank-shaper", 1.5, 0.3, objective=objective, masses=masses, loads=loads, omega2=10.0)
    r = qropt.solve(p)
    assert r.status in ("optimal", "acceptable"), r.message
    c = criteria.of(objective)
    best = _family_scan(p, c)
    assert r.objective <= best * (1 + 1e-9)
    assert r.objective == pytest.approx(best, rel=1e-6)
    assert r.objective == pytest.approx(c.value(p, r.mechanism), rel=1e-9)


@pytest.mark.parametrize(
    "loads, words",
    [
        (Loads(1000.0, pin_friction=qropt.PinFriction(0.1, 0.01)), "pin friction"),
        (Loads(forces=[Force("C", 10.0)], working="-x"), "named working stroke"),
        (Loads(forces=[Force("Q", 10.0)]), "no joint 'Q'"),
        (Loads(torques=[Torque("ram", 10.0)]), "ram does not turn"),
    ],
)
def test_what_the_nlp_cannot_take_is_refused_by_name(loads, words):
    with pytest.raises(ProblemError, match=words):
        type_problem("crank-shaper", 1.5, 0.3, objective="min_peak_torque", masses=MASSES, loads=loads, omega2=10.0)
