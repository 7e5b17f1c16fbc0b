"""Offset slider-crank for TR 1.3 and stroke 0.3 m, smallest r2 + r3 with gamma_min >= 30 degrees.

Oracle: grid along the closed-form family; the gamma_min boundary located by brentq."""

import math

from problems import _bases as problem_bases
from problems import _oracles as oracles

ORACLE = {"kind": "grid", "tolerance": 1e-7}


def build():
    return problem_bases.slider_crank(
        conditions={"gamma_min": math.radians(30)}, objective="min_size", name="slider_crank_size"
    )


def oracle() -> dict:
    """The reference optimum: {'objective', 'params'}."""
    p = build()
    margin = problem_bases.gamma_margin(p, oracles.slider_crank_family(1.3, 0.3), math.radians(30))
    return problem_bases.slider_crank_oracle(p, boundary=margin)
