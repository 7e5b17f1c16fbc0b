"""The classical crank-rocker design: ground r1 = 1 fixed, TR 1.25 and rocker swing 50 degrees,
maximise the minimum transmission angle (r2, r3, r4 free).

Oracle: grid along the classical construction ``analytic.crank_rocker_design``, refined.
"""

import math

from problems import _oracle
from qropt import Problem, analytic

ORACLE = {"kind": "grid", "tolerance": 1e-7}


def build() -> Problem:
    return Problem(
        mechanism="FourBar",
        fixed={"r1": 1.0},
        free={"r2": (0.05, 1.0), "r3": (0.2, 3.0), "r4": (0.2, 3.0)},
        targets={"time_ratio": 1.25, "swing": math.radians(50)},
        conditions={"grashof": "crank-rocker"},
        objective="max_gamma_min",
        name="crank_rocker_classic",
    )


def oracle() -> dict:
    """The reference optimum: {'objective', 'params'}."""

    def design(pos):
        d = analytic.crank_rocker_design(1.25, math.radians(50), 1.0, pos)
        return None if d is None else {"r2": d.r2, "r3": d.r3, "r4": d.r4}

    return _oracle.along(build(), design, 0.005, 0.495)
