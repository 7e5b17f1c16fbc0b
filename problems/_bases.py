"""Base problems shared by the problem files of one family, and the closed-form design families their grid
oracles walk along. A problem file states only what differs (objective, conditions) and its oracle."""

from __future__ import annotations

import math

from problems import _oracles as oracles
from qropt import Problem
from qropt.synthesis import analytic


def slider_crank(**changes) -> Problem:
    """Offset slider-crank for TR 1.3 and stroke 0.3 m; r2, r3, e free."""
    base = Problem(
        mechanism="SliderCrank",
        free={"r2": (0.05, 0.3), "r3": (0.1, 1.5), "e": (0.0, 0.6)},
        targets={"time_ratio": 1.3, "stroke": 0.3},
    )
    return base.replace(**changes)


def slider_crank_oracle(problem, boundary=None):
    return oracles.along(problem, oracles.slider_crank_family(1.3, 0.3), 0.0501, 0.14999, boundary=boundary)


def crank_shaper_rod(**changes) -> Problem:
    """Crank-shaper with a rod to the ram (slide line 0.62 m above the pivot), TR 1.6, stroke 0.4 m."""
    base = Problem(
        mechanism="CrankShaper",
        fixed={"r1": 0.3, "h": 0.62},
        free={"r2": (0.01, 0.29), "r4": (0.1, 2.0), "r6": (0.15, 0.8)},
        targets={"time_ratio": 1.6, "stroke": 0.4},
    )
    return base.replace(**changes)


def crank_shaper_rod_oracle(problem):
    """r2, r4 in closed form (TR and stroke fix them); grid over the rod r6."""
    k = analytic.crank_shaper_ratio(1.6)
    return oracles.along(problem, lambda r6: {"r2": k * 0.3, "r4": 0.4 / (2 * k), "r6": r6}, 0.15, 0.8)


def whitworth(**changes) -> Problem:
    """Whitworth for TR 2.0 and stroke 0.3 m with r1 = 0.1 m; r2, r5, r6 free."""
    base = Problem(
        mechanism="Whitworth",
        fixed={"r1": 0.1},
        free={"r2": (0.11, 0.5), "r5": (0.05, 0.4), "r6": (0.2, 0.6)},
        targets={"time_ratio": 2.0, "stroke": 0.3},
    )
    return base.replace(**changes)


def whitworth_design(r6):
    """r2 and r5 in closed form (TR and stroke fix them); the rod r6 is the family parameter."""
    return {"r2": 0.1 / analytic.whitworth_ratio(2.0), "r5": 0.15, "r6": r6}


def crank_rocker_slider(**changes) -> Problem:
    """Crank-rocker-driven slider (slide line through O2 and O4), TR 1.2, stroke 0.15 m; r3, r4, r5 free."""
    base = Problem(
        mechanism="CrankRockerSlider",
        fixed={"r1": 0.3, "r2": 0.1, "r6": 0.5},
        free={"r3": (0.15, 0.6), "r4": (0.15, 0.45), "r5": (0.02, 0.45)},
        targets={"time_ratio": 1.2, "stroke": 0.15},
    )
    return base.replace(**changes)


def crank_rocker_slider_oracle(problem):
    """Grid along r4 for each root of the rocker's TR (r3), r5 from the stroke; the better of the two."""
    runs = [
        oracles.along(problem, oracles.crank_rocker_slider_family(1.2, 0.15, 0.3, 0.1, 0.5, k), 0.15, 0.45, n=150)
        for k in (0, 1)
    ]
    runs = [r for r in runs if r["objective"] is not None]
    pick = max if problem.objective == "max_gamma_min" else min
    return pick(runs, key=lambda r: r["objective"])


def classic_crank_rocker(**changes) -> Problem:
    """The classical crank-rocker design: ground 1, TR 1.25, swing 50 degrees; r2, r3, r4 free."""
    base = Problem(
        mechanism="FourBar",
        fixed={"r1": 1.0},
        free={"r2": (0.05, 1.0), "r3": (0.2, 3.0), "r4": (0.2, 3.0)},
        targets={"time_ratio": 1.25, "swing": math.radians(50)},
        conditions={"grashof": "crank-rocker"},
    )
    return base.replace(**changes)


def classic_design(pos):
    """The classical construction at ``pos`` along its circle (analytic.crank_rocker_design)."""
    d = analytic.crank_rocker_design(1.25, math.radians(50), 1.0, pos)
    return None if d is None else {"r2": d.r2, "r3": d.r3, "r4": d.r4}


def gamma_margin(problem, design, bound):
    """t -> gamma_min(design(t)) - bound, for locating a gamma_min condition's boundary along a family."""

    def margin(t):
        s = oracles.score(problem.replace(conditions={**problem.conditions, "gamma_min": 0.0}), design(t))
        return -1.0 if s is None else s[1]["gamma_min"] - bound

    return margin
