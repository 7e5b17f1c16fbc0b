"""Whitworth: inverted slider-crank with r2 > r1; the slotted lever turns fully about O4 = (0, -r1)."""

from __future__ import annotations

from qropt.kinematics.closures import RIGHT_ANGLE, on_ray, pin_in_slot, rod_lines, rod_to_line
from qropt.mechanisms.base import REQUIRED, Body, Loop, Mechanism, Rule


class Whitworth(Mechanism):
    """Whitworth (r1 centres, r2 crank, r5 = O4C, rod r6 to the slide line y = -r1 + h)."""

    KIND = "whitworth"
    PARAMS = {"r1": REQUIRED, "r2": REQUIRED, "r5": REQUIRED, "r6": REQUIRED, "h": 0.0, "sigma_slider": 1.0}
    LENGTHS = ("r1", "r2", "r5", "r6")
    BODIES = (
        Body("crank", ("O2", "A"), "bar"),
        Body("block", ("A", "O4"), "block"),  # the crank-pin block in the lever's slot
        Body("lever", ("O4", "A", "C"), "slot-lever"),  # length max(r5, r1 + r2)
        Body("rod", ("C", "D"), "bar"),
        Body("ram", ("D",), "ram"),
    )
    GROUND = ("O2", "O4")
    OUTPUT_JOINT = "D"

    @classmethod
    def rules(cls, xp, p, grashof=None):
        return [
            Rule("a Whitworth needs crank r2 > centres r1 (r2 < r1 is a crank-shaper)", p["r2"] - (1 + 1e-9) * p["r1"])
        ]

    @staticmethod
    def loop(xp, theta2, p):
        o4 = (0.0, -p["r1"])
        a = (p["r2"] * xp.cos(theta2), p["r2"] * xp.sin(theta2))
        theta4 = pin_in_slot(xp, o4, a)
        c = on_ray(xp, o4, theta4, p["r5"])
        d, m = rod_to_line(xp, c, p["r6"], -p["r1"] + p["h"], p["sigma_slider"])
        return Loop(
            points={"O2": (0.0, 0.0), "A": a, "O4": o4, "C": c, "D": d},
            angles={"theta2": theta2, "theta4": theta4, "theta6": xp.atan2(d[1] - c[1], d[0] - c[0])},
            x=d[0],
            transmission={"A": RIGHT_ANGLE, "D": rod_lines(c, d)},
            margins=[("rod CD reaching the slide line", m)],
        )
