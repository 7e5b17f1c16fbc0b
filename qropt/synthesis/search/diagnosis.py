"""The diagnosis of a solve without a certified design: why, within a stated budget.

In order, each step only where the ones before said nothing:
1. each bound condition against the best value of its criterion among designs that meet the targets (one solve
   of that criterion, without diagnosis): a bound beyond it is 'infeasible', and that solve's designs that meet
   every bound start one refinement of the problem;
2. each target against its range (``Solver.target_range``: sampled designs and ``range_solves`` local solves): a
   range is sampled, so a target outside it is said, not proved absent ('infeasible' only where a complete
   closed form gives no design);
3. a feasibility solve (no objective): a design meeting every target and condition found there starts one
   refinement of the objective, and otherwise makes the answer 'failed' (the optimum was not reached), never
   'infeasible'; where such designs exist and every refinement fails, descents on the exact objective from one
   differential evolution (``descents.descended``) give the answer, 'feasible' (exact, not certified), where
   they end at a valid design;
4. where the closed forms gave the starts, one space-filling search of ``starts_n`` starts (they may have missed);
   where there are none or only starting points, one multi-start of ``wider`` times the starts (the spread starts may
   have been too few); it runs too where the multi-start's second pass finds fewer than ``thin`` certified designs.
Every other solve here runs the pipeline without diagnosis and with at most ``diagnosis_starts`` space-filling
starts (``Settings``), so a diagnosis costs at most (bounds + 4) solves, ``range_solves`` local solves per target and,
where its descents run, one differential evolution and its descents.
"""

from __future__ import annotations

import dataclasses
import math
import re
import time

from qropt.synthesis import atlas as atlas_
from qropt.synthesis import criteria, descents, evolution
from qropt.synthesis import starts as starts_
from qropt.synthesis.result import Result
from qropt.synthesis.search import results
from qropt.synthesis.search.base import STOP, Stage
from qropt.synthesis.search.descended import descended


class Failed(Stage):
    """Where no diagnosis is asked for: 'failed', with the backend's reasons."""

    name = "failed"
    finishing = True

    def run(self, problem, pool, context):
        late = context.out_of_time()
        if context.diagnose and not late:
            return None
        cands = pool.candidates
        stats = {**results.stats(context.solver, problem, cands, pool.plan), **pool.spent}
        stats["t_total"] = time.perf_counter() - context.t0
        why = reasons(cands, context.solver.tolerances)
        if late:
            msg = f"no certified design within the time limit ({len(cands)} local solves{': ' * bool(why)}{why})"
        else:
            msg = f"no start gave a certified design ({why})"
        pool.result = Result("failed", f"{msg}; not diagnosed", stats=stats, units=problem.units)
        return STOP


class Diagnose(Stage):
    """No certified design: the Result that says why."""

    name = "diagnosis"

    def run(self, problem, pool, context):
        evolved = "t_evolution" in pool.spent  # (set where the ``Evolution`` strategy ran one)
        pool.result = diagnose(context, problem, pool.plan, pool.candidates, pool.claim, pool.retry, evolved)
        return STOP


def _sub(context, problem, **kw):
    """A solve of the diagnosis: the Solver's own rounds, no diagnosis."""
    return context.sub(problem, max_rounds=context.solver.max_rounds, diagnose=False, **kw)


def diagnose(context, problem, plan, cands, claim, retry, evolved: bool = False) -> Result:
    """No certified design among ``cands`` (from ``plan``; ``retry``: the multi-start's second pass, or None;
    evolved: the solve's own evolution ran, so the diagnosis does not descend from one again)."""
    solver, targets, seed, t0 = context.solver, context.targets, context.seed, context.t0
    s = context.settings
    n = min(context.starts_n, s.diagnosis_starts)

    def stats():
        out = results.stats(solver, problem, cands, plan)
        out["t_total"] = time.perf_counter() - t0
        return out

    def done(status, msg, **kw):
        return Result(status, msg, stats=stats(), units=problem.units, **kw)

    beyond, found = bound_out_of_reach(context, problem, n)
    if beyond:
        return done("infeasible", beyond[0], reachable=beyond[1])
    if found:  # a design optimising a bounded criterion meets every bound: refine from it
        r = _sub(context, problem, starts_n=0, given=found, use_analytic=False)
        if r.success:
            return r
    # a complete enumeration that gives no design proves there is none; the ranges are sampled (designs and local
    # solves): a target beyond them proves nothing (a type can reach targets well beyond its sampled range), so the
    # search goes on
    proved = plan.kind == "enumeration" and not plan.analytic  # (every design it gives outside the bounds)
    reach = solver.target_ranges(
        problem, targets, list(targets), starts_n=n, seed=seed, solves=s.range_solves, toward=True
    )
    msgs = [range_message(problem, k, targets[k], lo, hi, proved) for k, (lo, hi) in reach.items()]
    outside = [  # a target beyond the designs found; none found proves nothing
        m
        for (k, (lo, hi)), m in zip(reach.items(), msgs, strict=True)
        if math.isfinite(lo) and not inside(targets[k], lo, hi)
    ]
    if proved:
        where = " inside the bounds" if plan.outside else ""
        why = f"no design: the closed form that gives every design ({plan.how}) gives none{where} for these targets"
        return done("infeasible", "; ".join([why, *msgs]), reachable=reach)
    cands, claim, wide = searched(context, problem, plan, cands, claim, retry)
    if any(c.ok for c in cands):
        return results.best(solver, problem, cands, claim, wide, t0)
    if problem.objective and not found:  # is there any design at all? (then the objective's solves failed)
        r = _sub(context, problem.replace(objective=None), starts_n=n)
        found = [{k: r.params[k] for k in problem.free}] if r.success else []
        if found:
            r = _sub(context, problem, starts_n=0, given=found, use_analytic=False)
            if r.success:
                return r
    if plan.kind in ("family", "enumeration") and plan.analytic:  # the closed forms may have missed
        # space-filling starts, each in its own TR orientation only (a second chance, not a second multi-start)
        none = starts_.plan(problem, use_analytic=False)
        more, how, _ = context.multistart(
            problem, none, context.starts_n, seed, retry=False, max_rounds=solver.max_rounds
        )
        if any(c.ok for c in more):
            return results.best(solver, problem, more, how, none, t0)
    feas = solver.tolerances["feasibility"]
    if all(max(c.residuals.values(), default=0.0) > feas or c.mechanism is None for c in cands):
        ends: dict = {}
        for c in cands:
            k = c.statuses[-1] if c.statuses else "no run"
            ends[k] = ends.get(k, 0) + 1
        how = ", ".join(f"{n} {k}" for k, n in sorted(ends.items(), key=lambda kv: -kv[1]))
        msg = f"none of {len(cands)} starts reaches a design meeting the targets and conditions together "
        alone = "though each target alone can be met" if not outside else "and the designs sampled for the ranges"
        msg += f"({solver.backend.name}: {how}), {alone} (" + "; ".join(msgs) + ")"
        if found:  # a design meeting every target and condition exists: the objective's solves failed
            shown = ", ".join(f"{k}={v:.6g}" for k, v in found[0].items())
            msg += (
                f"; designs meeting every target and condition exist (one: {shown}), so the {problem.objective}"
                f" optimum was not reached (it {_SINGULAR})" + _dead_point_hint(problem)
            )
            why = f"none of {len(cands)} starts reaches a design meeting the targets and conditions together ({how})"
            why += f"; the optimum {_SINGULAR}"
            return _descents(context, problem, found, why, stats, evolved) or done("failed", msg, reachable=reach)
        # local runs prove nothing of the whole problem, wherever they end (a run that converges to a point the
        # exact evaluation refuses, even where designs exist): no design was found, none was proved absent
        return done("failed", msg + "; no design was found, none was proved absent", reachable=reach)
    why = reasons(cands, solver.tolerances)
    msg = f"no start converged to a certified design ({why}); " + "; ".join(msgs)
    if found:
        shown = ", ".join(f"{k}={v:.6g}" for k, v in found[0].items())
        msg += f"; a design meeting every target and condition: {shown}" + _dead_point_hint(problem)
        r = _descents(context, problem, found, f"no start converged to a certified design: {why}", stats, evolved)
        if r is not None:
            return r
    return done("failed", msg, reachable=reach)


def reasons(cands, tolerances: dict, shown: int = 3) -> str:
    """Why the starts ended without a certified design: the ``shown`` commonest reasons, each with how many starts
    ended so (``ended``)."""
    count: dict = {}
    for c in cands:
        why = ended(c, tolerances)
        if why:
            count[why] = count.get(why, 0) + 1
    common = sorted(count.items(), key=lambda kv: (-kv[1], kv[0]))[:shown]
    return "; ".join(f"{n} start{'s' * (n != 1)}: {why}" for why, n in common)


def ended(c, tolerances: dict) -> str:
    """Why a start's candidate is not certified: the certifier's reason (the design it names first as 'its
    design'), the row missed or the exchange left open at a converged end, else the backend's last word."""
    if c.info.get("reason"):
        return _NAMED.sub("its design", c.info["reason"])
    if c.converged and c.info.get("ok"):
        worst = max(c.residuals.items(), key=lambda kv: kv[1], default=("", 0.0))
        if worst[1] > tolerances["feasibility"]:
            return f"converged where {worst[0]} is not met"
        if c.info.get("gap", 0.0) > tolerances["gap"]:
            return "converged where the NLP's value and the exact one still differ (the exchange did not close)"
    return ", ".join(c.statuses[-1:])


_SINGULAR = "may lie at a singular limit: a dead point, a link of zero length or a bound"
_NAMED = re.compile(r"^[A-Za-z_]\w*\([^()]*\)(?=[ :])")  # a design's repr heading a reason


def _descents(context, problem, found: list, why: str, stats, evolved: bool = False) -> Result | None:
    """Where designs meet every target and condition (``found``, free-parameter dicts) but no start certified one:
    the best end of descents on the exact objective from them and from one differential evolution's designs
    (``descents.descents``), as a ``feasible`` Result saying ``why`` no start certified, with ``stats()`` (the
    solve's statistics at its end); None where the evolution does not apply, is switched off, already ran in this
    solve (``evolved``: the same seed gives the same designs) or ends nowhere valid."""
    solver, s = context.solver, context.settings
    if evolved or not (solver.evolution and evolution.applies(problem)) or context.out_of_time():
        return None
    designs = list(found) + (evolution.evolve(problem, s.evolution_generations, context.seed, settings=s) or [])
    ends = descents.descents(problem, designs, sqp=solver.sqp, deadline=context.deadline, settings=s)
    return descended(solver, problem, None, ends, why, stats())


def searched(context, problem, plan, cands, claim, retry):
    """The searches a first pass without a certified design calls for: its second pass (``retry``, every
    space-filling start both ways), and where that certifies fewer than ``thin`` designs and the closed forms give
    starting points or none, one multi-start of ``wider`` times the starts, from seed + 1, without the closed-form
    points and the atlas (the spread starts may have been too few). (candidates, claim, plan) to take the best of:
    the passes' and, where it certifies any, the wider one's, every start counted."""
    s = context.settings
    if retry is not None:
        cands = cands + retry()
        if sum(c.ok for c in cands) >= s.thin:
            return cands, claim, plan
    if plan.kind in ("none", "partial") and context.starts_n > 0:
        wide = dataclasses.replace(plan, atlas=atlas_.Starts()) if plan.kind == "none" else starts_.plan(problem, False)
        more, how, _ = context.multistart(
            problem,
            wide,
            s.wider * context.starts_n,
            context.seed + 1,
            retry=False,
            max_rounds=context.solver.max_rounds,
        )
        if any(c.ok for c in more):
            return cands + more, how, wide
    return cands, claim, plan


def bound_problems(problem) -> list:
    """(condition, criterion, problem) for each bound condition of ``problem``: the problem that optimises the
    bound's criterion under the targets and the other conditions."""
    out = []
    for key, c in criteria.bounds().items():
        if problem.conditions.get(key) is None:
            continue
        others = {k: v for k, v in problem.conditions.items() if k != key}
        out.append((key, c, problem.replace(objective=c.objective, size=c.size or problem.size, conditions=others)))
    return out


def bound_out_of_reach(context, problem, starts_n, atlas_only: bool = False):
    """((message, {quantity: (low, high)}) if a bound condition is beyond what any design meeting the targets and
    the other conditions reaches (its best value, from a solve optimising it), else None; and the designs of those
    solves that meet every bound, as starts). atlas_only: only the bounds whose own problem the atlas holds."""
    found = []
    tol = context.solver.tolerances["feasibility"]
    for key, c, sub in bound_problems(problem):
        if atlas_only and not atlas_.starts(sub).designs:
            continue
        bound = problem.conditions[key]
        r = _sub(context, sub, starts_n=starts_n)
        if r.status not in ("optimal", "acceptable"):
            continue
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
                f"{key} {show(bound)} is beyond reach: the {word} {c.name} of a design meeting the "
                f"targets and the other conditions is {show(best)} ({r.certificate.global_claim})"
            )
            return (msg, {c.name: span}), []
    return None, found


def inside(v, lo, hi) -> bool:
    """v within a found range, to 1e-6 relative: the range's ends are designs found, not proofs of an end."""
    tol = 1e-6 * max(1.0, abs(v))
    return lo - tol <= v <= hi + tol


def range_message(problem, k, v, lo, hi, proved: bool = True):
    """A target against its range: 'the reachable' range where a complete closed form proves it, else the range
    of the designs sampled (which proves nothing beyond them)."""
    bounds = ", ".join(f"{n} in [{a:g}, {b:g}]" for n, (a, b) in problem.free.items())
    if not math.isfinite(lo):
        return f"no sampled design turns fully and meets the conditions for {bounds}"
    where = "inside" if inside(v, lo, hi) else "below" if v < lo else "above"
    reach = "the reachable" if proved else "the sampled range"
    return f"{k} {v:g} is {where} {reach} {lo:.6g}..{hi:.6g} for {bounds}"


def _dead_point_hint(problem) -> str:
    """For a dynamic objective without a transmission bound: why its optimum may sit at a dead point."""
    c = criteria.of_problem(problem)
    if c is None or c.kinematic or criteria.GUARDED in problem.conditions:
        return ""
    return (
        f"; {problem.objective} may drive a design toward a dead point of a joint (a transmission angle of zero, "
        "where the joint forces grow without bound but the torque and shaking stay finite): a gamma_min condition "
        "keeps the designs away from it"
    )


__all__ = [
    "Diagnose",
    "Failed",
    "diagnose",
    "searched",
    "inside",
    "range_message",
    "bound_problems",
    "bound_out_of_reach",
]
