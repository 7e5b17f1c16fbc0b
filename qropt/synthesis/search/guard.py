"""For a criterion that declares a transmission guard (``Criterion.guard``) above the problem's own bound, where no
closed form enumerates or walks the designs: the starts phase again on the problem with gamma_min >= guard, and
each distinct design it certifies continued to the problem (``MultiStart.continued``)."""

from __future__ import annotations

import math

from qropt.synthesis import criteria
from qropt.synthesis.multistart import distinct, under
from qropt.synthesis.search.base import Stage


def guard_of(problem, plan) -> float | None:
    """The guard (rad) that applies to the problem with this plan, else None."""
    c = criteria.of_problem(problem)
    if c is None or c.guard is None or plan is None or plan.kind not in ("none", "partial") or not plan.searching:
        return None
    return c.guard if problem.conditions.get(criteria.GUARDED, 0.0) < c.guard else None


class Guarded(Stage):
    name = "transmission guard"

    def accepts(self, problem, plan):
        return guard_of(problem, plan) is not None

    def run(self, problem, pool, context):
        guard, ms = guard_of(problem, pool.plan), context.solver.multistart
        found, _, _ = context.multistart(under(problem, guard), pool.plan, context.starts_n, context.seed, pool.designs)
        good = distinct([x for x in found if x.ok])
        out = []
        for g in good:
            if context.out_of_time():
                break
            x = ms.continued(problem, g, guard, context.targets, context.max_rounds, pool.designs, context.deadline)
            if x:
                x.origin, x.parent = "guard", g
                out.append(x)
        own = problem.conditions.get(criteria.GUARDED, 0.0)
        to = "the problem's bound" if own > 0 else "none"
        kept = f"{len(good)} distinct design{'s' * (len(good) != 1)}"
        pool.notes.append(
            f"{kept} of {len(found)} starts under a transmission guard (gamma_min >= {math.degrees(guard):g} "
            f"deg) continued to {to}, {len(out)} certified"
        )
        pool.more += out
        if found:
            pool.spent.update(
                guarded_starts=len(found),
                guarded_ipopt_runs=sum(len(c.statuses) for c in found),
                t_ipopt_guarded=sum(c.t_ipopt for c in found),
            )
