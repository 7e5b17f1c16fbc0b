"""The search's tuning numbers, one object: ``Solver(settings=Settings(...))`` changes them for that Solver."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

from qropt.errors import ProblemError


@dataclass(frozen=True)
class Settings:
    """How much each strategy searches, a field each, its meaning in one line; relative tolerances are fractions
    of the value they compare with. The numbers that define the NLP, its certificate or a verification stay with
    their definitions (``formulation``, ``certificate``, ``newton``)."""

    tie_tol: float = 1e-9  # relative: designs this close to an optimum tie with it (the least-size tie-break)
    stands: float = 1e-6  # relative: a descent's end this much better than every certified design is the result
    polished: int = 3  # the best certified designs the SQP on the exact peak descends again
    refreshes: int = 3  # a dynamic objective's best design solved again from itself at most this often
    tie_scan: int = 24  # scales of a continuum's tied lengths evaluated exactly, log-spaced over the bounds
    tie_bisect: int = 24  # bisections of the least scale whose size is the least
    min_way: int = 3  # space-filling starts tried in each way of meeting the TR equality, at least
    walk_grid: int = 33  # points of a family walk's finer grid between two scan points, before its bounded search
    walk_xtol: float = 1e-12  # a family walk's search tolerance relative to its parameter
    many_starts: int = 6  # more closed-form points than this are scored exactly and only the best few refined
    wider: int = 4  # the diagnosis's wider multi-start runs this many times the starts
    wrap_edge: float = 1e-6  # rad: a design's angle this near an edge of a full-turn box is at it
    evolution_generations: int = 100  # an evolution's generations
    thin: int = 3  # a second pass certifying fewer designs than this is thin: the wider multi-start runs too
    guard_step: float = 0.7  # a guarded design is continued through guards this much smaller each step
    guard_least: float = math.radians(1.0)  # rad: the smallest guard before none
    atlas_short: float = 0.02  # relative: atlas starts ending this much worse than their nodes' designs run again
    diagnosis_starts: int = 4  # space-filling starts of each solve a diagnosis runs
    range_solves: int = 4  # local solves that push a reachable range's ends out (two an end)
    range_samples: int = 64  # designs spread over the bounds whose exact target values start a reachable range
    # space-filling starts (``starts``)
    start_pool: int = 64  # Sobol points drawn per start wanted: the type's rules (one vectorised check) thin them
    rule_draws: int = 2**17  # Sobol points one call for rule points draws at most
    max_corners: int = 64  # the corners of the free bounds tried as designs, at most (every one up to six free)
    screen_points: int = 4096  # rule points a screen draws at least
    screen_grid: int = 180  # crank angles of a screen's grid
    screen_keep: int = 4  # designs per start wanted evaluated exactly, nearest the TR target first
    screen_tr_near: float = 0.05  # in log: a screened design this near the TR target competes on its objective
    shape_points: int = 32768  # rule points a shape search draws
    shape_grid: int = 64  # its crank angles (dead centres refined by the grid parabola)
    shape_window: float = 0.02  # relative: shapes this near the TR target compete on their objective
    shape_keep: int = 4  # starts a shape search gives, best by the grid objective first
    # the differential evolution and its descents (``evolution``, ``descents``)
    evolution_nodes: int = 48  # crank lengths (uniform in log over its bounds) at which a candidate's grid TR is read
    evolution_grid: int = 64  # crank angles of that grid
    evolution_window: float = 0.01  # relative: a candidate whose exact TR is this near the target is valued
    evolution_population: int = 15  # candidates per free parameter (SciPy's popsize)
    evolution_keep: int = 4  # distinct designs an evolution hands on
    evolution_distinct: float = 0.05  # designs differ when a parameter differs by this (in log, or of its range)
    many_free: int = 7  # a problem with this many free parameters or more runs ``many_evolutions`` by default
    many_evolutions: int = 4  # ... else none
    descent_evals: int = 1000  # exact evaluations of a Nelder-Mead descent
    secant_reach: float = 0.05  # relative: how far the secant steps onto the TR target may take the crank
    # the SQP on the exact peak (``minimax``)
    sqp_steps: int = 150  # its steps at most
    sqp_stationary: float = 1e-8  # relative: a step's predicted decrease below this ends it
    # the local solve (``local``, ``newton``)
    exchange_stuck: int = 3  # exchange rounds that end alike, in a row, after which the exchange loop stops
    restarts: int = 2  # runs continued from their last iterate when they hit the iteration limit near a design
    coarse_nodes: int = 48  # Gauss-Legendre nodes a stroke of a quadrature's first runs (``Criterion.coarse``); as
    # many as the certifier's rule (48) or more: no coarser rule
    relifts: int = 2  # runs of a dynamic objective continued, their extremes lifted anew, after the iteration limit
    restart_violation: float = 1e-6  # "near a design": no constraint violated by more than this
    newton_steps: int = 8  # Newton steps of a continuation from a neighbour's optimum, at most
    newton_size: int = 2_000  # NLPs (objective and rows) of at most this many instructions are continued by Newton

    def __post_init__(self):
        for f in dataclasses.fields(self):
            v = getattr(self, f.name)
            kind = type(f.default)
            ok = isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) and v > 0
            if kind is int:
                ok = ok and isinstance(v, int)
            if not ok:
                raise ProblemError(f"Settings: {f.name} is a positive {kind.__name__}, got {v!r}")

    def to_dict(self) -> dict:
        return dataclasses.asdict(self)

    @classmethod
    def from_dict(cls, d) -> Settings:
        names = {f.name for f in dataclasses.fields(cls)}
        if not isinstance(d, dict) or set(d) - names:
            raise ProblemError(f"Settings are {sorted(names)}, got {d!r}")
        return cls(**d)


DEFAULT = Settings()

__all__ = ["Settings", "DEFAULT"]
