"""A bound condition checked against its own optimum before the starts, where the atlas holds that optimum's
problem (a solve of a fraction of a second): a bound beyond what any design meeting the targets and the other
conditions reaches makes the solve 'infeasible' at once, with the diagnosis's words (its first step, which
otherwise runs after every start has failed)."""

from __future__ import annotations

import time

from qropt.synthesis import atlas as atlas_
from qropt.synthesis.result import Result
from qropt.synthesis.search import results
from qropt.synthesis.search.base import STOP, Stage
from qropt.synthesis.search.diagnosis import bound_out_of_reach, bound_problems


class BoundsInReach(Stage):
    name = "bounds in reach"

    def accepts(self, problem, plan):
        if plan is None or not (plan.spread and plan.searching) or (plan.atlas.designs and not plan.atlas.unbounded):
            return False  # a closed form or the atlas answers the problem itself as quickly
        return any(atlas_.starts(sub).designs for _, _, sub in bound_problems(problem))

    def run(self, problem, pool, context):
        if not (context.diagnose and context.solver.atlas):
            return None
        n = min(context.starts_n, context.settings.diagnosis_starts)
        beyond, _ = bound_out_of_reach(context, problem, n, atlas_only=True)
        if not beyond:
            return None
        stats = {**results.stats(context.solver, problem, [], pool.plan), "t_total": time.perf_counter() - context.t0}
        pool.result = Result("infeasible", beyond[0], stats=stats, units=problem.units, reachable=beyond[1])
        return STOP
