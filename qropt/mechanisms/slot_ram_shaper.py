"""Slot-ram shaper: the crank-shaper's slotted lever drives the ram's pin D directly, D riding in the lever's slot
and on the slide line y = -r1 + h (no rod)."""

from __future__ import annotations

from qropt.mechanisms import closed_forms
from qropt.mechanisms.base import REQUIRED, Mechanism
from qropt.mechanisms.crank_shaper import slotted_lever
from qropt.mechanisms.hints import SynthesisHints
from qropt.mechanisms.values import Rule

# D rides in the lever's slot O4->A (lever length max(r1 + r2, h r1 / sqrt(r1^2 - r2^2))) and on y = -r1 + h; it is
# on the ray (t > 0) wherever the rules hold
LINKAGE = slotted_lever(None).slot_line("D", ("O4", "A"), line_y="-r1 + h").output("D")


class SlotRamShaper(Mechanism):
    """Slot-ram shaper (r1 centres, r2 < r1 crank, h > 0 the slide line's height above O4 = (0, -r1)).

    The ram's pin D is where the lever's line O4->A crosses the slide line; the output is x_D. Closed forms
    (``qropt.mechanisms.closed_forms``): TR = (pi + 2 asin(r2/r1)) / (pi - 2 asin(r2/r1)),
    stroke = 2 h r2 / sqrt(r1^2 - r2^2), gamma_min = acos(r2/r1) (at D, with the lever at its extremes)."""

    KIND = "slot-ram-shaper"
    PARAMS = {"r1": REQUIRED, "r2": REQUIRED, "h": REQUIRED}
    LENGTHS = ("r1", "r2")  # h is the slide line's offset (positive by a rule), as the crank-shaper's
    BODIES, GROUND, OUTPUT_JOINT = LINKAGE.bodies(), LINKAGE.ground_joints(), LINKAGE.output_joint()
    SYNTHESIS = SynthesisHints(
        one_reversal=True,
        ties=("r1", "r2"),  # the motion depends on r2/r1 and h only
        closed_forms=(closed_forms.slot_ram_shaper_starts,),
    )
    EXAMPLE = {"r1": 0.2073, "r2": 0.0641, "h": 0.4617}

    @classmethod
    def rules(cls, xp, p, grashof=None):
        return [
            Rule("a slot-ram shaper needs crank r2 < centres r1", (1 - 1e-9) * p["r1"] - p["r2"]),
            Rule("a slot-ram shaper needs the slide line above O4: h > 0", p["h"] - 1e-9 * p["r1"]),
        ]

    loop = staticmethod(LINKAGE.loop)


__all__ = ["SlotRamShaper"]
