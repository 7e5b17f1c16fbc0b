"""Offset slider-crank for TR 1.3 and stroke 0.3 m with the best transmission angle (r2, r3, e free).

Oracle: the closed-form family ``analytic.slider_crank_design`` swept densely over r2 (reference
computed at test time).
"""

from qropt import Problem


def build() -> Problem:
    return Problem(
        mechanism="SliderCrank",
        free={"r2": (0.05, 0.3), "r3": (0.1, 1.5), "e": (0.0, 0.6)},
        targets={"time_ratio": 1.3, "stroke": 0.3},
        objective="max_gamma_min",
        name="slider_crank_gamma",
    )
