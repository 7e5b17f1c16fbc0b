"""Whitworth for TR 2.0 and stroke 0.3 m (r1 = 0.1 m fixed) with the least peak ram acceleration
at omega2 = 10 rad/s; the rod r6 is free.

Oracle: r2 = r1 / sin(phi / 2) = 0.2 m and r5 = 0.15 m are forced; the peak acceleration falls as
the rod lengthens, so the optimum is r6 at its upper bound (reference: grid over r6, refined).
"""

from problems import _oracle
from qropt import Problem, analytic

ORACLE = {"kind": "grid", "tolerance": 1e-6}


def build() -> Problem:
    return Problem(
        mechanism="Whitworth",
        fixed={"r1": 0.1},
        free={"r2": (0.11, 0.5), "r5": (0.05, 0.4), "r6": (0.2, 0.6)},
        targets={"time_ratio": 2.0, "stroke": 0.3},
        objective="min_peak_accel",
        omega2=10.0,
        name="whitworth_accel",
    )


def oracle() -> dict:
    """The reference optimum: {'objective', 'params'}."""
    r2 = 0.1 / analytic.whitworth_ratio(2.0)
    return _oracle.along(build(), lambda r6: {"r2": r2, "r5": 0.15, "r6": r6}, 0.2, 0.6)
