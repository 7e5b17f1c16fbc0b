"""The queued starts, each solved locally (``MultiStart.run``: the incumbent prunes starts that cannot beat it)."""

from __future__ import annotations

from qropt.synthesis.search.base import Stage


class LocalSolves(Stage):
    name = "local solves"

    def run(self, problem, pool, context):
        ms = context.solver.multistart
        pool.candidates += ms.run(
            problem,
            pool.runs,
            context.targets,
            context.max_rounds,
            pool.designs,
            both_ways=False,
            hint=context.hint,
            deadline=context.deadline,
        )
