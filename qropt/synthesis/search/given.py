"""Given starts (``extra_starts``, a neighbour's optimum): queued first, in their own TR orientation."""

from __future__ import annotations

from qropt.synthesis.search.base import Stage


class Given(Stage):
    name = "given starts"

    def accepts(self, problem, plan):
        return plan is not None and plan.given > 0

    def run(self, problem, pool, context):
        pool.runs += [("given", v) for v in context.given]
