"""Whitworth for TR 2.0 and stroke 0.3 m: the smallest sum of lengths with gamma_min >= 60 degrees.

Oracle: r2, r5 in closed form; grid over r6 with the gamma_min boundary located by brentq."""

import math

from problems import _bases as problem_bases
from problems import _oracles as oracles

ORACLE = {"kind": "grid", "tolerance": 1e-7}


def build():
    return problem_bases.whitworth(
        conditions={"gamma_min": math.radians(60)}, objective="min_size", name="whitworth_size"
    )


def oracle() -> dict:
    """The reference optimum: {'objective', 'params'}."""
    p = build()
    margin = problem_bases.gamma_margin(p, problem_bases.whitworth_design, math.radians(60))
    return oracles.along(p, problem_bases.whitworth_design, 0.2, 0.6, boundary=margin)
