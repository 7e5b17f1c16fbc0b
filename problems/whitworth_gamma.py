"""Whitworth for TR 2.0 and stroke 0.3 m (r1 = 0.1 m): best transmission angle; the rod r6 is free.

Oracle: r2, r5 in closed form; grid over r6, refined."""

from problems import _bases as problem_bases
from problems import _oracles as oracles

ORACLE = {"kind": "grid", "tolerance": 1e-7}


def build():
    return problem_bases.whitworth(objective="max_gamma_min", name="whitworth_gamma")


def oracle() -> dict:
    """The reference optimum: {'objective', 'params'}."""
    return oracles.along(build(), problem_bases.whitworth_design, 0.2, 0.6)
