"""Whitworth: inverted slider-crank with r2 > r1; the slotted lever turns fully about O4 = (0, -r1)."""

from __future__ import annotations

from qropt.mechanisms import closed_forms
from qropt.mechanisms.base import REQUIRED, Mechanism
from qropt.mechanisms.crank_shaper import slotted_lever
from qropt.mechanisms.hints import SynthesisHints
from qropt.mechanisms.values import Rule

# the lever O4-A-C turns fully (length max(r5, r1 + r2)); the rod CD drives the ram D on y = -r1 + h
LINKAGE = slotted_lever("r5").rrp("D", ("C", "r6"), line_y="-r1 + h", sign="sigma_slider").output("D")


class Whitworth(Mechanism):
    """Whitworth (r1 centres, r2 crank, r5 = O4C, rod r6 to the slide line y = -r1 + h)."""

    KIND = "whitworth"
    PARAMS = {"r1": REQUIRED, "r2": REQUIRED, "r5": REQUIRED, "r6": REQUIRED, "h": 0.0, "sigma_slider": 1.0}
    LENGTHS = ("r1", "r2", "r5", "r6")
    BODIES, GROUND, OUTPUT_JOINT = LINKAGE.bodies(), LINKAGE.ground_joints(), LINKAGE.output_joint()
    SYNTHESIS = SynthesisHints(
        one_reversal=True,
        ties=("r1", "r2"),  # the motion depends on r1/r2 (the lever), r5, r6 and h only
        closed_forms=(closed_forms.whitworth_starts,),
    )
    EXAMPLE = {"r1": 0.0212, "r2": 0.0688, "r5": 0.15, "r6": 0.4, "h": 0.0, "sigma_slider": 1.0}

    @classmethod
    def rules(cls, xp, p, grashof=None):
        return [
            Rule("a Whitworth needs crank r2 > centres r1 (r2 < r1 is a crank-shaper)", p["r2"] - (1 + 1e-9) * p["r1"])
        ]

    loop = staticmethod(LINKAGE.loop)
