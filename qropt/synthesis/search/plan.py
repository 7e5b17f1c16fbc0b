"""The plan of starts (``starts.plan``: the closed forms and what they cover, the atlas's designs), and the
space-filling starts grown with the free parameters unless the solve named their number."""

from __future__ import annotations

import dataclasses

from qropt.synthesis import starts
from qropt.synthesis.search.base import Stage


class Planned(Stage):
    name = "plan"
    finishing = True

    def run(self, problem, pool, context):
        plan = starts.plan(problem, context.use_analytic, context.solver.atlas)
        pool.plan = dataclasses.replace(plan, given=len(context.given))
        if not context.asked:
            context.starts_n = starts.grown(context.starts_n, problem, pool.plan)
