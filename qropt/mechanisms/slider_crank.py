"""Offset slider-crank: crank r2 about O2, rod r3 from A to the slider C on the line y = e."""

from __future__ import annotations

from qropt.kinematics.closures import rod_lines, rod_to_line
from qropt.mechanisms.base import REQUIRED, Body, Loop, Mechanism, Rule


class SliderCrank(Mechanism):
    """Offset slider-crank (r2 crank, r3 rod, e slide-line offset); the slider is C."""

    KIND = "slider-crank"
    PARAMS = {"r2": REQUIRED, "r3": REQUIRED, "e": 0.0, "sigma_slider": 1.0}
    LENGTHS = ("r2", "r3")
    BODIES = (Body("crank", ("O2", "A"), "bar"), Body("rod", ("A", "C"), "bar"), Body("ram", ("C",), "ram"))
    GROUND = ("O2",)
    OUTPUT_JOINT = "C"

    @classmethod
    def rules(cls, xp, p, grashof=None):
        return [
            Rule("full rotation needs r3 >= r2 + |e|", p["r3"] - p["r2"] - p["e"]),
            Rule("full rotation needs r3 >= r2 + |e|", p["r3"] - p["r2"] + p["e"]),
        ]

    @staticmethod
    def loop(xp, theta2, p):
        a = (p["r2"] * xp.cos(theta2), p["r2"] * xp.sin(theta2))
        c, m = rod_to_line(xp, a, p["r3"], p["e"], p["sigma_slider"])
        return Loop(
            points={"O2": (0.0, 0.0), "A": a, "C": c},
            angles={"theta2": theta2, "theta3": xp.atan2(c[1] - a[1], c[0] - a[0])},
            x=c[0],
            transmission={"C": rod_lines(a, c)},
            margins=[("rod AC reaching the slide line", m)],
        )
