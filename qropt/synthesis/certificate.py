"""Exact evaluation of a candidate design: the quantities a Result reports, and the certificate of an NLP point.

Every number here comes from the exact cycle analysis of the rebuilt mechanism, never from the NLP's
sample angles; the exchange loop adds the angles where the two disagree.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from qropt.errors import AssemblyError, QroptError, SlideLocked
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

    @classmethod
    def from_dict(cls, d) -> Certificate:
        """The Certificate of ``to_dict``; ProblemError naming the first field of the wrong type."""
        from qropt.errors import ProblemError

        def num(v):
            return isinstance(v, (int, float)) and not isinstance(v, bool)

        checks = {
            "exact": (lambda v: isinstance(v, bool), "true or false"),
            "nlp": (lambda v: v is None or num(v), "null or a number"),
            "certified": (lambda v: v is None or num(v), "null or a number"),
            "gap": (num, "a number"),
            "rounds": (lambda v: isinstance(v, int) and not isinstance(v, bool) and v >= 0, "a count"),
            "local": (lambda v: isinstance(v, str), "a string"),
            "global_claim": (lambda v: isinstance(v, str), "a string"),
        }
        if not isinstance(d, dict) or set(d) - set(checks) or set(checks) - {"global_claim"} - set(d):
            raise ProblemError(f"a certificate is a table of {list(checks)}, got {d!r:.80}")
        for k, v in d.items():
            if not checks[k][0](v):
                raise ProblemError(f"certificate {k} must be {checks[k][1]}, got {v!r:.80}")
        return cls(**d)


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
    """Exact quantities of a mechanism for a Result (angles in rad, lengths in the problem's units): time_ratio,
    the travel (stroke or swing), gamma_min; for a slider peak_accel at the problem's omega2 over its
    ``accel_over`` span, peak_velocity at omega2 over the working stroke and the peak crank torque per newton of
    cutting force; grashof, size by the problem's measure, working_direction; and every other registered
    criterion that applies to the type (one not ``reported`` where the problem uses it alone)."""
    slider = m.OUTPUT == "slider"
    q = {"time_ratio": m.time_ratio(), "gamma_min": m.gamma_min().value, m.TRAVEL: m.stroke()}
    q["peak_accel"] = m.peak_acceleration(problem.omega2, problem.accel_over).value if slider else None
    pv = m.peak_velocity(problem.omega2) if slider else None
    q["peak_velocity"] = pv.value if slider else None
    q["torque_per_newton"] = pv.torque_per_newton if slider else None
    q["grashof"] = m.grashof().kind if m.FOUR_BAR else None
    q["size"] = m.size(problem.size)
    q["working_direction"] = m.working_direction(problem.omega2)
    for c in criteria.reported(problem, type(m)):
        if c.name not in q and c.name not in criteria.SIZES:  # above (the size by the problem's measure)
            q[c.name] = c.value(problem, m)
    return q


def angle_gap(a, b):
    return abs((a - b + math.pi) % TWO_PI - math.pi)


def certify(problem, form, values, branch, th, z, f, gap_tol, feas_tol, build=build, concrete=None):
    """Exact check of an NLP point of Formulation ``form``. Returns (mechanism or None, info dict, angles to add,
    working-arc fractions to add).

    z: the epigraph values and f the NLP objective (z None for a point that did not come from the NLP);
    concrete: the problem as the point fixes it (a free counterweight chosen), which the exact values use.
    """
    try:
        m = build(problem, values, branch)
        return _certify(concrete or problem, form, m, th, z, f, gap_tol, feas_tol)
    except AssemblyError as e:
        mids = [((lo + hi) / 2) % TWO_PI for _, lo, hi in e.failures]
        return None, {"ok": False, "reason": str(e)}, mids, []
    except SlideLocked as e:  # the angle becomes a sample, where the NLP keeps the slide from locking
        return None, {"ok": False, "reason": str(e)}, [e.theta2], []
    except QroptError as e:
        return None, {"ok": False, "reason": str(e)}, [], []


def _certify(problem, form, m, th, z, f, gap_tol, feas_tol):
    d = m.dead_centres()
    if angle_gap(d.theta_max, th[0]) > 1e-7 or angle_gap(d.theta_min, th[1]) > 1e-7:
        why = "the NLP's dead centres are local, not the global extremes"  # the true ones become samples
        ends = [t for t, nlp in ((d.theta_max, th[0]), (d.theta_min, th[1])) if angle_gap(t, nlp) > 1e-7]
        return m, {"ok": False, "reason": why, "guard": True}, ends, []
    if d.reversals != 1:
        why = f"the output reverses {d.reversals} times a turn"
        return m, {"ok": False, "reason": why, "guard": True, "monotone": wrong_way(m, *th)}, [], []
    info = {"ok": True, "nlp": None, "certified": None, "gap": 0.0}
    add, frac = [], []
    if z is None:  # an enumerated point: the exact value only
        info["certified"] = form.objective.value(problem, m) if form.objective else None
    elif form.objective is not None:
        ex = form.exchange(problem, m, z, f, gap_tol)
        info.update(nlp=ex.nlp, certified=ex.certified, gap=ex.gap)
        add, frac = list(ex.angles), list(ex.fractions)
    exceeded = criteria.violations(problem, m)  # a bound the samples missed: add where it is exceeded, first
    for key, c in reversed(criteria.bounds().items()):  # (feasibility takes free slots before the objective)
        if exceeded.get(f"{key} bound (exact)", 0.0) > feas_tol:
            angles, fractions = c.exceeded(problem, m)
            add, frac = list(angles) + add, list(fractions) + frac
    return m, info, add, frac


WRONG_WAY_GRID = 720  # crank angles where a design that reverses inside a stroke is looked at


def wrong_way(m, theta_max, theta_min) -> list[tuple[int, float]]:
    """(stroke, fraction) where the output moves fastest against its stroke, for dead centres at theta_max and
    theta_min (the NLP's; where they are local extremes, the output turns back inside a stroke): stroke 0 falls
    from theta_max to theta_min (ccw), stroke 1 rises on the rest of the turn; fraction: 0..1 along it. One per
    stroke at most."""
    th = np.linspace(0.0, TWO_PI, WRONG_WAY_GRID, endpoint=False)
    v = np.asarray(m.slider(th).v, float)
    fall = (theta_min - theta_max) % TWO_PI
    u = (th - theta_max) % TWO_PI
    falling = u < fall
    out = []
    for stroke, inside, sign, start, arc in ((0, falling, 1.0, 0.0, fall), (1, ~falling, -1.0, fall, TWO_PI - fall)):
        wrong = np.where(inside & np.isfinite(v), sign * v, -np.inf)
        k = int(np.argmax(wrong))
        if wrong[k] > 0 and arc > 0:
            out.append((stroke, float((u[k] - start) / arc)))
    return out


def target_values(m) -> dict:
    """The quantities a target names, exactly: time_ratio, and the travel as stroke and as swing."""
    travel = m.stroke()
    return {"time_ratio": m.time_ratio(), "stroke": travel, "swing": travel}


def residuals(problem, violations: dict, m, targets) -> dict:
    """Named violations (>= 0): the NLP's rows of the design (``Formulation.violations``), and the targets and
    bound conditions evaluated exactly."""
    res = dict(violations)
    if m is not None:
        try:
            q = target_values(m)
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
    "target_values",
    "wrong_way",
]
