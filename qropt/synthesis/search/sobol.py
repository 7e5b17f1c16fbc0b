"""A scrambled Sobol design of ``starts_n`` starts over the bounds, thinned by the type's rules
(``starts.sobol``)."""

from __future__ import annotations

from qropt.synthesis import starts
from qropt.synthesis.search.base import Stage, spread


class Sobol(Stage):
    name = "Sobol multi-start"

    def run(self, problem, pool, context):
        if not spread(pool, context):
            return
        pool.runs += [("multistart", v) for v in starts.sobol(problem, context.starts_n, context.seed, pool.designs)]
