"""Offset slider-crank: crank r2 about O2, rod r3 from A to the slider C on the line y = e."""

from __future__ import annotations

from qropt.mechanisms import closed_forms
from qropt.mechanisms.base import REQUIRED, Mechanism
from qropt.mechanisms.builder import Linkage
from qropt.mechanisms.hints import SynthesisHints
from qropt.mechanisms.values import Rule

LINKAGE = Linkage()
LINKAGE.ground("O2", (0, 0))
LINKAGE.crank("A", about="O2", length="r2")
LINKAGE.rrp("C", ("A", "r3"), line_y="e", sign="sigma_slider")
LINKAGE.output("C")


class SliderCrank(Mechanism):
    """Offset slider-crank (r2 crank, r3 rod, e slide-line offset); the slider is C."""

    KIND = "slider-crank"
    PARAMS = {"r2": REQUIRED, "r3": REQUIRED, "e": 0.0, "sigma_slider": 1.0}
    LENGTHS = ("r2", "r3")
    BODIES, GROUND, OUTPUT_JOINT = LINKAGE.bodies(), LINKAGE.ground_joints(), LINKAGE.output_joint()
    SYNTHESIS = SynthesisHints(one_reversal=True, closed_forms=(closed_forms.slider_crank_starts,))
    EXAMPLE = {"r2": 0.1352, "r3": 0.2499, "e": 0.0865, "sigma_slider": 1.0}

    @classmethod
    def rules(cls, xp, p, grashof=None):
        return [
            Rule("full rotation needs r3 >= r2 + |e|", p["r3"] - p["r2"] - p["e"]),
            Rule("full rotation needs r3 >= r2 + |e|", p["r3"] - p["r2"] + p["e"]),
        ]

    loop = staticmethod(LINKAGE.loop)
