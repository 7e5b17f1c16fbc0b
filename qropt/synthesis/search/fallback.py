"""Where no closed-form point refines to a design (or the closed form missed) and no diagnosis is asked for: the
problem solved again without the closed forms (the space-filling starts)."""

from __future__ import annotations

from qropt.synthesis.search.base import STOP, Stage


class WithoutClosedForms(Stage):
    name = "without closed forms"

    def accepts(self, problem, plan):
        return plan is not None and plan.kind in ("family", "enumeration") and plan.searching

    def run(self, problem, pool, context):
        if pool.good or context.diagnose:
            return None
        pool.result = context.sub(problem, use_analytic=False, diagnose=False, targets=context.targets)
        return STOP
