"""Random synthesis tasks with closed-form answers, one generator per type.

Each returns (Problem, oracle params). Every oracle root is verified by the brute-force simulator
(tests/brute.py) before use; roots are closed forms, with a scalar brentq where the closed form gives
TR or stroke as a function of one length (crank-rocker types).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq

from qropt import Problem
from qropt.synthesis import analytic
from tests import brute

B = {"sigma": -1.0, "sigma_slider": 1.0}


def _tr(kind, p):
    t = brute.dead_centres(kind, p)
    return brute.time_ratio(t[0], t[1]), t[2] - t[3]


def _best(kind, cands):
    return max(cands, key=lambda p: brute.gamma_min(kind, p))


def crank_shaper(rng):
    r1, tr = rng.uniform(0.2, 1.0), rng.uniform(1.1, 3.0)
    s = rng.uniform(0.2, 2.0) * r1
    k = analytic.crank_shaper_ratio(tr)
    bounds = {"r2": (0.01 * r1, 0.99 * r1), "r4": (0.05 * r1, max(10 * r1, s / k))}
    prob = Problem(
        "CrankShaper", fixed={"r1": r1}, free=bounds, targets={"time_ratio": tr, "stroke": s}, objective=None
    )
    ans = {"r2": k * r1, "r4": s / (2 * k)}
    assert np.allclose(_tr("crank-shaper", {"r1": r1, **ans}), (tr, s), rtol=1e-10)
    return prob, ans


def whitworth(rng):
    r1, tr, s = rng.uniform(0.05, 0.3), rng.uniform(1.2, 3.0), rng.uniform(0.1, 1.0)
    prob = Problem(
        "Whitworth",
        fixed={"r1": r1, "r6": 1.5 * s},
        free={"r2": (1.01 * r1, 20 * r1), "r5": (0.01, s)},
        targets={"time_ratio": tr, "stroke": s},
        objective=None,
    )
    ans = {"r2": r1 / analytic.whitworth_ratio(tr), "r5": s / 2}
    p = {"r1": r1, "r6": 1.5 * s, "h": 0.0, "sigma_slider": 1.0, **ans}
    assert np.allclose(_tr("whitworth", p), (tr, s), rtol=1e-10)
    return prob, ans


def slider_crank(rng):
    r2, tr = rng.uniform(0.05, 0.3), rng.uniform(1.05, 1.6)
    s = r2 * rng.uniform(2.05, 3.5)
    d = analytic.slider_crank_design(tr, s, r2)[0]
    bounds = {"r3": (1.001 * r2, max(20 * r2, 2 * d.r3)), "e": (0.0, max(10 * r2, 2 * d.e))}
    prob = Problem(
        "SliderCrank", fixed={"r2": r2}, free=bounds, targets={"time_ratio": tr, "stroke": s}, objective=None
    )
    assert np.allclose(_tr("slider-crank", {"r2": r2, "r3": d.r3, "e": d.e, "sigma_slider": 1.0}), (tr, s), rtol=1e-10)
    return prob, {"r3": d.r3, "e": d.e}


def drag_link(rng):
    while True:
        r1, r2, r4, r6 = 0.1, rng.uniform(0.15, 0.3), rng.uniform(0.15, 0.35), 0.4
        tr, s = rng.uniform(1.3, 2.5), rng.uniform(0.1, 0.3)
        cands = []
        for sol in analytic.drag_link_r3(tr, r1, r2, r4):
            p = {"r1": r1, "r2": r2, "r3": sol.r3, "r4": r4, "r5": s / 2, "r6": r6, "h": 0.0, **B}
            v = sorted([r1, r2, sol.r3, r4])
            if v[0] == r1 and v[0] + v[3] < v[1] + v[2] and np.allclose(_tr("drag-link-slider", p), (tr, s)):
                cands.append(p)
        if cands:
            break
    prob = Problem(
        "DragLinkSlider",
        fixed={"r1": r1, "r2": r2, "r4": r4, "r6": r6},
        free={"r3": (0.05, 1.0), "r5": (0.01, 0.3)},
        targets={"time_ratio": tr, "stroke": s},
    )
    best = _best("drag-link-slider", cands)
    return prob, {"r3": best["r3"], "r5": best["r5"]}


def _crank_rocker_r3_roots(tr, r1, r2, r4):
    """r3 in the crank-rocker interval with the rocker's TR (closed form) equal to tr, by scan + brentq."""
    lo, hi = max(r2, r4 - r1 + r2, r1 - r4 + r2) * (1 + 1e-9), (r1 + r4 - r2) * (1 - 1e-9)

    def f(r3):
        return analytic.crank_rocker_extremes(r1, r2, r3, r4).time_ratio - tr

    grid = np.linspace(lo, hi, 801)
    vals = np.array([f(x) for x in grid])
    return [
        brentq(f, grid[i], grid[i + 1], xtol=1e-15) for i in np.flatnonzero(np.sign(vals[:-1]) != np.sign(vals[1:]))
    ]


def four_bar(rng):
    while True:
        r1, r2, r4 = 1.0, rng.uniform(0.1, 0.4), rng.uniform(0.6, 1.4)
        tr = rng.uniform(1.05, 1.5)
        cands = [
            {"r1": r1, "r2": r2, "r3": r3, "r4": r4, "sigma": -1.0} for r3 in _crank_rocker_r3_roots(tr, r1, r2, r4)
        ]
        cands = [p for p in cands if abs(_tr("four-bar", p)[0] - tr) < 1e-9]
        if cands:
            break
    prob = Problem(
        "FourBar",
        fixed={"r1": r1, "r2": r2, "r4": r4},
        free={"r3": (0.02, 2.5)},
        targets={"time_ratio": tr},
        objective="max_gamma_min",
    )
    return prob, {"r3": _best("four-bar", cands)["r3"]}


def _rocker_stroke(r1, r5, r6, e):
    """Slider travel between the rocker limits (slide line y = 0 through O2 and O4)."""

    def slider_x(t4):
        return r1 + r5 * math.cos(t4) + math.sqrt(r6**2 - (r5 * math.sin(t4)) ** 2)

    return abs(slider_x(e.theta4_extended) - slider_x(e.theta4_folded))


def crank_rocker_slider(rng):
    while True:
        r1, r2, r4, r6 = 0.3, rng.uniform(0.05, 0.12), rng.uniform(0.2, 0.4), 0.5
        tr, s = rng.uniform(1.05, 1.4), rng.uniform(0.05, 0.15)
        cands = []
        for r3 in _crank_rocker_r3_roots(tr, r1, r2, r4):
            e = analytic.crank_rocker_extremes(r1, r2, r3, r4)

            def stroke(r5, e=e, r1=r1, r6=r6, s=s):
                return _rocker_stroke(r1, r5, r6, e) - s

            grid = np.linspace(0.01, 0.45, 441)
            vals = np.array([stroke(x) for x in grid])
            for i in np.flatnonzero(np.sign(vals[:-1]) != np.sign(vals[1:])):
                r5 = brentq(stroke, grid[i], grid[i + 1], xtol=1e-15)
                p = {"r1": r1, "r2": r2, "r3": r3, "r4": r4, "r5": r5, "r6": r6, "h": 0.0, **B}
                if np.allclose(_tr("crank-rocker-slider", p), (tr, s), rtol=1e-9):
                    cands.append(p)
        if cands:
            break
    prob = Problem(
        "CrankRockerSlider",
        fixed={"r1": r1, "r2": r2, "r4": r4, "r6": r6},
        free={"r3": (0.05, 0.8), "r5": (0.01, 0.45)},
        targets={"time_ratio": tr, "stroke": s},
    )
    best = _best("crank-rocker-slider", cands)
    return prob, {"r3": best["r3"], "r5": best["r5"]}


TASKS = {
    "slider-crank": slider_crank,
    "crank-shaper": crank_shaper,
    "whitworth": whitworth,
    "crank-rocker-slider": crank_rocker_slider,
    "drag-link-slider": drag_link,
    "four-bar": four_bar,
}
