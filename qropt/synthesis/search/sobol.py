"""A scrambled Sobol design of ``starts_n`` starts over the bounds, thinned by the type's rules
(``starts.sobol``)."""

from __future__ import annotations

from qropt.synthesis import starts
from qropt.synthesis.search.base import Stage


class Sobol(Stage):
    name = "Sobol multi-start"

    def accepts(self, problem, plan):
        return plan is not None and plan.spread

    def run(self, problem, pool, context):
        pool.runs += [
            ("multistart", v)
            for v in starts.sobol(problem, context.starts_n, context.seed, pool.designs, context.settings)
        ]
