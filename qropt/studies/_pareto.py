"""Trade-off fronts between two objectives by the epsilon-constraint method.

The front's ends are the two single-objective solves; between them objective ``a`` is optimised with the
criterion of ``b`` bounded at values swept evenly between its values at the two ends. Each point is a certified
solve warm-started from its neighbour (the full solve where the warm start fails); points another point
dominates are removed, with the reason kept. Units as in ``qropt.criteria``.
"""

from __future__ import annotations

import csv
import inspect
import json
from dataclasses import dataclass, field

import numpy as np

from qropt import schema
from qropt.errors import ProblemError
from qropt.synthesis import criteria
from qropt.synthesis.problem import Problem
from qropt.synthesis.result import SOLUTION_PRESENT, Result, json_safe
from qropt.units import named

MAX_POINTS = 1000


@dataclass(frozen=True)
class Front:
    """points: the non-dominated Results in order along the front (from a's optimum to b's); values: their
    (a criterion, b criterion) pairs; removed: (bound value, reason) of every sweep point left out."""

    problem: Problem
    objectives: tuple
    criteria: tuple
    points: tuple
    values: tuple
    removed: tuple = field(default_factory=tuple)

    def __repr__(self):
        a, b = self.criteria
        ua, ub = (named(criteria.CRITERIA[q].unit, self.problem.units) for q in (a, b))
        lines = [
            f"Front({self.objectives[0]} vs {self.objectives[1]}: {len(self.points)} points, "
            f"{len(self.removed)} removed)"
        ]
        for va, vb in self.values[:6]:
            lines.append(f"  {a} {va:.6g} {ua}  {b} {vb:.6g} {ub}")
        if len(self.values) > 6:
            lines.append("  ...")
        return "\n".join(lines)

    def table(self) -> list[dict]:
        a, b = self.criteria
        return [
            {a: va, b: vb, "status": r.status, **r.params} for r, (va, vb) in zip(self.points, self.values, strict=True)
        ]

    def to_json(self) -> str:
        """The front as strict JSON, led by the schema version and qropt's (``qropt.schema.stamp``): its points
        (``table``) in order along it, the sweep points removed and why; "units" names each criterion's unit,
        "length" the length unit."""
        d = {
            **schema.stamp(),
            "objectives": list(self.objectives),
            "criteria": list(self.criteria),
            "units": {"length": self.problem.units, **criteria.units(self.problem.units)},
            "points": self.table(),
            "removed": [{"bound": eps, "reason": why} for eps, why in self.removed],
        }
        return json.dumps(json_safe(d), indent=2, allow_nan=False)

    def to_csv(self, path) -> None:
        rows = self.table()
        names = list(rows[0]) if rows else []
        with open(path, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(names)
            for r in rows:
                w.writerow([f"{r[k]:.12g}" if isinstance(r[k], float) else r[k] for k in names])


def pareto(
    problem: Problem, objectives=("max_gamma_min", "min_peak_accel"), n: int = 20, *, solver=None, progress=None
) -> Front:
    """The trade-off front between two objectives of ``problem`` (its own objective is replaced); see the
    module docstring. n: sweep points including the two ends (>= 2)."""
    from qropt.synthesis.solver import DEFAULT

    solver = solver or DEFAULT
    a, b = _check(problem, objectives, n)
    ca, cb = criteria.of(a, problem.size), criteria.of(b, problem.size)
    qa, qb = ca.name, cb.name
    bound_b = cb.bound
    base = problem.replace(conditions={k: v for k, v in problem.conditions.items() if k != bound_b})
    end_a = solver.solve(base.replace(objective=a))
    end_b = solver.solve(base.replace(objective=b))
    for end, name in ((end_a, a), (end_b, b)):
        if end.status not in SOLUTION_PRESENT:
            raise ProblemError(f"no front: the problem has no design for {name} ({end.status}: {end.message})")
    # each end the best in the other criterion among its own optima (several designs can share an optimum)
    end_a = _lexicographic(solver, base, end_a, a, b, problem.size)
    end_b = _lexicographic(solver, base, end_b, b, a, problem.size)
    lo, hi = _value(problem, qb, end_a), _value(problem, qb, end_b)
    continues = "continue_from" in inspect.signature(solver.solve).parameters

    def after(r):  # each point continued from the last one's optimum where the solver can (``newton``)
        return {"continue_from": r} if continues else {}

    runs = [(None, end_a)]
    prev = end_a
    for eps in np.linspace(lo, hi, n)[1:-1]:
        p = base.replace(objective=a, conditions={**base.conditions, bound_b: float(eps)})
        r = solver.solve(
            p, extra_starts=[_free(p, prev)], starts_n=0, use_analytic=False, diagnose=False, **after(prev)
        )
        if r.status not in SOLUTION_PRESENT:  # the neighbour's basin ended here: the full solve
            r = solver.solve(p)
        runs.append((float(eps), r))
        if r.status in SOLUTION_PRESENT:
            prev = r
        if progress:
            progress(1)
    runs.append((None, end_b))
    return _front(problem, (a, b), (qa, qb), runs)


LEXICOGRAPHIC = 1e-7  # relative give on an end's own optimum while the other criterion is optimised


def _lexicographic(solver, base, end, first, second, size):
    """The design optimising ``second`` among those within LEXICOGRAPHIC of ``end``'s optimum of ``first`` (the
    end itself if that solve does not improve on it)."""
    c1, c2 = criteria.of(first, size), criteria.of(second, size)
    v1 = c1.value(base.settled(end), end.mechanism)
    give = LEXICOGRAPHIC * max(1.0, abs(v1))
    bound = v1 - give if c1.maximise else v1 + give
    p = base.replace(objective=second, conditions={**base.conditions, c1.bound: bound})
    r = solver.solve(p, extra_starts=[_free(p, end)], starts_n=0, use_analytic=False, diagnose=False)
    if r.status not in SOLUTION_PRESENT:
        return end
    better = c2.better(c2.value(base.settled(r), r.mechanism), c2.value(base.settled(end), end.mechanism))
    return r if better else end


def _front(problem, objectives, names, runs) -> Front:
    sa, sb = (1.0 if criteria.CRITERIA[q].maximise else -1.0 for q in names)  # both maximised after the sign
    pts, removed = [], []
    for eps, r in runs:
        if r.status not in SOLUTION_PRESENT:
            removed.append((eps, f"no certified design ({r.status}: {r.message})"))
            continue
        pts.append((eps, r, (_value(problem, names[0], r), _value(problem, names[1], r))))
    keep = []
    for i, (eps, r, (va, vb)) in enumerate(pts):
        by = next(
            (j for j, (_, _, (wa, wb)) in enumerate(pts) if j != i and _dominates(sa * wa, sb * wb, sa * va, sb * vb)),
            None,
        )
        if by is not None:
            removed.append(
                (eps, f"dominated by the point with {names[0]} {pts[by][2][0]:.6g}, {names[1]} {pts[by][2][1]:.6g}")
            )
        elif (
            keep
            and abs(keep[-1][2][0] - va) <= 1e-9 * max(1, abs(va))
            and abs(keep[-1][2][1] - vb) <= 1e-9 * max(1, abs(vb))
        ):
            removed.append((eps, "the same design as its neighbour"))
        else:
            keep.append((eps, r, (va, vb)))
    return Front(
        problem,
        tuple(objectives),
        tuple(names),
        tuple(r for _, r, _ in keep),
        tuple(v for _, _, v in keep),
        tuple(removed),
    )


def _dominates(a1, b1, a2, b2, tol=1e-9) -> bool:
    """(a1, b1) dominates (a2, b2), both to be maximised: no worse in both, better in one beyond tol."""
    ta, tb = tol * max(1.0, abs(a2)), tol * max(1.0, abs(b2))
    return a1 >= a2 - ta and b1 >= b2 - tb and (a1 > a2 + ta or b1 > b2 + tb)


def _value(problem, quantity, r: Result) -> float:
    return criteria.CRITERIA[quantity].value(problem.settled(r), r.mechanism)


def _free(problem, r: Result) -> dict:
    return {k: r.params[k] for k in problem.free}


def _check(problem, objectives, n):
    if not isinstance(problem, Problem):
        raise ProblemError(f"pareto takes a qropt.Problem, got {type(problem).__name__}")
    names = objective_names()
    if not isinstance(objectives, (tuple, list)) or len(objectives) != 2:
        raise ProblemError(
            f"objectives is a pair (a tuple or list) of objective names from {names}, got {objectives!r}"
        )
    a, b = objectives
    for o in (a, b):
        if not isinstance(o, str) or o not in names:
            raise ProblemError(f"unknown objective {o!r}; objectives are {names}")
    if criteria.of(a, problem.size) is criteria.of(b, problem.size):
        raise ProblemError(f"the two objectives must differ, got {a!r} twice")
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or not 2 <= n <= MAX_POINTS:
        raise ProblemError(f"n is the number of front points, an integer in [2, {MAX_POINTS}]; got {n!r}")
    problem.replace(objective=a)  # the type supports both (a slider for the acceleration and velocity)
    problem.replace(objective=b)
    return a, b


def objective_names() -> tuple:
    """The objectives a front can trade (every registered criterion's)."""
    return tuple(o for o in criteria.objectives() if o)


__all__ = ["Front", "pareto", "objective_names"]
