"""Offset slider-crank for TR 1.3 and stroke 0.3 m with the best transmission angle (r2, r3, e free).

Oracle: grid along the closed-form family (r2 -> r3, e from the stroke triangle), refined."""

from problems import _oracle
from qropt import Problem

ORACLE = {"kind": "grid", "tolerance": 1e-07}


def build() -> Problem:
    return Problem(
        mechanism="SliderCrank",
        free={"r2": (0.05, 0.3), "r3": (0.1, 1.5), "e": (0.0, 0.6)},
        targets={"time_ratio": 1.3, "stroke": 0.3},
        objective="max_gamma_min",
        name="slider_crank_gamma",
    )


def oracle() -> dict:
    """The reference optimum: {'objective', 'params'}."""
    p = build()
    return _oracle.along(p, _oracle.slider_crank_family(1.3, 0.3), 0.0501, 0.14999)
