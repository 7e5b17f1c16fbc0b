"""The diagnosis of a solve without a certified design: why, within a budget.

A target beyond the range the type reaches within the bounds, a bound condition beyond the best value of its
criterion among designs that meet the targets, or nothing that meets everything together; a design meeting
every target and condition found on the way turns the answer into 'failed' (the optimum was not reached), never
'infeasible'.
"""

from __future__ import annotations

import math
import time

from qropt.synthesis import criteria
from qropt.synthesis.backends import PROVES
from qropt.synthesis.result import Result


class Diagnosis:
    """Says why a solve found no certified design, with the Solver's parts (its multi-start and target ranges)."""

    def __init__(self, solver):
        self.solver = solver

    def run(self, problem, cands, targets, starts_n, seed, stats, t0) -> Result:
        """No certified design: say why (a target out of its reachable range, or nothing meets all together)."""
        reasons = sorted({c.info.get("reason", "") or ", ".join(c.statuses[-1:]) for c in cands})
        beyond, found = self.bound_out_of_reach(problem, targets, starts_n, seed)
        if beyond:
            stats["t_total"] = time.perf_counter() - t0
            return Result("infeasible", beyond[0], stats=stats, reachable=beyond[1])
        if found:  # a design optimising a bounded criterion meets every bound: refine from it
            r = self.solver.solve(problem, targets=targets, starts_n=0, seed=seed, extra_starts=found, diagnose=False)
            if r.success:
                return r
        if problem.objective and not found:  # is there any design at all? (then the objective's solves failed)
            r = self.solver.solve(
                problem.replace(objective=None), targets=targets, starts_n=starts_n, seed=seed, diagnose=False
            )
            found = [{k: r.params[k] for k in problem.free}] if r.success else []
        reach, msgs = {}, []
        for k, v in targets.items():
            lo, hi = self.solver.target_range(problem, k, targets, starts_n=starts_n, seed=seed)
            reach[k] = (lo, hi)
            msgs.append(_range_message(problem, k, v, lo, hi))
        stats["t_total"] = time.perf_counter() - t0
        outside = [m for (k, (lo, hi)), m in zip(reach.items(), msgs, strict=True) if not _inside(targets[k], lo, hi)]
        if outside:
            return Result("infeasible", "; ".join(outside), stats=stats, reachable=reach)
        if all(
            max(c.residuals.values(), default=0.0) > self.solver.tolerances["feasibility"] or c.mechanism is None
            for c in cands
        ):
            ends: dict = {}
            for c in cands:
                k = c.statuses[-1] if c.statuses else "no run"
                ends[k] = ends.get(k, 0) + 1
            proved = any(c.ends and c.ends[-1] in PROVES for c in cands)
            how = ", ".join(f"{n} {k}" for k, n in sorted(ends.items(), key=lambda kv: -kv[1]))
            msg = f"none of {len(cands)} starts reaches a design meeting the targets and conditions together "
            msg += f"(IPOPT: {how}), though each target alone can be met (" + "; ".join(msgs) + ")"
            # IPOPT's own failures (invalid numbers, iteration limits) prove nothing: only converged or
            # infeasible-detected runs make the problem infeasible
            if found:  # a design meeting every target and condition exists: the objective's solves failed
                shown = ", ".join(f"{k}={v:.6g}" for k, v in found[0].items())
                msg += (
                    f"; designs meeting every target and condition exist (one: {shown}), so the {problem.objective}"
                    " optimum was not reached (it may lie at a singular limit: a dead point, a link of zero "
                    "length or a bound)"
                )
                return Result("failed", msg, stats=stats, reachable=reach)
            return Result("infeasible" if proved else "failed", msg, stats=stats, reachable=reach)
        why = "; ".join(r for r in reasons[:3] if r)
        return Result(
            "failed",
            f"no start converged to a certified design ({why}); " + "; ".join(msgs),
            stats=stats,
            reachable=reach,
        )

    def bound_out_of_reach(self, problem, targets, starts_n, seed):
        """((message, {quantity: (low, high)}) if a bound condition is beyond what any design meeting the targets
        and the other conditions reaches (its best value, from a solve optimising it), else None; and the designs
        of those solves that meet every bound, as starts)."""
        found = []
        for key, c in criteria.bounds().items():
            bound = problem.conditions.get(key)
            if bound is None:
                continue
            quantity = c.name
            sub = problem.replace(
                objective=c.objective,
                size=c.size or problem.size,
                conditions={k: v for k, v in problem.conditions.items() if k != key},
            )
            r = self.solver.solve(sub, targets=targets, starts_n=starts_n, seed=seed)
            if r.status not in ("optimal", "acceptable"):
                continue
            tol = self.solver.tolerances["feasibility"]
            found += [
                {k: o.params[k] for k in problem.free}
                for o in r.local_optima or (r,)
                if max(criteria.violations(problem, o.mechanism).values(), default=0.0) <= tol
            ]
            best = r.objective
            if c.better(bound, best):
                span = (0.0, best) if c.maximise else (best, math.inf)
                word = "largest" if c.maximise else "smallest"

                def show(v, c=c):
                    deg = f" ({math.degrees(v):.2f} deg)" if c.unit == "rad" else ""
                    return f"{v:.6g} {c.unit}{deg}"

                msg = (
                    f"{key} {show(bound)} is beyond reach: the {word} {quantity} of a design meeting the "
                    f"targets and the other conditions is {show(best)} ({r.certificate.global_claim})"
                )
                return (msg, {quantity: span}), []
        return None, found


def _inside(v, lo, hi) -> bool:
    """v within a found range, to 1e-6 relative: the range's ends are designs found, not proofs of an end."""
    tol = 1e-6 * max(1.0, abs(v))
    return lo - tol <= v <= hi + tol


def _range_message(problem, k, v, lo, hi):
    bounds = ", ".join(f"{n} in [{a:g}, {b:g}]" for n, (a, b) in problem.free.items())
    if not math.isfinite(lo):
        return f"no design turns fully and meets the conditions for {bounds}"
    where = "inside" if _inside(v, lo, hi) else "below" if v < lo else "above"
    return f"{k} {v:g} is {where} the reachable {lo:.6g}..{hi:.6g} for {bounds}"
