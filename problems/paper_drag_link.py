"""The paper's design task (1): a new coupler r3 and pin location r5 for TR 1.5 and stroke 0.3 m,
keeping r1 = 0.1, r2 = 0.225, r4 = 0.275, r6 = 0.3 m; drag-link; best minimum transmission angle.

Oracle: closed form, eqs. (7)-(13): r3 = 0.2504281 m (gamma_min 27.008 deg) or 0.1543445 m
(9.095 deg), r5 = 0.15 m.
"""

from qropt import Problem, analytic


def build() -> Problem:
    return Problem(
        mechanism="DragLinkSlider",
        fixed={"r1": 0.1, "r2": 0.225, "r4": 0.275, "r6": 0.3},
        free={"r3": (0.05, 1.0), "r5": (0.01, 0.5)},
        targets={"time_ratio": 1.5, "stroke": 0.3},
        conditions={"grashof": "drag-link"},
        objective="max_gamma_min",
        name="paper_drag_link",
    )


def oracle() -> dict:
    """Every solution (closed form): r3, r5."""
    return {"solutions": [{"r3": s.r3, "r5": 0.15} for s in analytic.drag_link_r3(1.5, 0.1, 0.225, 0.275)]}
