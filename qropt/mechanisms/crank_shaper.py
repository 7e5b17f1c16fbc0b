"""Crank-shaper: inverted slider-crank with r2 < r1; the slotted lever swings about O4 = (0, -r1)."""

from __future__ import annotations

from qropt.errors import InvalidParameter
from qropt.mechanisms import closed_forms
from qropt.mechanisms.base import REQUIRED, Mechanism
from qropt.mechanisms.builder import Linkage
from qropt.mechanisms.hints import SynthesisHints
from qropt.mechanisms.values import Rule


def slotted_lever(lever: str | None) -> Linkage:
    """Crank r2 about O2, the crank-pin block in the lever's slot about O4 = (0, -r1) (theta4), and C on the lever
    at ``lever`` from O4 (none without ``lever``): the crank-shaper's, Whitworth's and slot-ram shaper's frame."""
    L = Linkage()
    L.ground("O2", (0, 0))
    L.crank("A", about="O2", length="r2")
    L.ground("O4", (0, "-r1"))
    L.rpr("A", pivot="O4", angle="theta4")
    if lever is not None:
        L.on_ray("C", "O4", "A", lever)
    return L


YOKE = slotted_lever("r4").rpp("C").output("C")  # without a rod r6: the yoke-ram follows x_C
ROD = slotted_lever("r4").rrp("D", ("C", "r6"), line_y="-r1 + h", sign="sigma_slider").output("D")  # with r6


class CrankShaper(Mechanism):
    """Crank-shaper (r1 centres, r2 crank, r4 lever O4C; optional rod r6 to a slide line y = -r1 + h).

    Without r6 the ram is driven by a yoke and x = x_C (the lab rig of seed 001).
    """

    KIND = "crank-shaper"
    PARAMS = {"r1": REQUIRED, "r2": REQUIRED, "r4": REQUIRED, "r6": None, "h": None, "sigma_slider": 1.0}
    LENGTHS = ("r1", "r2", "r4", "r6")
    BODIES = YOKE.bodies()  # with the yoke (no rod r6): the yoke-ram moves along x with x_C
    ROD_BODIES = ROD.bodies()  # with a rod r6
    GROUND = YOKE.ground_joints()
    OUTPUT_JOINT = YOKE.output_joint()
    OPTIONS = {"rod": ("r6", "h")}
    SYNTHESIS = SynthesisHints(
        one_reversal=True,
        ties=("r1", "r2"),  # the motion depends on r2/r1 (the lever), r4, r6 and h only
        closed_forms=(closed_forms.crank_shaper_starts,),
    )
    EXAMPLE = {"r1": 0.2178, "r2": 0.0673, "r4": 0.4854, "sigma_slider": 1.0}

    def bodies(self):
        """BODIES with the yoke; ROD_BODIES with a rod r6."""
        return self.ROD_BODIES if "r6" in self.params else self.BODIES

    def output_joint(self):
        """C (the yoke-ram follows x_C) without a rod; D with a rod r6."""
        return ROD.output_joint() if "r6" in self.params else YOKE.output_joint()

    @classmethod
    def completed(cls, params):
        """With a rod r6 the slide line defaults to h = 0 (through O4)."""
        return {"h": 0.0} if "r6" in params and "h" not in params else {}

    @classmethod
    def rules(cls, xp, p, grashof=None):
        return [
            Rule("a crank-shaper needs crank r2 < centres r1 (r2 > r1 is a Whitworth)", (1 - 1e-9) * p["r1"] - p["r2"])
        ]

    def validate(self):
        super().validate()
        p = self.params
        if "h" in p and "r6" not in p:
            raise InvalidParameter("CrankShaper: h (slide-line height) needs the rod length r6")
        if "r6" in p and "h" not in p:
            object.__setattr__(self, "params", {**p, "h": 0.0})  # frozen by Mechanism.__init__

    @classmethod
    def linkage(cls, params):
        return ROD if "r6" in params else YOKE

    @staticmethod
    def loop(xp, theta2, p):
        """The yoke's loop without a rod r6, the rod's with one (a choice on the keys of p, never on values)."""
        return (ROD if "r6" in p else YOKE).loop(xp, theta2, p)
