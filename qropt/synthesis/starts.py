"""Where local solves begin: the closed forms first, then a scrambled Sobol design over the free bounds.

A closed form that enumerates every solution of a problem's structure replaces the multi-start; one
that walks a family holding every solution is scanned and only its best points are refined.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field

import numpy as np

from qropt.errors import QroptError
from qropt.kinematics.ops import NUMPY
from qropt.synthesis import analytic
from qropt.synthesis.formulation import slow_interval


@dataclass(frozen=True)
class Plan:
    """The starts of one solve. kind: 'enumeration', 'family', 'partial' or 'none' (see analytic.WarmStarts)."""

    analytic: tuple
    kind: str
    how: str
    outside: int = 0  # closed-form points of an enumeration left out as outside the bounds
    ranges: dict = field(default_factory=dict)  # target -> (low, high) over the bounds, by the closed form


def _build(problem, values, branch):
    return problem.build(values, branch)


def branches(problem) -> list[dict]:
    """Every combination of the problem's allowed assembly-branch signs."""
    names = list(problem.branches)
    return [dict(zip(names, combo, strict=True)) for combo in itertools.product(*problem.branches.values())]


def plan(problem, use_analytic: bool = True) -> Plan:
    """The closed-form starts (clipped to the bounds) and what they cover."""
    if not use_analytic:
        return Plan((), "none", "closed forms not used")
    w = analytic.warm_starts(problem)

    def clip(v):
        return {k: min(max(x, problem.free[k][0]), problem.free[k][1]) for k, x in v.items()}

    if w.kind == "enumeration":  # every design: one outside the bounds is no start, it is not a design here
        inside = [v for v in w.points if all(lo <= v[k] <= hi for k, (lo, hi) in problem.free.items())]
        return Plan(tuple(inside), w.kind, w.how, len(w.points) - len(inside), dict(w.ranges))
    return Plan(tuple(clip(v) for v in w.points), w.kind, w.how)


POOL = 64  # Sobol points drawn per start wanted: the type's rules (one vectorised check) thin them first


def rule_points(problem, n: int, seed: int) -> list[dict]:
    """Scrambled-Sobol points over the free bounds (log-spaced for lengths), a power of two of them at least n,
    with the points that break the type's rules (Grashof class, crank shorter than the centres and the like)
    dropped in one vectorised check; none is built."""
    from scipy.stats import qmc  # imported here: scipy.stats takes a second to import

    names = list(problem.free)
    u = qmc.Sobol(len(names), scramble=True, seed=seed).random_base2(max(0, n - 1).bit_length())
    cols = {}
    for j, k in enumerate(names):
        lo, hi = problem.free[k]
        cols[k] = lo * (hi / lo) ** u[:, j] if k in problem.mechanism.LENGTHS and lo > 0 else lo + (hi - lo) * u[:, j]
    p = {**problem.fixed, **cols, **branches(problem)[0]}
    ok = np.ones(u.shape[0], bool)
    for rule in problem.mechanism.rules(NUMPY, p, problem.conditions.get("grashof")):
        ok &= np.broadcast_to(np.asarray(rule.value) >= 0, ok.shape)
    return [{k: float(cols[k][i]) for k in names} for i in np.flatnonzero(ok).tolist()] or [
        {k: float(cols[k][i]) for k in names} for i in range(min(n, u.shape[0]))
    ]


MAX_CORNERS = 64  # the corners of the free bounds tried as designs (every one up to six free parameters)


def corners(problem) -> list[dict]:
    """The corners of the free bounds (where extremes of a target often lie), at most MAX_CORNERS of them."""
    names = list(problem.free)
    if 2 ** len(names) > MAX_CORNERS:
        return []
    return [
        {k: problem.free[k][bit] for k, bit in zip(names, bits, strict=True)}
        for bits in itertools.product((0, 1), repeat=len(names))
    ]


def sobol(problem, n: int, seed: int, build=None) -> list[dict]:
    """Up to n of the ``rule_points`` (POOL * n drawn) whose mechanism turns fully on the first branch; if none
    does, the first n points as they are. Where every length and offset is free, each point is scaled to meet
    the stroke target (TR and angles do not change with scale) when the scaled point stays inside the bounds."""
    if n <= 0:
        return []
    branch = branches(problem)[0]
    build = build or _build
    pts = rule_points(problem, POOL * n, seed)
    kept = []
    for v in pts:
        if orientation(problem, v, branch, build) is not None:
            kept.append(_to_stroke(problem, v, branch, build))
            if len(kept) == n:
                break
    return kept or pts[:n]


def _to_stroke(problem, values, branch, build) -> dict:
    """The design scaled so that its stroke meets the target, if scaling is free and stays in bounds."""
    stroke = problem.targets.get("stroke")
    scalable = [k for k, kind in problem.mechanism.kinds().items() if kind in ("length", "offset")]
    if stroke is None or any(k in problem.fixed and problem.fixed[k] != 0.0 for k in scalable):
        return values
    try:
        k = stroke / build(problem, values, branch).stroke()
    except QroptError:
        return values
    scaled = {name: x * k if name in scalable else x for name, x in values.items()}
    inside = all(lo <= scaled[name] <= hi for name, (lo, hi) in problem.free.items())
    return scaled if inside else values


def orientation(problem, values, branch, build=None) -> int | None:
    """+1 if the design's slow interval runs from theta_max to theta_min (counter-clockwise), -1 if not,
    None if it does not build or turn fully."""
    try:
        a, b = (build or _build)(problem, values, branch).stroke_angles()
    except QroptError:
        return None
    return 1 if a >= b else -1


def dead_centre_start(problem, values, branch, targets, orientation, range_target, build=None):
    """Dead-centre angles of the start design (moved to meet the TR target) and the TR orientation."""
    try:
        m0 = (build or _build)(problem, values, branch)
        d = m0.dead_centres()
        a, b = m0.stroke_angles()
        orientation = orientation or (1 if a >= b else -1)
        th0 = (d.theta_max, d.theta_max + a)
    except QroptError:
        orientation, tr = orientation or 1, targets.get("time_ratio", 1.5)
        th0 = (0.5, 0.5 + slow_interval(tr, orientation))
    if "time_ratio" in targets and range_target != "time_ratio":
        th0 = (th0[0], th0[0] + slow_interval(targets["time_ratio"], orientation))
    return th0, orientation


def local_best(scores: list, maximise: bool, keep: int = 3) -> list[int]:
    """Indices of the best local optima of a sequence of scores (None where a point is invalid), best first."""
    s = np.array([np.nan if v is None else (v if maximise else -v) for v in scores], float)
    ok = np.isfinite(s)
    idx = []
    for i in np.flatnonzero(ok):
        left = s[i - 1] if i > 0 and ok[i - 1] else -np.inf
        right = s[i + 1] if i + 1 < s.size and ok[i + 1] else -np.inf
        if s[i] >= left and s[i] >= right:
            idx.append(int(i))
    return sorted(idx, key=lambda i: -s[i])[:keep]


__all__ = ["Plan", "branches", "plan", "sobol", "orientation", "dead_centre_start", "local_best"]
