"""For a dynamic objective, the best design solved again from itself with a fresh NLP (its samples and lifted
extremes placed anew), up to ``refreshes`` times while that improves it by more than ``tie_tol``: the exchange
loop's samples can hold a design that a fresh start at it leaves for a better one nearby."""

from __future__ import annotations

import dataclasses

from qropt.synthesis import criteria
from qropt.synthesis.search.base import Stage


class Refresh(Stage):
    name = "solved again from the best"

    def accepts(self, problem, plan):
        c = criteria.of_problem(problem)
        return c is not None and not c.kinematic and plan is not None and plan.searching

    def run(self, problem, pool, context):
        r = pool.result
        if r is None or r.status != "optimal":
            return
        c, s = criteria.of_problem(problem), context.settings
        best, times = r, 0
        for _ in range(s.refreshes):
            start = [{k: best.params[k] for k in problem.free}]
            x = context.sub(problem, starts_n=0, given=start, use_analytic=False, diagnose=False)
            if x.status != "optimal" or not c.better(x.objective, best.objective):
                break
            if abs(x.objective - best.objective) <= s.tie_tol * max(1.0, abs(best.objective)):
                break
            best, times = x, times + 1
        if best is r:
            return
        again = "once" if times == 1 else f"{times} times"
        claim = f"{r.certificate.global_claim}; its best design solved again from itself, better {again}"
        cert = dataclasses.replace(best.certificate, global_claim=claim)
        message = best.message.replace(best.certificate.global_claim, claim)
        best = dataclasses.replace(best, certificate=cert, message=message, local_optima=(), stats=r.stats)
        pool.result = dataclasses.replace(best, local_optima=(best, *r.local_optima[1:]))
