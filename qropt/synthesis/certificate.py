"""Exact evaluation of a candidate design: the quantities a Result reports, and the certificate of an NLP point.

Every number here comes from the exact cycle analysis of the rebuilt mechanism, never from the NLP's
sample angles; the exchange loop adds the angles where the two disagree.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from qropt.errors import AssemblyError, QroptError
from qropt.mechanisms import FourBar
from qropt.synthesis import criteria
from qropt.synthesis.criteria import better, objective_of, objective_value

TWO_PI = 2.0 * math.pi


@dataclass(frozen=True)
class Certificate:
    """What a solve proves about its design.

    exact: the NLP's epigraph value (``nlp``) and the exact value over the full turn (``certified``) agree to
    ``gap`` (the exchange loop closed; for min_size 'sum' both are the same lengths); rounds: exchange rounds;
    local: how the point is a local solution (IPOPT's status, or a point of a finite feasible set);
    global_claim: 'by enumeration (...)', 'best along the closed-form family (...)' or
    'best of K distinct local optima from N starts'.
    """

    exact: bool
    nlp: float | None
    certified: float | None
    gap: float
    rounds: int
    local: str
    global_claim: str = ""

    def to_dict(self) -> dict:
        return asdict(self)


class Designs:
    """Mechanisms built from a problem's free values, each built once (they are immutable); one per Solver.

    Calling it is ``problem.build(values, branch)``, raising the same QroptError for a design that cannot exist.
    """

    def __init__(self, size: int = 512):
        self.size, self._memo = size, {}

    def __call__(self, problem, values: dict, branch: dict):
        key = (id(problem), tuple(sorted(values.items())), tuple(sorted(branch.items())))
        hit = self._memo.get(key)
        if hit is None or hit[0] is not problem:
            if len(self._memo) >= self.size:
                self._memo.clear()
            try:
                hit = (problem, problem.build(values, branch), None)
            except QroptError as e:
                hit = (problem, None, e)
            self._memo[key] = hit
        if hit[2] is not None:
            raise hit[2]
        return hit[1]


def build(problem, values, branch):
    """problem.build, uncached (the default where no Solver's Designs is given)."""
    return problem.build(values, branch)


def quantities(problem, m) -> dict:
    """Exact quantities of a mechanism for a Result (angles in rad, lengths in the problem's units; peak_accel
    at the problem's omega2 over its ``accel_over`` span, peak_velocity at omega2 over the working stroke with
    the peak crank torque per newton of cutting force; size by the problem's measure)."""
    q = {"time_ratio": m.time_ratio(), "gamma_min": m.gamma_min().value}
    slider = not isinstance(m, FourBar)
    q["swing" if not slider else "stroke"] = m.stroke()
    q["peak_accel"] = m.peak_acceleration(problem.omega2, problem.accel_over).value if slider else None
    pv = m.peak_velocity(problem.omega2) if slider else None
    q["peak_velocity"] = pv.value if slider else None
    q["torque_per_newton"] = pv.torque_per_newton if slider else None
    q["grashof"] = m.grashof().kind if hasattr(m, "grashof") else None
    q["size"] = m.size(problem.size)
    q["working_direction"] = m.working_direction(problem.omega2)
    return q


def angle_gap(a, b):
    return abs((a - b + math.pi) % TWO_PI - math.pi)


def certify(problem, range_target, values, branch, th, z, f, gap_tol, feas_tol, build=build):
    """Exact check of an NLP point. Returns (mechanism or None, info dict, angles to add, fractions to add).

    z: the epigraph values and f the NLP objective (None for a point that did not come from the NLP).
    """
    try:
        return _certify(problem, range_target, build(problem, values, branch), th, z, f, gap_tol, feas_tol)
    except AssemblyError as e:
        mids = [((lo + hi) / 2) % TWO_PI for _, lo, hi in e.failures]
        return None, {"ok": False, "reason": str(e)}, mids, []
    except QroptError as e:
        return None, {"ok": False, "reason": str(e)}, [], []


def _certify(problem, range_target, m, th, z, f, gap_tol, feas_tol):
    d = m.dead_centres()
    if angle_gap(d.theta_max, th[0]) > 1e-7 or angle_gap(d.theta_min, th[1]) > 1e-7:
        return m, {"ok": False, "reason": "the NLP's dead centres are local, not the global extremes"}, [], []
    if d.reversals != 1:
        return m, {"ok": False, "reason": f"the slider reverses {d.reversals} times a turn"}, [], []
    info = {"ok": True, "nlp": None, "certified": None, "gap": 0.0}
    add, frac = [], []
    obj = problem.objective if not range_target else None
    g = m.gamma_min()
    if z is None:  # an enumerated point: the exact value only
        info["certified"] = objective_of(problem, m) if obj else None
    elif obj == "max_gamma_min":
        exact = math.cos(g.value)
        info.update(nlp=math.acos(min(1.0, z[0])), certified=g.value, gap=exact - z[0])
        if exact - z[0] > gap_tol:  # every local minimum of every joint below the NLP's value
            for t, v in m.transmission_minima():
                add += [float(a) for a, b in sorted(zip(t, v, strict=True), key=lambda q: q[1]) if math.cos(b) > z[0]]
    elif obj == "min_peak_accel":
        peak = m.peak_acceleration(1.0, problem.accel_over)
        w2 = problem.omega2**2
        info.update(nlp=z[0] * w2, certified=peak.value * w2, gap=(peak.value - z[0]) * w2)
        if peak.value - z[0] > gap_tol:  # every local extreme of the acceleration above the NLP's bound
            ex = m.acceleration_extremes()
            ts = np.concatenate([ex.maxima[0], ex.minima[0]])
            vs = np.concatenate([ex.maxima[1], ex.minima[1]])
            worst = [float(a) for a, b in sorted(zip(ts, vs, strict=True), key=lambda q: -abs(q[1])) if abs(b) > z[0]]
            if problem.accel_over == "working":
                frac += _working_fractions(m, ex, z[0]) or _working_fractions(m, None, peak.theta2)
            else:
                add += worst or [peak.theta2]
    elif obj == "min_peak_velocity":
        pv, w = m.peak_velocity(1.0), abs(problem.omega2)
        info.update(nlp=z[0] * w, certified=pv.value * w, gap=(pv.value - z[0]) * w)
        if pv.value - z[0] > gap_tol:  # every local extreme of the velocity in the working stroke above the bound
            frac += _working_fractions(m, m.velocity_extremes(), z[0]) or _working_fractions(m, None, pv.theta2)
    elif obj == "min_size" and problem.size == "footprint":
        box = m.bounding_box()
        exact = (box.x_max - box.x_min) * (box.y_max - box.y_min)
        nlp = (z[0] + z[1]) * (z[2] + z[3])
        info.update(nlp=nlp, certified=exact, gap=exact - nlp)
        if exact - nlp > gap_tol * max(1.0, exact):
            add += list(box.angles)
    elif obj == "min_size":
        exact = m.size(problem.size)
        info.update(nlp=f, certified=exact, gap=abs(exact - f) if f is not None else 0.0)
    exceeded = criteria.violations(problem, m)  # a bound the samples missed: add where it is exceeded
    for key, (quantity, _) in criteria.BOUNDS.items():
        if exceeded.get(f"{key} bound (exact)", 0.0) <= feas_tol:  # (feasibility first: it takes a free slot
            continue  # before the objective's angles)
        if quantity == "gamma_min":
            add.insert(0, g.theta2)
        elif quantity == "footprint":
            add += list(m.bounding_box().angles)
        elif quantity == "peak_velocity":
            frac += _working_fractions(m, None, m.peak_velocity().theta2)
        elif quantity == "peak_accel":
            t = m.peak_acceleration(1.0, problem.accel_over).theta2
            if problem.accel_over == "working":
                frac += _working_fractions(m, None, t)
            else:
                add.append(t)
    return m, info, add, frac


def _working_fractions(m, extremes, above):
    """Fractions of the working arc: of the extremes whose |value| exceeds ``above`` (extremes given), or of the
    crank angle ``above`` (extremes None)."""
    lo, length = m.working_arc()
    if extremes is None:
        return [((above - lo) % TWO_PI) / length]
    ts = np.concatenate([extremes.maxima[0], extremes.minima[0]])
    vs = np.concatenate([extremes.maxima[1], extremes.minima[1]])
    order = np.argsort(-np.abs(vs))
    return [((ts[i] - lo) % TWO_PI) / length for i in order if abs(vs[i]) > above and (ts[i] - lo) % TWO_PI <= length]


def residuals(problem, violations: dict, m, targets) -> dict:
    """Named violations (>= 0): the NLP rows but the criteria's epigraphs and lifted extremes, and the targets and
    bound conditions evaluated exactly."""
    res = {k: v for k, v in violations.items() if not k.startswith(("epigraph", "lifted"))}
    if m is not None:
        try:
            q = {"time_ratio": m.time_ratio(), "stroke": m.stroke(), "swing": m.stroke()}
        except QroptError:  # the output reverses more than once a turn: no target is met
            q = dict.fromkeys(("time_ratio", "stroke", "swing"), math.inf)
        for k, v in targets.items():
            res[f"{k} (exact)"] = abs(q[k] - v)
        try:
            res.update(criteria.violations(problem, m))
        except QroptError:
            res["bounds (exact)"] = math.inf
    return res


__all__ = [
    "Certificate",
    "Designs",
    "build",
    "quantities",
    "objective_of",
    "objective_value",
    "better",
    "certify",
    "residuals",
]
