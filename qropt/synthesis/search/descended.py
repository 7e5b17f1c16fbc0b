"""The best descent's end (the pool's ends: the evolution's and the SQP's) that meets every target, condition,
rule and bound exactly, its output turning back nowhere inside a stroke (``Mechanism.dwells``), as a ``feasible``
Result where it beats the best certified design by more than ``stands`` (relative): the design is exact, not
certified by the NLP (its certificate's ``local`` says what holds at the end); the certified designs stay as its
local optima. Not for a free counterweight (the descents keep it at its start). Ends the pipeline where a Result
stands."""

from __future__ import annotations

import dataclasses
import math
import time

import numpy as np

from qropt.errors import QroptError
from qropt.synthesis import criteria, evolution
from qropt.synthesis import starts as starts_
from qropt.synthesis.certificate import Certificate, quantities, residuals
from qropt.synthesis.certificate import objective_value as value_of
from qropt.synthesis.result import Result
from qropt.synthesis.search import results
from qropt.synthesis.search.base import STOP, Stage


def relabelled(r: Result) -> Result:
    """A certified design as another local optimum (a better design stands before it)."""
    claim = r.message.split("; global: ", 1)[-1]
    return dataclasses.replace(r, status="local_optimum", message=f"another certified local optimum; global: {claim}")


def descended(solver, problem, r, ends: list, how: str, stats: dict | None = None, polished: int = 0):
    """The Result of the best of ``ends`` (``evolution.End``s, best first; of them ``polished`` the SQP's) where it
    stands against ``r`` (the best certified design, or None); ``r`` otherwise."""
    if not ends or (problem.masses is not None and problem.masses.balancing):
        return r
    n = len(ends) - polished
    best_of = f"the best of {n} descents' ends" if n else "the best of "
    if polished:
        best_of += f"{' and ' if n else ''}{polished} ends of the SQP on the exact peak from the best designs"
    branch, feasible = starts_.branches(problem)[0], solver.tolerances["feasibility"]
    for end in ends:
        d = end.design
        try:
            m = problem.build(d, branch)
            if m.dwells():  # a descent on exact values walks into the dwell tolerance: its output turns back there
                continue
            q = quantities(problem, m)
            res = residuals(problem, {}, m, problem.targets)
        except QroptError:
            continue
        kept = starts_.rules_kept(problem, {k: np.array([v]) for k, v in d.items()})[0]
        if not kept or evolution.outside(problem, d) > 0 or max(res.values(), default=0.0) > feasible:
            continue
        value = value_of(problem, q)
        if value is None or not math.isfinite(value):
            continue
        if r is not None:
            margin = solver.settings.stands * max(1.0, abs(r.objective))
            if not (criteria.better(problem, value, r.objective) and abs(value - r.objective) > margin):
                return r
            claim = f"{best_of}; certified: {r.certificate.global_claim}"
            head = f"better than the best certified design, {r.objective:.6g}, by exact evaluation"
            local = tuple(relabelled(x) for x in r.local_optima or (r,))
            stats = r.stats
        else:
            claim = f"{best_of} ({how})"
            head, local = "no start gave a certified design", ()
        cert = Certificate(True, None, value, 0.0, 0, end.local, claim)
        return Result(
            status="feasible",
            message=f"a design meeting every target and condition exactly, not certified ({head}); global: {claim}",
            params=dict(m.params),
            mechanism=m,
            objective=value,
            quantities=q,
            residuals=res,
            certificate=cert,
            stats={**(stats or {}), "branch": dict(branch), "origin": "descent"},
            local_optima=local,
        )
    return r


class Descended(Stage):
    name = "descents' ends"
    finishing = True

    def run(self, problem, pool, context):
        solver, polished = context.solver, pool.spent.get("sqp_ends", 0)
        if pool.result is not None:
            r = descended(solver, problem, pool.result, pool.ends, pool.guard, polished=polished)
            stats = {**r.stats, **pool.spent, "t_total": time.perf_counter() - context.t0}
            pool.result = dataclasses.replace(r, stats=stats)
            return STOP
        if not pool.ends:
            return None
        stats = {**results.stats(solver, problem, pool.candidates, pool.plan), **pool.spent}
        r = descended(solver, problem, None, pool.ends, pool.guard, stats, polished=polished)
        if r is None:
            return None
        pool.result = dataclasses.replace(r, stats={**r.stats, "t_total": time.perf_counter() - context.t0})
        return STOP
