"""Each distinct certified design with an angle at an edge of a full-turn box (its width 2 pi), solved again from
that angle taken across the edge (2 pi less or more: the same mechanism), where the box cut its descent."""

from __future__ import annotations

import math

from qropt.synthesis.multistart import distinct
from qropt.synthesis.search.base import Stage

FULL_TURN = 2 * math.pi * (1 - 1e-9)  # an angle's box this wide holds every angle: its edges are one


def turns(problem) -> list:
    """The free angles whose box holds a full turn."""
    kinds = problem.mechanism.kinds()
    return [k for k, (lo, hi) in problem.free.items() if kinds[k] == "angle" and hi - lo >= FULL_TURN]


class Wrapped(Stage):
    name = "across a full turn's edge"

    def accepts(self, problem, plan):
        return bool(turns(problem))

    def run(self, problem, pool, context):
        edge, runs, parents = context.settings.wrap_edge, [], []
        for c in distinct(pool.good):
            for k in turns(problem):
                lo, hi = problem.free[k]
                x = c.values[k]
                if min(x - lo, hi - x) <= edge:
                    across = x - 2 * math.pi if hi - x <= edge else x + 2 * math.pi
                    runs.append(("wrapped", {**c.values, k: min(max(across, lo), hi)}, c.branch))
                    parents.append(c)
        if not runs:
            return
        ms = context.solver.multistart
        out = ms.run(problem, runs, context.targets, context.max_rounds, pool.designs, False, deadline=context.deadline)
        for x in out:
            x.parent = parents[x.start]
        n = len(runs)
        pool.candidates += out
        pool.notes.append(
            f"{n} design{'s' * (n != 1)} at an edge of a full-turn angle's box solved again from across it, "
            f"{sum(c.ok for c in out)} certified"
        )
