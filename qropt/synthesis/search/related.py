"""For a dynamic objective, the atlas's optima of the same shape by the kinematic criteria, queued (from the
backend's default barrier)."""

from __future__ import annotations

from qropt.synthesis.search.base import Stage, spread


class Related(Stage):
    name = "related atlas optima"

    def accepts(self, problem, plan):
        return plan is not None and bool(plan.related.designs)

    def run(self, problem, pool, context):
        if context.given or not spread(pool, context):
            return
        pool.runs += [("related", v, b) for v, b in pool.plan.related.designs]
