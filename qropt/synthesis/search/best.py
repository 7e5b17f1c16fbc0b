"""The certified candidates' Result, best first, with every distinct local optimum (``results.best``)."""

from __future__ import annotations

from qropt.synthesis.search import results
from qropt.synthesis.search.base import Stage


class Best(Stage):
    name = "best certified"
    finishing = True

    def run(self, problem, pool, context):
        if pool.good:
            pool.result = results.best(
                context.solver, problem, pool.candidates, pool.claim, pool.plan, context.t0, pool.guard
            )
