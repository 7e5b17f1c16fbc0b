"""Offset slider-crank for TR 1.3 and stroke 0.3 m, smallest r2 + r3 with gamma_min >= 30 degrees.

Oracle: grid along the closed-form family; the gamma_min boundary located by brentq."""

import math

from problems import _oracle
from qropt import Problem

ORACLE = {"kind": "grid", "tolerance": 1e-07}


def build() -> Problem:
    return Problem(
        mechanism="SliderCrank",
        free={"r2": (0.05, 0.3), "r3": (0.1, 1.5), "e": (0.0, 0.6)},
        targets={"time_ratio": 1.3, "stroke": 0.3},
        conditions={"gamma_min": math.radians(30)},
        objective="min_size",
        name="slider_crank_size",
    )


def oracle() -> dict:
    """The reference optimum: {'objective', 'params'}."""
    p = build()
    design = _oracle.slider_crank_family(1.3, 0.3)

    def margin(r2):
        s = _oracle.score(p.replace(conditions={}), design(r2))
        return -1.0 if s is None else s[1]["gamma_min"] - math.radians(30)

    return _oracle.along(p, design, 0.0501, 0.14999, boundary=margin)
