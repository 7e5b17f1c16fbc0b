"""The classical crank-rocker design: ground r1 = 1 fixed, TR 1.25 and rocker swing 50 degrees,
maximise the minimum transmission angle (r2, r3, r4 free).

Oracle: the classical construction ``analytic.crank_rocker_design`` swept densely along its family.
"""

import math

from qropt import Problem


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
