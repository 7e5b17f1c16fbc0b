"""Crank-rocker-driven slider with a raised slide line (h = 0.05 m): no closed form exists.
TR 1.4, stroke 0.2 m, r1 = 0.3, r2 = 0.1, r6 = 0.4 m fixed; r3, r4, r5 free; best gamma_min.

Oracle: none in closed form; reference computed at test time by a dense grid search.
"""

from qropt import Problem


def build() -> Problem:
    return Problem(
        mechanism="CrankRockerSlider",
        fixed={"r1": 0.3, "r2": 0.1, "r6": 0.4, "h": 0.05},
        free={"r3": (0.15, 0.6), "r4": (0.12, 0.5), "r5": (0.05, 0.4)},
        targets={"time_ratio": 1.4, "stroke": 0.2},
        objective="max_gamma_min",
        name="crank_rocker_slider_gamma",
    )
