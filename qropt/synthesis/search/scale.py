"""A problem far from unit scale is solved at unit scale (the tolerances are absolute) and its Result scaled back
(``qropt.synthesis.scaling``)."""

from __future__ import annotations

import dataclasses

from qropt.synthesis import scaling
from qropt.synthesis.search.base import STOP, Stage


class UnitScale(Stage):
    name = "unit scale"
    finishing = True

    def accepts(self, problem, plan):
        return scaling.factor(problem) != 1.0

    def run(self, problem, pool, context):
        k = scaling.factor(problem)
        given = [{n: v * k for n, v in e.items()} for e in context.given]
        r = context.sub(scaling.scaled(problem, k), given=given, use_analytic=context.use_analytic)
        r = scaling.unscaled(r, problem, k)
        if not r.success:
            r = dataclasses.replace(r, message=f"{r.message} (lengths in this message are {k:g} times the problem's)")
        pool.result = r
        return STOP
