"""Whitworth for TR 2.0 and stroke 0.3 m (r1 = 0.1 m): best transmission angle; the rod r6 is free.

Oracle: r2, r5 in closed form; grid over r6, refined."""

from problems import _oracle
from qropt import Problem, analytic

ORACLE = {"kind": "grid", "tolerance": 1e-07}


def build() -> Problem:
    return Problem(
        mechanism="Whitworth",
        fixed={"r1": 0.1},
        free={"r2": (0.11, 0.5), "r5": (0.05, 0.4), "r6": (0.2, 0.6)},
        targets={"time_ratio": 2.0, "stroke": 0.3},
        objective="max_gamma_min",
        name="whitworth_gamma",
    )


def oracle() -> dict:
    """The reference optimum: {'objective', 'params'}."""
    p = build()
    r2 = 0.1 / analytic.whitworth_ratio(2.0)
    return _oracle.along(p, lambda r6: {"r2": r2, "r5": 0.15, "r6": r6}, 0.2, 0.6)
