"""Shapes best by the objective's grid value among many (``starts.shapes``), for a criterion that declares one
(``Criterion.grid_value``)."""

from __future__ import annotations

from qropt.synthesis import criteria, starts
from qropt.synthesis.search.base import Stage


class Shapes(Stage):
    name = "shape search"

    def accepts(self, problem, plan):
        return plan is not None and plan.spread and plan.searching and criteria.grid_criterion(problem) is not None

    def run(self, problem, pool, context):
        pool.runs += [
            ("shape", v) for v in starts.shapes(problem, context.settings.shape_keep, context.seed, context.settings)
        ]
