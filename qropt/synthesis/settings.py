"""The search's tuning numbers, one object: ``Solver(settings=Settings(...))`` changes them for that Solver."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

from qropt.errors import ProblemError


@dataclass(frozen=True)
class Settings:
    """Each field's meaning in one line; relative tolerances are fractions of the value they compare with."""

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
