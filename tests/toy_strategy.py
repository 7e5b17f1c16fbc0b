"""A search strategy defined in one file, as a user would: starts on a coarse grid over the free bounds (``per_axis``
points on each, inside the box), queued for the local solves of the starts phase."""

from __future__ import annotations

import itertools

import numpy as np

from qropt.synthesis.search import Stage


class GridStarts(Stage):
    """Every point of a per_axis^n grid over the n free parameters' bounds (n at most 4)."""

    name = "grid starts"

    def __init__(self, per_axis: int = 3):
        self.per_axis = per_axis

    def accepts(self, problem, plan):
        return len(problem.free) <= 4

    def run(self, problem, pool, context):
        axes = [np.linspace(lo, hi, self.per_axis + 2)[1:-1] for lo, hi in problem.free.values()]
        pool.runs += [("grid", dict(zip(problem.free, map(float, v), strict=True))) for v in itertools.product(*axes)]
