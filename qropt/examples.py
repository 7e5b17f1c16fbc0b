"""The built-in example: the paper's drag-link project (Podhorodeski, Nokleby and Wittchen)."""

from __future__ import annotations

from qropt.mechanisms import DragLinkSlider
from qropt.synthesis.problem import Problem


def paper_mechanism() -> DragLinkSlider:
    """The paper's design: TR 1.5, stroke 0.3 m, r3 from eqs. (7)-(13) (the root with the larger gamma_min); the
    drag-link slider's example design (``DragLinkSlider.EXAMPLE``)."""
    return DragLinkSlider(**DragLinkSlider.EXAMPLE)


def paper_problem() -> Problem:
    """The paper's design task (1): new coupler r3 and pin location r5 for TR 1.5 and stroke 0.3 m,
    keeping r1 = 0.1, r2 = 0.225, r4 = 0.275, r6 = 0.3 m; drag-link; best minimum transmission angle."""
    return Problem(
        mechanism="DragLinkSlider",
        fixed={"r1": 0.1, "r2": 0.225, "r4": 0.275, "r6": 0.3},
        free={"r3": (0.05, 1.0), "r5": (0.01, 0.5)},
        targets={"time_ratio": 1.5, "stroke": 0.3},
        conditions={"grashof": "drag-link"},
        objective="max_gamma_min",
        name="paper_drag_link",
    )
