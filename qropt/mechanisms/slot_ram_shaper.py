"""Slot-ram shaper: the crank-shaper's slotted lever drives the ram's pin D directly, D riding in the lever's slot
and on the slide line y = -r1 + h (no rod)."""

from __future__ import annotations

from qropt.kinematics.closures import RIGHT_ANGLE, pin_in_slot, slot_line_lines, slot_to_line
from qropt.mechanisms.base import REQUIRED, Body, Loop, Mechanism, Rule


class SlotRamShaper(Mechanism):
    """Slot-ram shaper (r1 centres, r2 < r1 crank, h > 0 the slide line's height above O4 = (0, -r1)).

    The ram's pin D is where the lever's line O4->A crosses the slide line; the output is x_D. Closed forms
    (``qropt.synthesis.analytic``): TR = (pi + 2 asin(r2/r1)) / (pi - 2 asin(r2/r1)),
    stroke = 2 h r2 / sqrt(r1^2 - r2^2), gamma_min = acos(r2/r1) (at D, with the lever at its extremes)."""

    KIND = "slot-ram-shaper"
    PARAMS = {"r1": REQUIRED, "r2": REQUIRED, "h": REQUIRED}
    LENGTHS = ("r1", "r2")  # h is the slide line's offset (positive by a rule), as the crank-shaper's
    BODIES = (
        Body("crank", ("O2", "A"), "bar"),
        Body("block", ("A", "O4"), "block"),  # the crank-pin block in the lever's slot
        Body("lever", ("O4", "A", "D"), "slot-lever"),  # length max(r1 + r2, h r1 / sqrt(r1^2 - r2^2))
        Body("ram", ("D",), "ram"),
    )
    GROUND = ("O2", "O4")
    OUTPUT_JOINT = "D"

    @classmethod
    def rules(cls, xp, p, grashof=None):
        return [
            Rule("a slot-ram shaper needs crank r2 < centres r1", (1 - 1e-9) * p["r1"] - p["r2"]),
            Rule("a slot-ram shaper needs the slide line above O4: h > 0", p["h"] - 1e-9 * p["r1"]),
        ]

    @staticmethod
    def loop(xp, theta2, p):
        o4 = (0.0, -p["r1"])
        a = (p["r2"] * xp.cos(theta2), p["r2"] * xp.sin(theta2))
        theta4 = pin_in_slot(xp, o4, a)
        d, _ = slot_to_line(xp, o4, a, -p["r1"] + p["h"])  # on the ray (t > 0) wherever the rules hold
        return Loop(
            points={"O2": (0.0, 0.0), "A": a, "O4": o4, "D": d},
            angles={"theta2": theta2, "theta4": theta4},
            x=d[0],
            transmission={"A": RIGHT_ANGLE, "D": slot_line_lines(o4, a)},
            margins=[],
        )


__all__ = ["SlotRamShaper"]
