"""Offset slider-crank for TR 1.3 and stroke 0.3 m with the least peak slider acceleration (omega2 = 1).

Oracle: grid along the closed-form family, refined."""

from problems import _bases as problem_bases

ORACLE = {"kind": "grid", "tolerance": 1e-6}


def build():
    return problem_bases.slider_crank(objective="min_peak_accel", name="slider_crank_accel")


def oracle() -> dict:
    """The reference optimum: {'objective', 'params'}."""
    return problem_bases.slider_crank_oracle(build())
