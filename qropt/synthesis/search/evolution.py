"""Where the guard applies (``guard.guard_of``) and the evolution can put designs on the targets
(``evolution.applies``): local solves from the ends of descents on the exact objective from differential
evolutions' designs (``descents.descended``; ``Solver.evolutions_of`` of them, from seeds seed, seed + 1, ...). Run
whether or not the passes certify a design: the descents reach basins the passes miss. Its ends go to the pool
(``Pool.ends``), which the ``Descended`` strategy compares with the certified designs."""

from __future__ import annotations

import time

from qropt.synthesis import descents
from qropt.synthesis import evolution as evolution_
from qropt.synthesis.search.base import Stage
from qropt.synthesis.search.guard import guard_of


class Evolution(Stage):
    name = "differential evolution"

    def accepts(self, problem, plan):
        return guard_of(problem, plan) is not None and evolution_.applies(problem)

    def run(self, problem, pool, context):
        solver = context.solver
        if not solver.evolution:
            return
        t0, seed = time.perf_counter(), context.seed
        count, generations = solver.evolutions_of(problem), context.settings.evolution_generations
        if count == 0:
            return
        each = []
        for i in range(count):
            if context.out_of_time():
                break
            each.append(
                descents.descended(
                    problem, generations, seed + i, sqp=solver.sqp, deadline=context.deadline, settings=context.settings
                )
            )
        runs = [
            ("evolution", e.design) for ends in each for e in ends[: context.settings.evolution_keep]
        ]  # the best distinct ends
        out = solver.multistart.run(
            problem, runs, context.targets, context.max_rounds, pool.designs, False, deadline=context.deadline
        )
        which = (
            "a differential evolution"
            if count == 1
            else f"{count} differential evolutions (seeds {seed}-{seed + count - 1})"
        )
        pool.notes.append(
            f"{len(runs)} starts from descents on the exact objective after {which} of "
            f"{generations} generations, {sum(x.ok for x in out)} certified"
        )
        pool.more += out
        pool.ends = sorted((e for ends in each for e in ends), key=lambda e: e.value)
        pool.spent["t_evolution"] = time.perf_counter() - t0
