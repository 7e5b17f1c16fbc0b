"""Where a closed form that gives every design gives no valid one and no diagnosis is asked for: 'infeasible',
with the closed form's words."""

from __future__ import annotations

import time

from qropt.synthesis.result import Result
from qropt.synthesis.search.base import STOP, Stage


class ProvedInfeasible(Stage):
    name = "proof by enumeration"
    finishing = True

    def accepts(self, problem, plan):
        return plan is not None and plan.kind == "enumeration" and plan.searching

    def run(self, problem, pool, context):
        if pool.good or context.diagnose:
            return None
        plan, cands = pool.plan, pool.candidates
        why = sorted({c.info.get("reason", "") or "it breaks a condition" for c in cands})
        msg = f"no design: the closed form that gives every design ({plan.how}) gives "
        msg += f"{plan.outside + len(cands)}" if plan.outside or cands else "none for these targets"
        msg += f", {plan.outside} outside the bounds" if plan.outside else ""
        msg += f"; {len(cands)} fail ({'; '.join(why[:3])})" if cands else ""
        stats = {"plan": plan.kind, "starts": len(cands), "t_total": time.perf_counter() - context.t0}
        pool.result = Result("infeasible", msg, stats=stats, units=problem.units)
        return STOP
