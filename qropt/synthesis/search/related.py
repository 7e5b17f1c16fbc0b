"""For a dynamic objective, the atlas's optima of the same shape by the kinematic criteria, queued (from the
backend's default barrier)."""

from __future__ import annotations

from qropt.synthesis.search.base import Stage


class Related(Stage):
    name = "related atlas optima"

    def accepts(self, problem, plan):
        return plan is not None and bool(plan.related.designs) and plan.spread and plan.searching

    def run(self, problem, pool, context):
        pool.runs += [("related", v, b) for v, b in pool.plan.related.designs]
