"""Where the objective is a peak over the turn (``minimax.applies``: its criterion declares the ``quantity``): the
SQP on the exact peak (``minimax.polish``) from the ``polished`` best certified designs and from each descent's end;
its ends, where it moves them, join the pool's ends (only ends: a design is not moved, so what the solve found
stands; ``Descended`` takes the best). A Nelder-Mead descent stalls where peaks are equal, and a certified design
can be a point the SQP leaves for a lower peak."""

from __future__ import annotations

import time

from qropt.synthesis import evolution, minimax
from qropt.synthesis.search.base import Stage


def polished(problem, r, ends: list, settings, deadline: float | None = None) -> tuple[list, dict]:
    """``ends`` with the SQP's ends from the ``settings.polished`` best certified designs of ``r`` (or None) and from
    each of ``ends``, best first; and {'sqp_ends': how many were added, 't_sqp': the time taken, s}. deadline: no SQP
    starts after it (perf_counter s)."""
    t0 = time.perf_counter()
    if not minimax.applies(problem):
        return ends, {"sqp_ends": 0, "t_sqp": time.perf_counter() - t0}
    certified = [r, *(r.local_optima or ())[1:]][: settings.polished] if r is not None else []
    seeds = [{k: x.params[k] for k in problem.free} for x in certified] + [e.design for e in ends]
    added = []
    for d in seeds:
        if deadline is not None and time.perf_counter() >= deadline:
            break
        p = minimax.polish(problem, d, settings=settings)
        if p is not None and p.steps:
            added.append(evolution.End(p.value, p.design, p.local))
    spent = {"sqp_ends": len(added), "t_sqp": time.perf_counter() - t0}
    return sorted([*ends, *added], key=lambda e: e.value), spent


class PeakSQP(Stage):
    name = "SQP on the exact peak"

    def accepts(self, problem, plan):
        return plan is not None and plan.searching and minimax.applies(problem)

    def run(self, problem, pool, context):
        if pool.result is None and not pool.ends:
            return
        pool.ends, spent = polished(problem, pool.result, pool.ends, context.settings, context.deadline)
        pool.spent.update(spent)
