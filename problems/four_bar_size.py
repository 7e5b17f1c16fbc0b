"""Classical crank-rocker (ground 1, TR 1.25, swing 50 degrees): the shortest longest link with gamma_min >= 35 deg.

Oracle: grid along the classical construction, the gamma_min boundary located by brentq."""

import math

from problems import _bases as problem_bases
from problems import _oracles as oracles

ORACLE = {"kind": "grid", "tolerance": 1e-7}


def build():
    return problem_bases.classic_crank_rocker(
        conditions={"grashof": "crank-rocker", "gamma_min": math.radians(35)},
        objective="min_size",
        size="longest",
        name="four_bar_size",
    )


def oracle() -> dict:
    """The reference optimum: {'objective', 'params'}."""
    p = build()
    margin = problem_bases.gamma_margin(p, problem_bases.classic_design, math.radians(35))
    return oracles.along(p, problem_bases.classic_design, 0.005, 0.495, boundary=margin)
