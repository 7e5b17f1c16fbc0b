"""Offset slider-crank for TR 1.3 and stroke 0.3 m with the best transmission angle (r2, r3, e free).

Oracle: grid along the closed-form family (r2 -> r3, e from the stroke triangle), refined."""

from problems import _bases as problem_bases

ORACLE = {"kind": "grid", "tolerance": 1e-7}


def build():
    return problem_bases.slider_crank(objective="max_gamma_min", name="slider_crank_gamma")


def oracle() -> dict:
    """The reference optimum: {'objective', 'params'}."""
    return problem_bases.slider_crank_oracle(build())
