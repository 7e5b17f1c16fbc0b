"""Where the type's optima form a continuum (``Mechanism.SYNTHESIS.ties`` free) and the objective is kinematic: of
the designs within ``tie_tol`` of the optimum, the one of least size (the problem's size measure). Along the
continuum by exact evaluation first (``least_along``), else min_size under a bound at the optimum, and alone (where
the targets fix the criterion, the bound is redundant and degenerate), from the optimum first, then along the
closed forms' family; a design is accepted within 2 ``tie_tol`` of the optimum. The optimum stands where none is."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from scipy.optimize import minimize_scalar

from qropt.synthesis import criteria
from qropt.synthesis import starts as starts_
from qropt.synthesis.certificate import Designs, objective_value, quantities
from qropt.synthesis.multistart import score
from qropt.synthesis.search import results
from qropt.synthesis.search.base import Stage


class LeastSize(Stage):
    name = "least-size tie-break"

    def accepts(self, problem, plan):
        c = criteria.of_problem(problem)
        ties = list(problem.mechanism.SYNTHESIS.ties)
        return bool(ties) and set(ties) <= set(problem.free) and c is not None and not c.size and c.kinematic

    def run(self, problem, pool, context):
        r = pool.result
        if r is None or r.status != "optimal":  # a tie of what the certificate does not prove optimal stands
            return
        c, tol_rel = criteria.of_problem(problem), context.settings.tie_tol
        ties = list(problem.mechanism.SYNTHESIS.ties)
        tol = tol_rel * max(1.0, abs(r.objective))
        old = problem.conditions.get(c.bound)

        def within(k):  # k tol worse than the optimum, or the problem's own bound where that is stricter
            v = r.objective - k * tol if c.maximise else r.objective + k * tol
            return old if old is not None and c.better(old, v) else v

        # the bound holds at the sub-solve's design to rounding only: accepted within 2 tol of the optimum, so that
        # a bit either way (a kernel compiled or not) does not decide
        accept = within(2)
        along = least_along(context, problem, r, ties, c, accept, tol)
        if along is not None:
            pool.result = along
            return
        start = [{k: r.params[k] for k in problem.free}]
        sized = criteria.SIZE_OBJECTIVE
        bounded = problem.replace(objective=sized, conditions={**problem.conditions, c.bound: within(1)})
        alone = problem.replace(objective=sized)
        local = {"use_analytic": False, "given": start}
        tries = [(bounded, local), (alone, local)]  # from the optimum first, then along a closed-form family
        if starts_.plan(bounded).kind in ("family", "enumeration"):
            tries += [(bounded, {}), (alone, {})]
        for sub, how in tries:
            s = context.sub(sub, starts_n=0, diagnose=False, **how)
            if s.status == "optimal" and not c.better(accept, s.quantities[c.name]):
                size = s.quantities[criteria.SIZE]
                best = dataclasses.replace(
                    s,
                    objective=objective_value(problem, s.quantities),
                    message=f"{r.message}; optima form a continuum along {', '.join(ties)}: the least "
                    f"{problem.size} ({size:.6g}) within {2 * tol:.1e} of it ({s.certificate.global_claim})",
                    local_optima=(),
                )
                pool.result = dataclasses.replace(best, local_optima=(best, *r.local_optima[1:]))
                return


def least_along(context, problem, r, ties, c, accept, tol):
    """The least-size design of the continuum through the optimum ``r``: its tied lengths scaled together by one
    factor leave the motion, and so every kinematic criterion, the same (``Mechanism.SYNTHESIS.ties``); the size at
    ``tie_scan`` factors log-spaced over what the bounds allow (each design built, its rules, one reversal and the
    bound conditions checked), the least refined by a bounded 1-D search between its neighbours, and of designs
    that small (within ``tie_tol``) the one of the largest tied lengths, then certified by exact evaluation like any
    design. None where it is not certified within ``accept`` of the optimum."""
    s = context.settings
    v0 = {k: r.params[k] for k in problem.free}
    branch = {k: r.params[k] for k in problem.branches}
    if any(v0[k] <= 0 for k in ties):
        return None
    lo = max(math.log(problem.free[k][0] / v0[k]) for k in ties)
    hi = min(math.log(problem.free[k][1] / v0[k]) for k in ties)
    if not lo < hi:
        return None
    designs, sized = Designs(), problem.replace(objective=criteria.SIZE_OBJECTIVE)

    def at(u):
        v = dict(v0)
        for k in ties:
            v[k] = min(max(v0[k] * math.exp(u), problem.free[k][0]), problem.free[k][1])
        return v

    def size(u):
        f, _ = score(sized, at(float(u)), branch, designs)
        return math.inf if f is None else f

    us = np.linspace(lo, hi, s.tie_scan)
    sizes = np.array([size(u) for u in us])
    i = int(np.argmin(sizes))
    if not np.isfinite(sizes[i]):
        return None
    a, b = us[max(i - 1, 0)], us[min(i + 1, s.tie_scan - 1)]
    found = minimize_scalar(size, bounds=(a, b), method="bounded", options={"xatol": 1e-9 * max(1.0, hi - lo)})
    u, least = (float(found.x), float(found.fun)) if found.fun <= sizes[i] else (float(us[i]), float(sizes[i]))
    # the size can be flat along the continuum (the lever's sweep spans the box): of the least, the largest tied
    # lengths (the same motion and torque with the least crank-pin force), their edge found by bisection from the
    # last scale within tie_tol of the least size
    level = least * (1.0 + s.tie_tol)
    small = np.flatnonzero(sizes <= level)
    if small.size and us[small[-1]] > u:
        j = int(small[-1])
        u = float(us[j])
        if j < s.tie_scan - 1:
            inside, out = u, float(us[j + 1])
            for _ in range(s.tie_bisect):
                mid = 0.5 * (out + inside)
                inside, out = (mid, out) if size(mid) <= level else (inside, mid)
            u = inside
    cand = context.solver.local_solve.evaluate(problem, at(u), branch, context.targets, designs)
    if not cand.ok:
        return None
    cand.q = quantities(problem, cand.mechanism)
    if c.better(accept, cand.q[c.name]):
        return None
    claim = (
        f"{r.certificate.global_claim}; optima form a continuum along {' and '.join(ties)} scaled together: "
        f"the least {problem.size} ({cand.q[criteria.SIZE]:.6g}) by exact evaluation at {s.tie_scan} scales and a "
        f"bounded 1-D search, within {2 * tol:.1e} of the optimum"
    )
    best = results.result(context.solver, problem, cand, None, claim, r.stats)
    return dataclasses.replace(best, local_optima=(best, *r.local_optima[1:]))
