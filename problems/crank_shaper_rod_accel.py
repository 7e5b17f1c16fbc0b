"""Crank-shaper with a rod to the ram for TR 1.6 and stroke 0.4 m: least peak ram acceleration at 5 rad/s
over the rod length.

Oracle: r2, r4 in closed form; grid over r6, refined."""

from problems import _bases as problem_bases

ORACLE = {"kind": "grid", "tolerance": 1e-6}


def build():
    return problem_bases.crank_shaper_rod(objective="min_peak_accel", omega2=5.0, name="crank_shaper_rod_accel")


def oracle() -> dict:
    """The reference optimum: {'objective', 'params'}."""
    return problem_bases.crank_shaper_rod_oracle(build())
