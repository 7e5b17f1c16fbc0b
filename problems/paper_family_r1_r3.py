"""The paper's discussion issue (3): how many drag-link designs give TR 1.5 when both the base length
r1 and the coupler r3 may change (r2 = 0.225, r4 = 0.275, r5 = 0.15, r6 = 0.3 m fixed)?

A single order of infinity: one curve in (r1, r3). Oracle: eq. (12) solved at each r1 (closed form);
its fold is where A^2 + B^2 - C^2 vanishes.
"""

from qropt import Problem


def build() -> Problem:
    return Problem(
        mechanism="DragLinkSlider",
        fixed={"r2": 0.225, "r4": 0.275, "r5": 0.15, "r6": 0.3},
        free={"r1": (0.02, 0.2), "r3": (0.05, 0.6)},
        targets={"time_ratio": 1.5},
        conditions={"grashof": "drag-link"},
        objective="max_gamma_min",
        name="paper_family_r1_r3",
    )
