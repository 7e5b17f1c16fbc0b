"""The lab rig of seed 001 (centres 160 mm, yoke) redesigned to TR 1.6 with its 120 mm stroke: crank and lever
lengths, the shortest lever.

Oracle: closed form r2 = r1 sin(phi / 2), r4 = stroke / (2 sin(phi / 2))."""

from problems import _oracles as oracles
from qropt import Problem
from qropt.synthesis import analytic

ORACLE = {"kind": "closed form", "tolerance": 1e-09}


def build() -> Problem:
    return Problem(
        mechanism="CrankShaper",
        fixed={"r1": 160.0},
        free={"r2": (5.0, 150.0), "r4": (50.0, 600.0)},
        targets={"time_ratio": 1.6, "stroke": 120.0},
        objective="min_size",
        size="longest",
        name="seed001_redesign",
    )


def oracle() -> dict:
    """The reference optimum: {'objective', 'params'}."""
    k = analytic.crank_shaper_ratio(1.6)
    return oracles.best_of(build(), [{"r2": 160.0 * k, "r4": 120.0 / (2 * k)}])
