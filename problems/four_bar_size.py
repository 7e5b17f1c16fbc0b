"""Classical crank-rocker (ground 1, TR 1.25, swing 50 degrees): the shortest longest link with gamma_min >= 35 deg.

Oracle: grid along the classical construction, the gamma_min boundary located by brentq."""

import math

from problems import _oracle
from qropt import Problem, analytic

ORACLE = {"kind": "grid", "tolerance": 1e-07}


def build() -> Problem:
    return Problem(
        mechanism="FourBar",
        fixed={"r1": 1.0},
        free={"r2": (0.05, 1.0), "r3": (0.2, 3.0), "r4": (0.2, 3.0)},
        targets={"time_ratio": 1.25, "swing": math.radians(50)},
        conditions={"gamma_min": math.radians(35)},
        objective="min_size",
        size="longest",
        name="four_bar_size",
    )


def oracle() -> dict:
    """The reference optimum: {'objective', 'params'}."""
    p = build()

    def design(pos):
        d = analytic.crank_rocker_design(1.25, math.radians(50), 1.0, pos)
        return None if d is None else {"r2": d.r2, "r3": d.r3, "r4": d.r4}

    def margin(pos):
        s = _oracle.score(p.replace(conditions={}), design(pos))
        return -1.0 if s is None else s[1]["gamma_min"] - math.radians(35)

    return _oracle.along(p, design, 0.005, 0.495, boundary=margin)
