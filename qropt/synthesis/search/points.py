"""The closed forms' points (where they neither enumerate nor walk every design): queued, or where there are more
than ``many_starts``, scored by exact evaluation and only the best few queued."""

from __future__ import annotations

from qropt.synthesis.search.base import Stage


class ClosedFormPoints(Stage):
    name = "closed-form points"

    def accepts(self, problem, plan):
        return plan is not None and bool(plan.analytic) and plan.spread

    def run(self, problem, pool, context):
        plan = pool.plan
        if len(plan.analytic) > context.settings.many_starts and plan.searching:
            best = context.solver.multistart.family_starts(problem, plan, pool.designs)
            pool.runs += [("analytic", v, *b) for _, v, *b in best]
        else:
            pool.runs += [("analytic", v) for v in plan.analytic]
