"""Hard: a crank-rocker (r1 = 1, r2 = 0.2, r4 = 0.9) for TR 1.2 with the coupler confined to a narrow window
around one of its two solutions.

Oracle: closed form (the rocker's TR from its limit positions) solved for r3 by brentq."""

from problems import _oracles as oracles
from qropt import Problem

ORACLE = {"kind": "closed form", "tolerance": 1e-09}


def build() -> Problem:
    return Problem(
        mechanism="FourBar",
        fixed={"r1": 1.0, "r2": 0.2, "r4": 0.9},
        free={"r3": (1.38, 1.41)},
        targets={"time_ratio": 1.2},
        objective="max_gamma_min",
        name="four_bar_narrow",
    )


def oracle() -> dict:
    """The reference optimum: {'objective', 'params'}."""
    p = build()
    return oracles.best_of(p, [{"r3": x} for x in oracles.crank_rocker_r3(1.2, 1.0, 0.2, 0.9)])
