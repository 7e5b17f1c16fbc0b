"""A family point where IPOPT ended without a design: a bounded 1-D search of the exact objective along the family
instead (``MultiStart.walked``)."""

from __future__ import annotations

from qropt.synthesis.search.base import Stage


class FamilyWalk(Stage):
    name = "family walk"

    def accepts(self, problem, plan):
        family = plan is not None and plan.kind == "family" and plan.searching
        return family and plan.walk is not None and bool(problem.objective)

    def run(self, problem, pool, context):
        ms = context.solver.multistart
        failed = [
            (pool.runs[c.start], c) for c in pool.candidates if c.origin == "family" and not c.ok and not c.pruned
        ]
        walked = [w for run, c in failed if (w := ms.walked(problem, pool.plan, run, c, context.targets, pool.designs))]
        if any(c.ok for c in walked):
            pool.claim += (
                f"; from {sum(c.ok for c in walked)} point(s) where IPOPT ended without a design, a bounded 1-D "
                f"search of the exact objective along the family's {pool.plan.walk.name} instead"
            )
        pool.candidates += walked
