"""Hard: the paper's linkage pushed to TR 3.4, near the largest reachable 3.538, where the coupler approaches
the change point r3 = 0.4 and the transmission angle collapses.

Oracle: closed form, eqs. (7)-(13)."""

from problems import _oracle
from qropt import Problem

ORACLE = {"kind": "closed form", "tolerance": 1e-08}


def build() -> Problem:
    return Problem(
        mechanism="DragLinkSlider",
        fixed={"r1": 0.1, "r2": 0.225, "r4": 0.275, "r6": 0.3},
        free={"r3": (0.05, 1.0), "r5": (0.01, 0.5)},
        targets={"time_ratio": 3.4, "stroke": 0.3},
        objective="max_gamma_min",
        name="drag_link_near_change_point",
    )


def oracle() -> dict:
    """The reference optimum: {'objective', 'params'}."""
    p = build()
    return _oracle.best_of(p, _oracle.drag_link(p, 0.1, 0.225, 0.275, 0.3))
