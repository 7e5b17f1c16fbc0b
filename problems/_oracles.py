"""Oracles of the benchmark problems (``problems/``), independent of the NLP: the best of a set of
closed-form designs, or a dense grid along a one-parameter closed-form family with bounded-Brent refinement.
Designs are evaluated by qropt's exact analysis (itself checked against an independent brute-force simulator
in tests/); the search over designs never uses the NLP."""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq, minimize_scalar

from qropt import QroptError
from qropt.synthesis import analytic, criteria
from qropt.synthesis.certificate import better, objective_value, quantities


def score(problem, values: dict):
    """(objective, quantities) of a design, or None if it does not build, or violates a bound or a condition."""
    if any(not (lo - 1e-12 <= values[k] <= hi + 1e-12) for k, (lo, hi) in problem.free.items()):
        return None
    branch = {k: v[0] for k, v in problem.branches.items()}
    try:
        m = problem.build({k: values[k] for k in problem.free}, branch)
        q = quantities(problem, m)
    except QroptError:
        return None
    if m.dead_centres().reversals != 1:
        return None
    if any(v > 1e-12 for v in criteria.violations(problem, m).values()):
        return None
    return objective_value(problem, q), q


def candidate(problem, values: dict):
    """``score`` of a closed form's design, or None if it misses a target (a point outside the closed form's range
    of validity is no design of the task)."""
    s = score(problem, values)
    if s is None or any(abs(s[1][k] - v) > 1e-8 * max(1.0, abs(v)) for k, v in problem.targets.items()):
        return None
    return s


def best_of(problem, candidates):
    """The best of closed-form candidate designs: {'objective', 'params'}."""
    best, where = None, None
    for c in candidates:
        s = candidate(problem, c)
        if s is not None and better(problem, s[0], best):
            best, where = s[0], dict(c)
    return {"objective": best, "params": where}


def along(problem, design, lo, hi, n=400, boundary=None):
    """Dense grid along a 1-D family ``design(t) -> params or None`` for t in [lo, hi], refined by bounded Brent
    around the best grid point; if ``boundary(t)`` is given (>= 0 where the design is acceptable, e.g. a
    gamma_min margin), sign changes of it are refined by brentq and included."""
    sign = -criteria.sense(problem.objective)

    def f(t):
        d = design(t)
        s = candidate(problem, d) if d is not None else None
        return math.inf if s is None else sign * s[0]

    ts = np.linspace(lo, hi, n)
    vals = np.array([f(t) for t in ts])
    cands = [(vals[i], ts[i]) for i in range(n)]
    i = int(np.argmin(vals))
    if math.isfinite(vals[i]):
        a, b = ts[max(i - 1, 0)], ts[min(i + 1, n - 1)]
        with np.errstate(invalid="ignore"):  # a neighbour may not work (score inf): Brent copes
            r = minimize_scalar(f, bounds=(a, b), method="bounded", options={"xatol": 1e-13})
        cands.append((r.fun, r.x))
    if boundary is not None:
        m = np.array([boundary(t) for t in ts])
        for k in np.flatnonzero(np.isfinite(m[:-1]) & np.isfinite(m[1:]) & (np.sign(m[:-1]) != np.sign(m[1:]))):
            t = brentq(boundary, ts[k], ts[k + 1], xtol=1e-15)
            for tt in (t, t + 1e-13 * np.sign(m[k + 1] - m[k])):
                cands.append((f(tt), tt))
    v, t = min(cands)
    return {"objective": sign * v if math.isfinite(v) else None, "params": design(t)}


def paper(problem):
    """The best closed-form design of the paper's linkage (r1, r2, r4 = 0.1, 0.225, 0.275 m) for a problem."""
    return best_of(problem, drag_link(problem, 0.1, 0.225, 0.275, problem.targets["stroke"]))


def drag_link(problem, r1, r2, r4, stroke):
    """Closed-form designs of the drag-link slider (h = 0): every root of eqs. (7)-(13), r5 = stroke / 2."""
    tr = problem.targets["time_ratio"]
    return [{"r3": s.r3, "r5": stroke / 2} for s in analytic.drag_link_r3(tr, r1, r2, r4)]


def slider_crank_family(tr, stroke):
    """r2 -> the offset slider-crank (e > 0) with this TR and stroke (the stroke triangle), or None."""

    def design(r2):
        d = analytic.slider_crank_design(tr, stroke, r2)
        return {"r2": r2, "r3": d[0].r3, "e": d[0].e} if d else None

    return design


def crank_rocker_r3(tr, r1, r2, r4):
    """Every r3 of a crank-rocker (r1, r2, r4 given) whose rocker TR is tr, on a finer grid than the starts'."""
    return analytic.crank_rocker_r3(tr, r1, r2, r4, n=400)


def crank_rocker_slider_family(tr, stroke, r1, r2, r6, pick):
    """r4 -> a crank-rocker slider (h = 0) with this TR and stroke: r3 from the rocker TR, r5 from the stroke
    (both by brentq on closed forms); ``pick`` chooses among several r3 roots (index)."""

    def design(r4):
        roots = crank_rocker_r3(tr, r1, r2, r4)
        if len(roots) <= pick:
            return None
        r3 = roots[pick]
        arms = analytic.rocker_slider_r5(stroke, r1, r2, r3, r4, r6, n=200)
        return {"r3": r3, "r4": r4, "r5": arms[0]} if arms else None

    return design
