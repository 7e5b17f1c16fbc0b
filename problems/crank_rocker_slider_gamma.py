"""Crank-rocker-driven slider (slide line through O2 and O4) for TR 1.2 and stroke 0.15 m; r1 = 0.3, r2 = 0.1,
r6 = 0.5 fixed; r3, r4, r5 free; best transmission angle.

Oracle: grid along r4 (r3 from the rocker's closed-form TR, r5 from the stroke, both by brentq), refined."""

from problems import _oracle
from qropt import Problem

ORACLE = {"kind": "grid", "tolerance": 1e-06}


def build() -> Problem:
    return Problem(
        mechanism="CrankRockerSlider",
        fixed={"r1": 0.3, "r2": 0.1, "r6": 0.5},
        free={"r3": (0.15, 0.6), "r4": (0.15, 0.45), "r5": (0.02, 0.45)},
        targets={"time_ratio": 1.2, "stroke": 0.15},
        objective="max_gamma_min",
        name="crank_rocker_slider_gamma",
    )


def oracle() -> dict:
    """The reference optimum: {'objective', 'params'}."""
    p = build()
    designs = [_oracle.crank_rocker_slider_family(1.2, 0.15, 0.3, 0.1, 0.5, k) for k in (0, 1)]
    runs = [_oracle.along(p, d, 0.15, 0.45, n=150) for d in designs]
    runs = [r for r in runs if r["objective"] is not None]
    pick = max if p.objective == "max_gamma_min" else min
    return pick(runs, key=lambda r: r["objective"])
