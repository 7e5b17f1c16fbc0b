"""The offset slider-crank design chart: stroke 1; the minimum transmission angle, rod r3 and offset e over time
ratio x crank ratio r2 (the crank radius per unit stroke), with the best crank ratio of each time ratio.

Chart: ``qropt chart problems/chart_slider_crank.py`` (default axes X and Y). Oracle at any cell: the stroke
triangle (``analytic.slider_crank_design``) gives the one design with e > 0; over r2 it is the closed-form
family that holds every design of the time ratio and stroke."""

from qropt import Problem

X = ("time_ratio", tuple(1.05 + 0.05 * k for k in range(20)))
Y = ("r2", tuple(0.2 + 0.02 * k for k in range(15)))


def build():
    return Problem(
        mechanism="SliderCrank",
        fixed={"r2": 0.3},
        free={"r3": (0.2, 20.0), "e": (0.0, 10.0)},
        targets={"time_ratio": 1.5, "stroke": 1.0},
        objective="max_gamma_min",
        name="chart_slider_crank",
    )
