"""Crank-shaper: inverted slider-crank with r2 < r1; the slotted lever swings about O4 = (0, -r1)."""

from __future__ import annotations

from qropt.errors import InvalidParameter
from qropt.kinematics.closures import RIGHT_ANGLE, on_ray, pin_in_slot, rod_lines, rod_to_line
from qropt.mechanisms.base import REQUIRED, Body, Loop, Mechanism, Rule


class CrankShaper(Mechanism):
    """Crank-shaper (r1 centres, r2 crank, r4 lever O4C; optional rod r6 to a slide line y = -r1 + h).

    Without r6 the ram is driven by a yoke and x = x_C (the lab rig of seed 001).
    """

    KIND = "crank-shaper"
    PARAMS = {"r1": REQUIRED, "r2": REQUIRED, "r4": REQUIRED, "r6": None, "h": None, "sigma_slider": 1.0}
    LENGTHS = ("r1", "r2", "r4", "r6")
    BODIES = (  # with the yoke (no rod r6): the yoke-ram moves along x with x_C
        Body("crank", ("O2", "A"), "bar"),
        Body("block", ("A", "O4"), "block"),  # the crank-pin block in the lever's slot
        Body("lever", ("O4", "A", "C"), "slot-lever"),  # length max(r4, r1 + r2)
        Body("yoke", ("C",), "yoke"),
    )
    ROD_BODIES = (*BODIES[:3], Body("rod", ("C", "D"), "bar"), Body("ram", ("D",), "ram"))  # with a rod r6
    GROUND = ("O2", "O4")
    OUTPUT_JOINT = "C"

    def bodies(self):
        """BODIES with the yoke; ROD_BODIES with a rod r6."""
        return self.ROD_BODIES if "r6" in self.params else self.BODIES

    def output_joint(self):
        """C (the yoke-ram follows x_C) without a rod; D with a rod r6."""
        return "D" if "r6" in self.params else "C"

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

    @staticmethod
    def loop(xp, theta2, p):
        o4 = (0.0, -p["r1"])
        a = (p["r2"] * xp.cos(theta2), p["r2"] * xp.sin(theta2))
        theta4 = pin_in_slot(xp, o4, a)
        c = on_ray(xp, o4, theta4, p["r4"])
        points = {"O2": (0.0, 0.0), "A": a, "O4": o4, "C": c}
        angles = {"theta2": theta2, "theta4": theta4}
        if "r6" not in p:
            return Loop(points, angles, c[0], {"A": RIGHT_ANGLE, "C": RIGHT_ANGLE}, [])
        d, m = rod_to_line(xp, c, p["r6"], -p["r1"] + p["h"], p["sigma_slider"])
        points["D"] = d
        angles["theta6"] = xp.atan2(d[1] - c[1], d[0] - c[0])
        trans = {"A": RIGHT_ANGLE, "D": rod_lines(c, d)}
        return Loop(points, angles, d[0], trans, [("rod CD reaching the slide line", m)])
