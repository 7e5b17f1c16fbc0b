"""An evolution's designs descended on the exact objective: each put on the targets and descended by Nelder-Mead
(``evolution.descend``) and, for a peak over the turn, by the SQP on its exact extremes (``minimax.polish``). What
``MultiStart.evolved`` and the independent search (``benchmarks.search``) start from."""

from __future__ import annotations

import time

from qropt.synthesis import evolution, minimax
from qropt.synthesis.settings import DEFAULT, Settings


def descended(
    problem,
    generations: int,
    seed: int,
    keep: int | None = None,
    evals: int | None = None,
    sqp: bool = False,
    deadline: float | None = None,
    settings: Settings = DEFAULT,
) -> list[evolution.End]:
    """The ``descents`` of an evolution's designs (``evolve``: ``generations`` from ``seed``, ``keep`` of them)."""
    designs = evolution.evolve(problem, generations, seed, keep, settings)
    return descents(problem, designs, evals, sqp, deadline, settings)


def descents(
    problem,
    designs: list[dict],
    evals: int | None = None,
    sqp: bool = False,
    deadline: float | None = None,
    settings: Settings = DEFAULT,
) -> list[evolution.End]:
    """The designs, each put on the targets and descended by Nelder-Mead (``descend``, ``evals`` evaluations); with
    ``sqp``, where the objective is a peak over the turn, the SQP on its exact extremes (``minimax.polish``) runs
    from the design and from Nelder-Mead's end too (the two often reach different minima; the ends then kept where
    they differ, ``apart``). The ends, best first; deadline: no descent starts after it (perf_counter s)."""
    ends: list[evolution.End] = []
    sqp = sqp and minimax.applies(problem)
    for d in designs:
        if deadline is not None and time.perf_counter() >= deadline:
            break
        on = evolution.on_targets(problem, d, settings=settings)
        if on is None:
            continue
        got = evolution.descend(problem, on, evals, settings)
        for x in ([on] + ([got[1]] if got is not None else [])) if sqp else []:
            if (p := minimax.polish(problem, x, settings=settings)) is not None:
                ends.append(evolution.End(p.value, p.design, p.local))  # first: at a tie its end says what holds
        if got is not None:
            ends.append(evolution.End(got[0], got[1], evolution.DESCENT_LOCAL))
    distinct: list[evolution.End] = []
    for e in sorted(ends, key=lambda e: e.value):
        if not sqp or all(evolution.apart(problem, e.design, x.design, settings) for x in distinct):
            distinct.append(e)
    return distinct


__all__ = ["descended", "descents"]
