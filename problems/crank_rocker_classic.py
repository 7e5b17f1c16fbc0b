"""The classical crank-rocker design: ground r1 = 1 fixed, TR 1.25 and rocker swing 50 degrees,
maximise the minimum transmission angle (r2, r3, r4 free).

Oracle: grid along the classical construction ``analytic.crank_rocker_design``, refined."""

from problems import _bases as problem_bases
from problems import _oracles as oracles

ORACLE = {"kind": "grid", "tolerance": 1e-7}


def build():
    return problem_bases.classic_crank_rocker(objective="max_gamma_min", name="crank_rocker_classic")


def oracle() -> dict:
    """The reference optimum: {'objective', 'params'}."""
    return oracles.along(build(), problem_bases.classic_design, 0.005, 0.495)
