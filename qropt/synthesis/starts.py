"""Where local solves begin: the closed forms first, then a scrambled Sobol design over the free bounds.

A closed form that enumerates every solution of a problem's structure replaces the multi-start; one
that walks a family holding every solution is scanned and only its best points are refined.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field

import numpy as np

from qropt.errors import QroptError
from qropt.kinematics.ops import NUMPY
from qropt.synthesis import analytic, criteria
from qropt.synthesis import atlas as atlas_
from qropt.synthesis.formulation import slow_interval
from qropt.synthesis.settings import DEFAULT, Settings


@dataclass(frozen=True)
class Plan:
    """The starts of one solve. kind: 'enumeration', 'family', 'partial' or 'none' (see analytic.WarmStarts)."""

    analytic: tuple
    kind: str
    how: str
    outside: int = 0  # closed-form points of an enumeration left out as outside the bounds
    ranges: dict = field(default_factory=dict)  # target -> (low, high) over the bounds, by the closed form
    atlas: atlas_.Starts = atlas_.Starts()  # where no closed form enumerates or walks every solution
    related: atlas_.Starts = atlas_.Starts()  # the same, where the objective is dynamic: the atlas's kinematic optima
    walk: analytic.Walk | None = None  # a family's designs as a function of its parameter (``analytic.Walk``)
    given: int = 0  # starts the solve was given (``extra_starts``): they replace the closed forms' own searches

    @property
    def spread(self) -> bool:
        """Whether the space-filling starts run: no closed form enumerates or walks every design, or starts are
        given."""
        return bool(self.given) or self.kind not in ("enumeration", "family")

    @property
    def searching(self) -> bool:
        """Whether the solve searches on its own (no starts given): the global strategies run only then."""
        return not self.given


def _build(problem, values, branch):
    return problem.build(values, branch)


def branches(problem) -> list[dict]:
    """Every combination of the problem's allowed assembly-branch signs."""
    names = list(problem.branches)
    return [dict(zip(names, combo, strict=True)) for combo in itertools.product(*problem.branches.values())]


def plan(problem, use_analytic: bool = True, use_atlas: bool = False) -> Plan:
    """The closed-form starts (clipped to the bounds) and what they cover; with ``use_atlas``, the atlas's designs
    where the closed forms neither enumerate nor walk every solution."""
    if not use_analytic:
        return Plan((), "none", "closed forms not used", **_from_atlas(problem, use_atlas))
    w = analytic.warm_starts(problem)

    def clip(v):
        return {k: min(max(x, problem.free[k][0]), problem.free[k][1]) for k, x in v.items()}

    if w.kind == "enumeration":  # every design: one outside the bounds is no start, it is not a design here
        inside = [v for v in w.points if all(lo <= v[k] <= hi for k, (lo, hi) in problem.free.items())]
        return Plan(tuple(inside), w.kind, w.how, len(w.points) - len(inside), dict(w.ranges))
    found = _from_atlas(problem, use_atlas and w.kind != "family")
    return Plan(tuple(clip(v) for v in w.points), w.kind, w.how, walk=w.walk, **found)


def _from_atlas(problem, use: bool) -> dict:
    """A plan's ``atlas`` and ``related`` starts (none unless ``use``)."""
    if not use:
        return {"atlas": atlas_.Starts(), "related": atlas_.Starts()}
    return {"atlas": atlas_.starts(problem), "related": atlas_.related(problem)}


def rule_points(problem, n: int, seed: int, least: int = 1, settings: Settings = DEFAULT) -> list[dict]:
    """Scrambled-Sobol points over the free bounds (log-spaced for lengths), a power of two of them at least n,
    with the points that break the type's rules (Grashof class, crank shorter than the centres and the like)
    dropped in one vectorised check; none is built. While fewer than ``least`` pass, four times as many more are
    drawn (``settings.rule_draws`` in all at most). If none passes, the first n points as they are."""
    from scipy.stats import qmc  # imported here: scipy.stats is slow to import

    names = list(problem.free)
    sampler = qmc.Sobol(len(names), scramble=True, seed=seed)
    kept: list[dict] = []
    first: list[dict] = []
    draw, drawn = 1 << max(0, n - 1).bit_length(), 0
    while drawn < settings.rule_draws and (not drawn or len(kept) < least):
        u = sampler.random(draw)
        drawn += draw
        cols = {k: from_unit(problem, k, u[:, j]) for j, k in enumerate(names)}
        ok = rules_kept(problem, cols)
        kept += [{k: float(cols[k][i]) for k in names} for i in np.flatnonzero(ok).tolist()]
        first = first or [{k: float(cols[k][i]) for k in names} for i in range(min(n, u.shape[0]))]
        draw = min(4 * draw, settings.rule_draws - drawn)
    return kept or first


def from_unit(problem, k: str, u):
    """Free parameter k at unit coordinates u (0..1): log-uniform over its bounds for a length, uniform else."""
    lo, hi = problem.free[k]
    return lo * (hi / lo) ** u if k in problem.mechanism.LENGTHS and lo > 0 else lo + (hi - lo) * u


def rules_kept(problem, cols: dict) -> np.ndarray:
    """Which designs, given as columns (free parameter -> 1-D array, first branch), keep the type's rules
    (Grashof class and the like), in one vectorised check."""
    p = {**problem.fixed, **cols, **branches(problem)[0]}
    ok = np.ones(next(iter(cols.values())).shape[0], bool)
    for rule in problem.mechanism.rules(NUMPY, p, problem.conditions.get("grashof")):
        ok &= np.broadcast_to(np.asarray(rule.value) >= 0, ok.shape)
    return ok


def corners(problem, settings: Settings = DEFAULT) -> list[dict]:
    """The corners of the free bounds (where extremes of a target often lie), at most ``settings.max_corners``."""
    names = list(problem.free)
    if 2 ** len(names) > settings.max_corners:
        return []
    return [
        {k: problem.free[k][bit] for k, bit in zip(names, bits, strict=True)}
        for bits in itertools.product((0, 1), repeat=len(names))
    ]


def sobol(problem, n: int, seed: int, build=None, settings: Settings = DEFAULT) -> list[dict]:
    """Up to n of the ``rule_points`` whose mechanism turns fully on the first branch; if none does, the first n points
    as they are. With a time-ratio target and no closed form that enumerates or walks every design (only starting
    points, or none), ``screen`` chooses them (``start_pool`` * n points and at least ``screen_points``, evaluated at
    once). Where every length and offset is free, each point is scaled to meet the stroke target (TR and angles do not
    change with scale) when the scaled point stays inside the bounds."""
    if n <= 0:
        return []
    branch = branches(problem)[0]
    build = build or _build
    if "time_ratio" in problem.targets and plan(problem).kind in ("none", "partial"):  # screen
        chosen = screen(problem, n, seed, build, settings)
        if chosen:
            return chosen
    pts = rule_points(problem, settings.start_pool * n, seed, settings=settings)
    kept = []
    for v in pts:
        if orientation(problem, v, branch, build) is not None:
            kept.append(_to_stroke(problem, v, branch, build))
            if len(kept) == n:
                break
    return kept or pts[:n]


def grown(n: int, problem, plan: Plan) -> int:
    """The default number of space-filling starts: n, and where no closed form enumerates or walks every design
    (only starting points, or none) n per two free parameters."""
    return n * max(1, len(problem.free) // 2) if plan.kind in ("none", "partial") else n


SCREEN_CHUNK = 512  # designs per vectorised pass (memory: chunk * grid numbers per intermediate)


def screen(problem, n: int, seed: int, build, settings: Settings = DEFAULT) -> list[dict]:
    """n starts near the targets: rule points evaluated on a crank-angle grid in vectorised passes (no
    mechanism built), those that close everywhere with one output reversal a turn scaled to the stroke target
    where scaling is free, the ``screen_keep`` * n nearest the TR target built and evaluated exactly, and of those
    in turn the nearest and the best by the objective among the ones within ``screen_tr_near`` of the target. [] if none
    turns fully."""
    branch = branches(problem)[0]
    many = max(settings.screen_points, settings.start_pool * n)
    pts = rule_points(problem, many, seed, least=settings.screen_points // 8, settings=settings)
    try:
        tr, stroke = grid_cycle(problem, pts, settings.screen_grid)
    except (TypeError, ValueError, IndexError):  # a user type's loop that takes one design at a time
        return []
    good = np.flatnonzero(np.isfinite(tr))
    if good.size == 0:
        return []
    target = problem.targets.get("stroke")
    scalable = list(problem.mechanism.scalable())
    if target is not None and not any(k in problem.fixed and problem.fixed[k] != 0.0 for k in scalable):
        k = target / stroke[good]  # designs that fit the bounds once scaled to the stroke go first
        fits = np.ones(good.size, bool)
        for name, (lo, hi) in problem.free.items():
            x = np.array([pts[i][name] for i in good.tolist()]) * (k if name in scalable else 1.0)
            fits &= (x >= lo) & (x <= hi)
        good = good[fits] if fits.any() else good
    near = good[np.argsort(np.abs(np.log(tr[good] / problem.targets["time_ratio"])))][: settings.screen_keep * n]
    from qropt.synthesis import criteria  # here: criteria imports the formulation this module imports

    scored = []
    for i in near.tolist():
        v = _to_stroke(problem, pts[i], branch, build, stroke=float(stroke[i]))
        try:
            m = build(problem, v, branch)
            miss = abs(math.log(m.time_ratio() / problem.targets["time_ratio"]))
            f = criteria.objective_of(problem, m) if problem.objective else 0.0
        except QroptError:
            continue
        scored.append((miss, f, v))
    maximise = bool(problem.objective) and criteria.maximises(problem.objective)
    best = sorted((s for s in scored if s[0] <= settings.screen_tr_near), key=lambda s: -s[1] if maximise else s[1])
    nearest = sorted(scored, key=lambda s: s[0])
    chosen: list[dict] = []
    for pair in itertools.zip_longest(nearest, best):  # the nearest and the best in turn
        for s in pair:
            if s is not None and len(chosen) < n and not any(s[2] is c for c in chosen):
                chosen.append(s[2])
    return chosen


def grid_cycle(problem, pts: list[dict], grid: int) -> tuple[np.ndarray, np.ndarray]:
    """(TR, stroke) of designs (free-parameter dicts, first branch) on a crank-angle grid of ``grid`` points, in
    vectorised passes with no mechanism built; nan where a design does not close everywhere or its output does
    not reverse exactly once a turn. Grid values: starts and samples, not results."""
    tr, stroke = np.full(len(pts), np.nan), np.full(len(pts), np.nan)
    if not pts:
        return tr, stroke
    theta = np.linspace(0.0, 2 * np.pi, grid, endpoint=False)
    with np.errstate(all="ignore"):
        for i, _, loop, x in grid_loops(problem, _columns(problem, pts), theta):
            rows = x.shape[0]
            ok = turns(loop, x)
            a = (theta[np.argmin(x, axis=1)] - theta[np.argmax(x, axis=1)]) % (2 * np.pi)
            a = np.minimum(a, 2 * np.pi - a)
            ok &= a > 0
            tr[i : i + rows] = np.where(ok, (2 * np.pi - a) / np.where(ok, a, 1.0), np.nan)
            stroke[i : i + rows] = np.where(ok, np.ptp(x, axis=1), np.nan)
    return tr, stroke


def turning_points(problem, n: int, seed: int, settings: Settings = DEFAULT) -> list[dict]:
    """Up to n rule points (``screen_points`` drawn at least) that turn fully with one output reversal on the grid."""
    pts = rule_points(problem, max(settings.screen_points, n), seed, least=n, settings=settings)
    try:
        tr, _ = grid_cycle(problem, pts, settings.screen_grid)
    except (TypeError, ValueError, IndexError):  # a user type's loop that takes one design at a time
        return pts[:n]
    return [pts[i] for i in np.flatnonzero(np.isfinite(tr))[:n].tolist()]


def shapes(problem, n: int, seed: int, settings: Settings = DEFAULT) -> list[dict]:
    """Up to n starts chosen by the objective: ``shape_points`` rule points on a ``shape_grid`` grid in vectorised
    passes (no mechanism built), those that close everywhere with one output reversal, scaled to the stroke target (TR,
    gamma_min and the shape do not change with scale) and inside the bounds, within ``shape_window`` of the TR target,
    best first by the objective's grid value (gamma_min, the peak acceleration at omega2 or the footprint). [] where
    scaling is not free or the objective has no grid value here. Grid values choose starts; results come from the local
    solves."""
    scalable = list(problem.mechanism.scalable())
    c = criteria.grid_criterion(problem)
    target = problem.targets.get("stroke")
    if c is None or target is None or "time_ratio" not in problem.targets or n <= 0:
        return []
    if any(k in problem.fixed and problem.fixed[k] != 0.0 for k in scalable):
        return []
    names = list(problem.free)
    pts = rule_points(problem, settings.shape_points, seed, least=settings.shape_points // 8, settings=settings)
    theta = np.linspace(0.0, 2 * np.pi, settings.shape_grid, endpoint=False)
    tr_target, found = problem.targets["time_ratio"], []
    chunks = grid_loops(problem, _columns(problem, pts), theta)
    with np.errstate(all="ignore"):
        while True:
            try:
                chunk = next(chunks, None)
            except (TypeError, ValueError, IndexError):  # a user type's loop that takes one design at a time
                return []
            if chunk is None:
                break
            _, cols, loop, x = chunk
            ok = turns(loop, x)
            tr, stroke = refined_cycle(x)
            scale = target / stroke
            ok &= np.abs(tr / tr_target - 1.0) <= settings.shape_window
            for k in names:
                lo, hi = problem.free[k]
                v = cols[k] * (scale if k in scalable else 1.0)
                ok &= (v >= lo) & (v <= hi)
            if not ok.any():
                continue
            value = c.grid_value(problem, loop, x, scale)
            ok &= np.isfinite(value)
            for j in np.flatnonzero(ok).tolist():
                v = {k: float(cols[k][j] * (scale[j] if k in scalable else 1.0)) for k in names}
                found.append((float(value[j]), v))
    found.sort(key=lambda f: f[0])
    return [v for _, v in found[:n]]


def refined_cycle(x) -> tuple[np.ndarray, np.ndarray]:
    """(TR, stroke) of each row of x (designs, uniform angles over a turn) from its grid extremes refined by the
    grid parabola (``vertex``): the longer interval between them over the shorter."""
    (t_hi, x_hi), (t_lo, x_lo) = vertex(x, np.argmax(x, axis=1)), vertex(x, np.argmin(x, axis=1))
    a = (t_lo - t_hi) % (2 * np.pi)
    return np.maximum(a, 2 * np.pi - a) / np.minimum(a, 2 * np.pi - a), x_hi - x_lo


def vertex(x, j):
    """The vertex of the parabola through each row's grid point j of x (n, m) and its neighbours on a uniform
    grid over a turn: (angle, value)."""
    r, m = np.arange(x.shape[0]), x.shape[1]
    a, b, c = x[r, (j - 1) % m], x[r, j], x[r, (j + 1) % m]
    den = a - 2 * b + c
    u = np.where(den != 0, 0.5 * (a - c) / np.where(den != 0, den, 1.0), 0.0)
    return (j + u) * (2 * np.pi / m), b - 0.25 * (a - c) * u


def _columns(problem, pts: list[dict]) -> dict:
    """Designs (free-parameter dicts) as columns: free parameter -> array."""
    return {k: np.array([v[k] for v in pts], float) for k in problem.free}


def grid_loops(problem, cols: dict, theta: np.ndarray):
    """The type's loop over designs ``cols`` (free parameter -> array, first branch) x crank angles ``theta``, in
    vectorised passes of SCREEN_CHUNK designs: (first index, the pass's free columns, its Loop, x as (designs,
    angles)). No mechanism is built; a user type's loop that takes one design at a time raises TypeError,
    ValueError or IndexError. The caller sets numpy's error state."""
    cls, branch, names = problem.mechanism, branches(problem)[0], list(problem.free)
    n = next(iter(cols.values())).size if cols else 0
    given = {**problem.fixed, **branch, **{k: 1.0 for k in names}}
    base = {k: v for k, v in cls.PARAMS.items() if k not in given and isinstance(v, (int, float))}
    base.update(cls.completed(given))
    for i in range(0, n, SCREEN_CHUNK):
        part = {k: c[i : i + SCREEN_CHUNK] for k, c in cols.items()}
        loop = cls.loop(
            NUMPY, theta[None, :], {**base, **problem.fixed, **branch, **{k: c[:, None] for k, c in part.items()}}
        )
        yield i, part, loop, np.broadcast_to(loop.x, (min(SCREEN_CHUNK, n - i), theta.size))


def turns(loop, x) -> np.ndarray:
    """Which designs of a vectorised loop close at every grid angle and whose output reverses exactly twice."""
    ok = np.all(np.isfinite(x), axis=1)
    for _, margin in loop.margins:
        ok &= np.all(np.broadcast_to(margin, x.shape) >= 0, axis=1)
    dx = np.diff(x, axis=1, append=x[:, :1])
    ok &= np.count_nonzero(np.sign(dx) != np.sign(np.roll(dx, 1, axis=1)), axis=1) == 2
    return ok


def _to_stroke(problem, values, branch, build, stroke: float | None = None) -> dict:
    """The design scaled so that its stroke (given, or evaluated) meets the target, if scaling is free and stays
    in bounds."""
    target = problem.targets.get("stroke")
    scalable = list(problem.mechanism.scalable())
    if target is None or any(k in problem.fixed and problem.fixed[k] != 0.0 for k in scalable):
        return values
    try:
        k = target / (stroke if stroke else build(problem, values, branch).stroke())
    except QroptError:
        return values
    if not math.isfinite(k) or k <= 0:
        return values
    out = scaled(problem, values, k)
    inside = all(lo <= out[name] <= hi for name, (lo, hi) in problem.free.items())
    return out if inside else values


def scaled(problem, values: dict, k: float) -> dict:
    """The design with its lengths and offsets (the type's scalable parameters) times k: TR and angles do not
    change with scale."""
    scalable = problem.mechanism.scalable()
    return {name: x * k if name in scalable else x for name, x in values.items()}


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


__all__ = [
    "Plan",
    "branches",
    "plan",
    "sobol",
    "grown",
    "screen",
    "grid_cycle",
    "turning_points",
    "orientation",
    "dead_centre_start",
    "local_best",
    "grid_loops",
    "turns",
    "vertex",
    "refined_cycle",
    "from_unit",
    "rules_kept",
    "scaled",
]
