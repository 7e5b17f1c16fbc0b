"""Crank-shaper (yoke) for TR 1.6 and stroke 0.4 m with centres r1 = 0.3 m: the shortest lever.

Oracle: closed form r2 = r1 sin(phi / 2), r4 = stroke r1 / (2 r2) (phi of eq. 7): the lever length
is fixed by TR and stroke, so ``min_size`` must return it.
"""

from problems import _oracles as oracles
from qropt import Problem
from qropt.synthesis import analytic

ORACLE = {"kind": "closed form", "tolerance": 1e-9}


def build() -> Problem:
    return Problem(
        mechanism="CrankShaper",
        fixed={"r1": 0.3},
        free={"r2": (0.01, 0.29), "r4": (0.1, 2.0)},
        targets={"time_ratio": 1.6, "stroke": 0.4},
        objective="min_size",
        size="longest",
        name="crank_shaper_size",
    )


def oracle() -> dict:
    """The reference optimum: {'objective', 'params'}."""
    k = analytic.crank_shaper_ratio(1.6)
    return oracles.best_of(build(), [{"r2": 0.3 * k, "r4": 0.4 / (2 * k)}])
