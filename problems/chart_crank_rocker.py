"""The crank-rocker design chart (Brodell and Soni's charts, computed exactly): ground r1 = 1; the best minimum
transmission angle and the optimal crank r2, coupler r3 and rocker r4 over time ratio x rocker swing.

Chart: ``qropt chart problems/chart_crank_rocker.py`` (default axes X and Y). Oracle at any cell: every design
with the cell's TR and swing lies on the classical construction (``analytic.crank_rocker_design``), swept densely
and refined by bounded Brent."""

import math

from qropt import Problem

X = ("time_ratio", tuple(1.05 + 1.95 * k / 39 for k in range(40)))
Y = ("swing", tuple(math.radians(30 + 5 * k) for k in range(19)))


def build():
    return Problem(
        mechanism="FourBar",
        fixed={"r1": 1.0},
        free={"r2": (0.01, 1.0), "r3": (0.05, 10.0), "r4": (0.05, 10.0)},
        targets={"time_ratio": 1.5, "swing": math.radians(60)},
        conditions={"grashof": "crank-rocker"},
        objective="max_gamma_min",
        name="chart_crank_rocker",
    )
