"""A type of one's own, defined in this file: the bent-lever shaper. An inverted slider-crank (crank r2 about O2,
its pin A sliding in a slotted lever that swings about O4 = (0, -r1), r2 < r1) whose ram is driven by a rod r6
from a point C of the lever that sits at r4 from O4 at a fixed angle ``beta`` to the slot (an angle parameter:
the slot and the arm are one rigid bent lever). The rod's end D slides on the line y = -r1 + h.

``qropt synth problems/user_slotted_lever.py`` solves it; see docs/extending.md."""

from __future__ import annotations

import math

from qropt import Problem
from qropt.mechanisms import REQUIRED, Body, Loop, Mechanism, Rule
from qropt.mechanisms.closures import RIGHT_ANGLE, on_ray, pin_in_slot, rod_lines, rod_to_line


class BentLeverShaper(Mechanism):
    """Bent-lever shaper: r1 centres, r2 crank, r4 arm O4C at beta (rad) to the slot, rod r6 to y = -r1 + h."""

    KIND = "bent-lever-shaper"
    PARAMS = {
        "r1": REQUIRED,
        "r2": REQUIRED,
        "r4": REQUIRED,
        "r6": REQUIRED,
        "h": REQUIRED,
        "beta": 0.0,
        "sigma_slider": 1.0,
    }
    LENGTHS = ("r1", "r2", "r4", "r6")
    ANGLES = ("beta",)
    BODIES = (
        Body("crank", ("O2", "A"), "bar"),
        Body("block", ("A", "O4"), "block"),  # the crank-pin block in the lever's slot
        Body("lever", ("O4", "A"), "slot-lever"),  # the slotted part of the bent lever
        Body("arm", ("O4", "C"), "bar"),  # its arm at beta to the slot
        Body("rod", ("C", "D"), "bar"),
        Body("ram", ("D",), "ram"),
    )
    GROUND = ("O2", "O4")
    OUTPUT_JOINT = "D"

    @classmethod
    def rules(cls, xp, p, grashof=None):
        return [Rule("the lever swings (it does not turn) where crank r2 < centres r1", (1 - 1e-9) * p["r1"] - p["r2"])]

    @staticmethod
    def loop(xp, theta2, p):
        o4 = (0.0, -p["r1"])
        a = (p["r2"] * xp.cos(theta2), p["r2"] * xp.sin(theta2))
        theta4 = pin_in_slot(xp, o4, a)
        c = on_ray(xp, o4, theta4 + p["beta"], p["r4"])
        d, margin = rod_to_line(xp, c, p["r6"], -p["r1"] + p["h"], p["sigma_slider"])
        return Loop(
            points={"O2": (0.0, 0.0), "A": a, "O4": o4, "C": c, "D": d},
            angles={"theta2": theta2, "theta4": theta4, "theta6": xp.atan2(d[1] - c[1], d[0] - c[0])},
            x=d[0],
            transmission={"A": RIGHT_ANGLE, "D": rod_lines(c, d)},
            margins=[("rod CD reaching the slide line", margin)],
        )


def build() -> Problem:
    """TR 1.6 and a stroke of 0.3 m with the arm bent 15 degrees off the slot: the largest gamma_min."""
    return Problem(
        mechanism=BentLeverShaper,
        fixed={"beta": math.radians(15.0)},
        free={"r1": (0.05, 1.5), "r2": (0.015, 1.5), "r4": (0.05, 1.5), "r6": (0.05, 1.5), "h": (-1.5, 1.5)},
        targets={"time_ratio": 1.6, "stroke": 0.3},
        objective="max_gamma_min",
        name="user_slotted_lever",
    )
