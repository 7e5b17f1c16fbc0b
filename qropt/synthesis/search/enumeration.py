"""A closed form that enumerates every design: each point polished in every branch (no multi-start)."""

from __future__ import annotations

from qropt.synthesis import starts
from qropt.synthesis.search.base import Stage


class Enumeration(Stage):
    name = "enumeration"

    def accepts(self, problem, plan):
        return plan is not None and plan.kind == "enumeration" and plan.searching

    def run(self, problem, pool, context):
        local = context.solver.local_solve
        for v in pool.plan.analytic:
            for br in starts.branches(problem):
                pool.candidates.append(local.polish(problem, v, br, context.targets, pool.designs))
        pool.claim = f"by enumeration: {pool.plan.how}"
