"""A closed-form family that holds every solution: scanned by exact evaluation, its best points queued."""

from __future__ import annotations

from qropt.synthesis.search.base import Stage


class FamilyScan(Stage):
    name = "closed-form family"

    def accepts(self, problem, plan):
        return plan is not None and plan.kind == "family" and plan.searching

    def run(self, problem, pool, context):
        plan = pool.plan
        pool.runs += context.solver.multistart.family_starts(problem, plan, pool.designs)
        pool.claim = (
            f"best along a closed-form family that holds every solution ({plan.how}; {len(plan.analytic)} points)"
        )
