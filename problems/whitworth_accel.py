"""Whitworth for TR 2.0 and stroke 0.3 m (r1 = 0.1 m fixed) with the least peak ram acceleration
at omega2 = 10 rad/s; the rod r6 is free.

Oracle: r2 = r1 / sin(phi / 2) = 0.2 m and r5 = 0.15 m are forced; the peak acceleration falls as
the rod lengthens, so the optimum is r6 at its upper bound (reference: grid over r6, refined)."""

from problems import _bases as problem_bases
from problems import _oracles as oracles

ORACLE = {"kind": "grid", "tolerance": 1e-6}


def build():
    return problem_bases.whitworth(objective="min_peak_accel", omega2=10.0, name="whitworth_accel")


def oracle() -> dict:
    """The reference optimum: {'objective', 'params'}."""
    return oracles.along(build(), problem_bases.whitworth_design, 0.2, 0.6)
