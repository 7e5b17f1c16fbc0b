"""Where no space-filling start gives a certified design, each of them again in both ways of meeting the TR
equality: here, or deferred to the diagnosis (``Pool.retry``) where one may run."""

from __future__ import annotations

from qropt.synthesis.search.base import Stage


class BothWays(Stage):
    name = "second pass"

    def accepts(self, problem, plan):
        return plan is not None and plan.spread

    def run(self, problem, pool, context):
        spread = [r for r in pool.runs if r[0] == "multistart"]
        if not spread or any(c.ok for c in pool.candidates):
            return
        ms, designs = context.solver.multistart, pool.designs

        def again():  # the other way of meeting the TR equality
            return ms.run(
                problem, spread, context.targets, context.max_rounds, designs, True, deadline=context.deadline
            )

        if context.diagnose:
            pool.retry = again
        else:
            pool.candidates += again()
