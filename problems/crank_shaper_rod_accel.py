"""Crank-shaper with a rod to the ram for TR 1.6 and stroke 0.4 m: least peak ram acceleration at 5 rad/s
over the rod length.

Oracle: r2, r4 in closed form; grid over r6, refined."""

from problems import _oracle
from qropt import Problem, analytic

ORACLE = {"kind": "grid", "tolerance": 1e-06}


def build() -> Problem:
    return Problem(
        mechanism="CrankShaper",
        fixed={"r1": 0.3, "h": 0.62},
        free={"r2": (0.01, 0.29), "r4": (0.1, 2.0), "r6": (0.15, 0.8)},
        targets={"time_ratio": 1.6, "stroke": 0.4},
        objective="min_peak_accel",
        omega2=5.0,
        name="crank_shaper_rod_accel",
    )


def oracle() -> dict:
    """The reference optimum: {'objective', 'params'}."""
    p = build()
    k = analytic.crank_shaper_ratio(1.6)
    return _oracle.along(p, lambda r6: {"r2": k * 0.3, "r4": 0.4 / (2 * k), "r6": r6}, 0.15, 0.8)
