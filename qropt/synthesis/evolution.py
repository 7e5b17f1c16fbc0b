"""Designs on the targets without the NLP: a differential evolution over the box and descents on the exact objective.

For a problem with TR and stroke targets whose lengths scale freely and whose crank length (the type's
``Mechanism.SYNTHESIS.crank``) is free.

- ``evolve``: SciPy's differential evolution over the unit box (lengths log-uniform, other parameters uniform).
  Each candidate is moved onto the TR target by its crank length: its TR on a crank-angle grid (the type's loop in
  numpy, vectorised over candidates x ``evolution_nodes`` crank lengths x ``evolution_grid`` angles, extremes refined by
  the grid parabola), the crossing of the target nearest the candidate's own crank gene interpolated. It is then built,
  scaled to the stroke and, within ``evolution_window`` of the TR exactly and inside the box, valued by the exact
  objective (minimised); off the targets its value is INFEASIBLE plus how far off, so the evolution moves toward them
  first.
- ``on_targets``: a design with its crank length moved until the exact TR meets the target (secant steps from
  its own, else Brent's root search in a bracket grown from 0.2 % to 30 %), then scaled to the stroke.
- ``descend``: Nelder-Mead on the exact objective over every free parameter but the crank, each point put on the
  targets by ``on_targets``: no samples between which a torque spike could hide. With ``Solver(sqp=True)`` a
  peak over the turn is descended by an SQP on its exact extremes too (``minimax.polish``), which does not stall
  where peaks are equal (``descended``).

Grid values place candidates; the values that rank them are exact. The descents' ends are starts
(``MultiStart.evolved``), part of a benchmark's reference (``benchmarks.search``) and, where one beats every
certified design, a solve's ``feasible`` result (``Solver.descended``): they meet the targets exactly; the NLP
does not certify them (an SQP's end is first-order stationary, a Nelder-Mead end carries nothing).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from qropt.errors import QroptError
from qropt.synthesis import criteria
from qropt.synthesis import starts as starts_
from qropt.synthesis.settings import DEFAULT, Settings

INFEASIBLE = 1e12  # the value of a candidate off the targets (plus how far off)
SECANT_STEP, SECANT_STEPS, SECANT_TOL = 1e-4, 8, 1e-14  # ``on_targets``'s secant steps: first step (relative),
# most steps and the |log TR ratio| that ends them
DESCENT_LOCAL = "none: the end of a Nelder-Mead descent on the exact objective, every point on the targets"


def count(problem, settings: Settings = DEFAULT) -> int:
    """The evolutions a solve runs by default: ``many_evolutions`` where the problem has ``many_free`` free
    parameters or more (the four-bar-driven types), else none: each evolution reaches its own basins at the cost
    of its own run, which pays where the free parameters are many; with fewer, the starts (the closed forms', the
    atlas's and the spread ones) already reach the designs an evolution finds (docs/benchmarks.md).
    ``Solver(evolutions=k)`` runs k anyway."""
    return settings.many_evolutions if len(problem.free) >= settings.many_free else 0


@dataclass(frozen=True)
class End:
    """A descent's end: its exact objective (minimised: negated where it is maximised), the design (free
    parameters) and what holds there (a certificate's ``local`` words)."""

    value: float
    design: dict
    local: str


def applies(problem) -> bool:
    """Whether the problem has TR and stroke targets, free scale, a free crank length and an objective."""
    scalable = problem.mechanism.scalable()
    return (
        bool(problem.objective)
        and {"time_ratio", "stroke"} <= set(problem.targets)
        and problem.mechanism.SYNTHESIS.crank in problem.free
        and not any(k in problem.fixed and problem.fixed[k] != 0.0 for k in scalable)
        and all(problem.free[k][0] > 0 for k in problem.free if problem.mechanism.kinds()[k] == "length")
    )


def value(problem, design: dict, branch: dict | None = None) -> float | None:
    """The exact objective of a design (free parameters; the first branch unless given), minimised (negated
    where it is maximised); None where it does not build, its analysis fails, it breaks a bound condition or its
    output turns back inside a stroke (``Mechanism.dwells``: a descent would walk into the dwell tolerance)."""
    try:
        m = problem.build(design, branch or starts_.branches(problem)[0])
        if m.dwells() or any(v > 0.0 for v in criteria.violations(problem, m).values()):
            return None
        v = criteria.objective_of(problem, m)
    except QroptError:
        return None
    if v is None or not math.isfinite(v):
        return None
    return -v if criteria.maximises(problem.objective) else v


def outside(problem, design: dict) -> float:
    """How far a design lies outside the box (0 inside): log ratios for lengths, fractions of the range else."""
    out, kinds = 0.0, problem.mechanism.kinds()
    for k, (lo, hi) in problem.free.items():
        x, log = design[k], kinds[k] == "length"
        if x < lo:
            out += math.log(lo / x) if log and x > 0 else (lo - x) / (hi - lo)
        elif x > hi:
            out += math.log(x / hi) if log else (x - hi) / (hi - lo)
    return out


def _to_stroke(problem, design: dict, stroke: float) -> dict:
    """The design scaled from its stroke to the target's."""
    return starts_.scaled(problem, design, problem.targets["stroke"] / stroke)


def _grid_miss(problem, cols: dict, grid: int) -> np.ndarray:
    """log(TR / target) of designs given as columns (free parameter -> array) on a grid of ``grid`` crank angles,
    first branch; nan
    where a design breaks the type's rules, does not close everywhere or does not reverse exactly twice."""
    n = next(iter(cols.values())).size
    theta = np.linspace(0.0, 2 * np.pi, grid, endpoint=False)
    miss = np.full(n, np.nan)
    with np.errstate(all="ignore"):
        for i, part, loop, x in starts_.grid_loops(problem, cols, theta):
            ok = starts_.turns(loop, x) & starts_.rules_kept(problem, part)
            tr, _ = starts_.refined_cycle(x)
            miss[i : i + x.shape[0]] = np.where(ok, np.log(tr / problem.targets["time_ratio"]), np.nan)
    return miss


def evolve(problem, generations: int, seed: int, keep: int | None = None, settings: Settings = DEFAULT) -> list[dict]:
    """Up to ``keep`` (``settings.evolution_keep``) distinct designs (free-parameter dicts) of an evolution of
    ``generations`` (module docstring), exact objective best first; each within ``evolution_window`` of the TR, at the
    stroke, inside the box. None for a user type whose loop takes one design at a time (it does not vectorise over
    designs)."""
    from scipy.optimize import differential_evolution  # imported here: scipy.optimize takes a while to import

    names, crank = list(problem.free), problem.mechanism.SYNTHESIS.crank
    others = [k for k in names if k != crank]
    branch = starts_.branches(problem)[0]
    s, keep = settings, keep or settings.evolution_keep
    nodes = np.linspace(0.0, 1.0, s.evolution_nodes)
    found: list[tuple[float, dict]] = []

    def candidate(row: np.ndarray, gene: float, d: dict) -> float:
        ends = np.flatnonzero(np.isfinite(row[:-1]) & np.isfinite(row[1:]) & (np.sign(row[:-1]) != np.sign(row[1:])))
        if ends.size == 0:  # no crank length meets the TR: how near the nearest comes
            near = np.abs(row[np.isfinite(row)])
            return INFEASIBLE * (3.0 + (float(near.min()) if near.size else 10.0))
        c = ends[np.argmin(np.abs(ends + 0.5 - gene * (s.evolution_nodes - 1)))]  # the crossing nearest the crank gene
        u = nodes[c] + row[c] / (row[c] - row[c + 1]) * (nodes[c + 1] - nodes[c])
        d = d | {crank: float(starts_.from_unit(problem, crank, u))}
        try:
            m = problem.build(d, branch)
            miss = abs(math.log(m.time_ratio() / problem.targets["time_ratio"]))
            d = _to_stroke(problem, d, m.stroke())
        except (QroptError, ValueError, ZeroDivisionError):
            return INFEASIBLE * 2.0
        off = outside(problem, d)
        if off > 0 or miss > s.evolution_window:
            return INFEASIBLE * (1.0 + off + miss)
        v = value(problem, d, branch)
        if v is None:
            return INFEASIBLE * 2.0
        found.append((v, d))
        return v

    def values(u: np.ndarray) -> np.ndarray:  # u: (parameters, candidates), SciPy's vectorised call
        n = u.shape[1]
        cols = {k: np.repeat(starts_.from_unit(problem, k, u[names.index(k)]), s.evolution_nodes) for k in others}
        cols[crank] = np.tile(starts_.from_unit(problem, crank, nodes), n)
        miss = _grid_miss(problem, cols, s.evolution_grid).reshape(n, s.evolution_nodes)
        gene = u[names.index(crank)]
        return np.array(
            [
                candidate(miss[i], float(gene[i]), {k: float(cols[k][i * s.evolution_nodes]) for k in others})
                for i in range(n)
            ]
        )

    try:  # one small vectorised call first
        _grid_miss(problem, {k: np.full(2, starts_.from_unit(problem, k, 0.5)) for k in names}, s.evolution_grid)
    except (TypeError, ValueError, IndexError):  # a user type's loop that takes one design at a time
        return []
    differential_evolution(
        values,
        [(0.0, 1.0)] * len(names),
        popsize=s.evolution_population,
        maxiter=generations,
        seed=seed,
        tol=0.0,
        init="sobol",
        polish=False,
        vectorized=True,
        updating="deferred",
    )
    found.sort(key=lambda f: f[0])
    chosen: list[dict] = []
    for _, d in found:
        if all(apart(problem, d, c, s) for c in chosen):
            chosen.append(d)
            if len(chosen) == keep:
                break
    return chosen


def apart(problem, a: dict, b: dict, settings: Settings = DEFAULT) -> bool:
    """Whether two designs differ by ``evolution_distinct`` in some free parameter (in log for lengths, of its range
    else)."""
    kinds = problem.mechanism.kinds()
    for k, (lo, hi) in problem.free.items():
        log = kinds[k] == "length"
        if (abs(math.log(a[k] / b[k])) if log else abs(a[k] - b[k]) / (hi - lo)) > settings.evolution_distinct:
            return True
    return False


def _secant(miss, c0: float, e0: float, lo: float, hi: float, reach: float) -> float | None:
    """The crank length where ``miss`` (the log TR ratio) is zero by secant steps from c0 (e0 = miss(c0)):
    converged to SECANT_TOL and at most ``reach`` (relative) from c0, or None (then the bracket and Brent's search)."""
    a, fa, b = c0, e0, c0 * (1.0 + SECANT_STEP)
    fb = miss(b)
    for _ in range(SECANT_STEPS):
        if not math.isfinite(fb) or fb == fa:
            return None
        if abs(fb) <= SECANT_TOL:
            return b
        c = b - fb * (b - a) / (fb - fa)
        if not lo <= c <= hi or abs(c - c0) > reach * c0:
            return None
        a, fa, b = b, fb, c
        fb = miss(b)
    return None


def on_targets(problem, design: dict, bounds: tuple | None = None, settings: Settings = DEFAULT) -> dict | None:
    """The design with its crank length moved to one whose exact TR meets the target (by secant steps from its
    own, else the nearest by Brent's search in a growing bracket) and scaled to the stroke (module docstring);
    None if neither finds one. ``bounds``: the crank lengths searched (default: its box)."""
    from scipy.optimize import brentq

    branch, crank = starts_.branches(problem)[0], problem.mechanism.SYNTHESIS.crank
    lo, hi = bounds or problem.free[crank]
    built: dict = {}  # crank length -> its mechanism, the last one only (the root's is built once)

    def miss(c: float) -> float:
        try:
            built.clear()
            built[c] = problem.build(design | {crank: c}, branch)
            return math.log(built[c].time_ratio() / problem.targets["time_ratio"])
        except (QroptError, ValueError, ZeroDivisionError):
            return math.nan

    c0 = design[crank]
    e0 = miss(c0)
    if not math.isfinite(e0):
        return None
    root = c0 if e0 == 0.0 else _secant(miss, c0, e0, lo, hi, settings.secant_reach)
    for step in (1.002, 1.01, 1.03, 1.1, 1.3):
        for c1 in (c0 * step, c0 / step):
            e1 = miss(c1) if root is None and lo <= c1 <= hi else math.nan
            if math.isfinite(e1) and e1 * e0 <= 0.0:
                try:
                    root = brentq(miss, min(c0, c1), max(c0, c1), xtol=1e-15, rtol=1e-14)
                except ValueError:  # a crank length inside the bracket where the loop does not close
                    continue
    if root is None:
        return None
    try:
        m = built.get(root) or problem.build(design | {crank: root}, branch)
        return _to_stroke(problem, design | {crank: root}, m.stroke())
    except (QroptError, ValueError, ZeroDivisionError):
        return None


def descend(problem, design: dict, evals: int | None = None, settings: Settings = DEFAULT) -> tuple[float, dict] | None:
    """A Nelder-Mead descent from a design on the exact objective (minimised) with every point on the targets (module
    docstring), of ``evals`` exact evaluations (``settings.descent_evals``): the best (value, design) met, or None."""
    from scipy.optimize import minimize

    names = [k for k in problem.free if k != problem.mechanism.SYNTHESIS.crank]
    log = {k: problem.mechanism.kinds()[k] == "length" for k in names}
    branch = starts_.branches(problem)[0]
    best: list = [None]

    def cost(z: np.ndarray) -> float:
        moved = {k: math.exp(x) if log[k] else x for k, x in zip(names, z, strict=True)}
        d = on_targets(problem, design | moved, settings=settings)
        f = None if d is None or outside(problem, d) > 0 else value(problem, d, branch)
        if f is None:
            return math.inf
        if best[0] is None or f < best[0][0]:
            best[0] = (f, d)
        return f

    z0 = np.array([math.log(design[k]) if log[k] else design[k] for k in names])
    if not math.isfinite(cost(z0)):  # no exact value at the start: nothing to descend from
        return None
    opts = {"maxfev": evals or settings.descent_evals, "xatol": 1e-9, "fatol": 1e-12, "adaptive": True}
    with np.errstate(invalid="ignore"):  # a simplex with several points without a value (inf - inf)
        minimize(cost, z0, method="Nelder-Mead", options=opts)
    return best[0]


__all__ = [
    "End",
    "applies",
    "count",
    "evolve",
    "on_targets",
    "descend",
    "apart",
    "outside",
    "value",
]
