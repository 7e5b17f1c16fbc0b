"""Hard: the paper's task with both four-bar assembly branches (sigma = -1 and +1) enumerated: four local
optima in two mirror pairs.

Oracle: closed form, eqs. (7)-(13) (the branch mirrors give the same lengths and gamma_min)."""

from problems import _oracle
from qropt import Problem

ORACLE = {"kind": "closed form", "tolerance": 1e-08}


def build() -> Problem:
    return Problem(
        mechanism="DragLinkSlider",
        fixed={"r1": 0.1, "r2": 0.225, "r4": 0.275, "r6": 0.3},
        free={"r3": (0.05, 1.0), "r5": (0.01, 0.5)},
        targets={"time_ratio": 1.5, "stroke": 0.3},
        objective="max_gamma_min",
        branches={"sigma": (-1, 1)},
        name="drag_link_both_branches",
    )


def oracle() -> dict:
    """The reference optimum: {'objective', 'params'}."""
    p = build()
    return _oracle.best_of(p, _oracle.drag_link(p, 0.1, 0.225, 0.275, 0.3))
