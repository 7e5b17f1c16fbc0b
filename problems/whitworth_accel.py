"""Whitworth for TR 2.0 and stroke 0.3 m (r1 = 0.1 m fixed) with the least peak ram acceleration
at omega2 = 10 rad/s; the rod r6 is free.

Oracle: r2 = r1 / sin(phi / 2) = 0.2 m and r5 = 0.15 m are forced; the peak acceleration falls as
the rod lengthens, so the optimum is r6 at its upper bound (reference: dense scan of r6 at test time).
"""

from qropt import Problem


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
