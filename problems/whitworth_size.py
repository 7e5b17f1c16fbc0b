"""Whitworth for TR 2.0 and stroke 0.3 m: the smallest sum of lengths with gamma_min >= 60 degrees.

Oracle: r2, r5 in closed form; grid over r6 with the gamma_min boundary located by brentq."""

import math

from problems import _oracle
from qropt import Problem, analytic

ORACLE = {"kind": "grid", "tolerance": 1e-07}


def build() -> Problem:
    return Problem(
        mechanism="Whitworth",
        fixed={"r1": 0.1},
        free={"r2": (0.11, 0.5), "r5": (0.05, 0.4), "r6": (0.2, 0.6)},
        targets={"time_ratio": 2.0, "stroke": 0.3},
        conditions={"gamma_min": math.radians(60)},
        objective="min_size",
        name="whitworth_size",
    )


def oracle() -> dict:
    """The reference optimum: {'objective', 'params'}."""
    p = build()
    r2 = 0.1 / analytic.whitworth_ratio(2.0)

    def design(r6):
        return {"r2": r2, "r5": 0.15, "r6": r6}

    def margin(r6):
        s = _oracle.score(p.replace(conditions={}), design(r6))
        return -1.0 if s is None else s[1]["gamma_min"] - math.radians(60)

    return _oracle.along(p, design, 0.2, 0.6, boundary=margin)
