"""A type qropt does not ship, built from docs/extending.md alone: a Watt II six-bar quick-return. Two four-bars in
series drive a ram:

- the first, O2-A-B-O4 (O2 at the origin, O4 = (r1, 0)): crank r2, coupler r3, follower r4, a Grashof
  crank-rocker (the crank r2 shortest), branch ``sigma``;
- the follower O4-B carries a second arm O4-E of length r5 at the fixed angle ``alpha`` to O4-B (one rigid
  bell-crank), the input of the second four-bar O4-E-F-O6: coupler r6 from E to F, rocker r7 about the ground
  pivot O6 = (r1 + x6, y6) (offsets from O4), branch ``sigma2``;
- the rocker O6-F carries G on the ray O6->F at r8, and a rod r9 from G drives the ram D on the line y = h
  (branch ``sigma_slider``).

``qropt synth problems/user_watt_sixbar.py`` solves it; see docs/extending.md."""

from __future__ import annotations

import math

from qropt import Problem
from qropt.mechanisms import REQUIRED, Body, Loop, Mechanism, SynthesisHints, four_bar, grashof, grashof_rules
from qropt.mechanisms.closures import circle_circle, joint_lines, on_ray, rod_lines, rod_to_line


class WattSixBarShaper(Mechanism):
    """Watt II six-bar quick-return: a crank-rocker r1..r4, the bell-crank arm r5 at alpha, a second four-bar
    (r6 coupler, r7 rocker about O6 = (r1 + x6, y6)), G at r8 on the rocker and a rod r9 to the ram on y = h."""

    KIND = "watt-sixbar-shaper"
    PARAMS = {
        **{k: REQUIRED for k in ("r1", "r2", "r3", "r4", "r5", "r6", "r7", "r8", "r9", "x6", "y6", "h")},
        "alpha": 0.0,
        "sigma": -1.0,
        "sigma2": 1.0,
        "sigma_slider": 1.0,
    }
    LENGTHS = ("r1", "r2", "r3", "r4", "r5", "r6", "r7", "r8", "r9")
    ANGLES = ("alpha",)  # x6, y6 and h are offsets; sigma, sigma2 and sigma_slider branch signs
    FOUR_BAR = True  # the first four-bar's Grashof class is a condition of every problem
    CLASS = "crank-rocker"
    SYNTHESIS = SynthesisHints(
        exact_transmission={"B": (0.0, math.pi)},  # the first four-bar's coupler-follower extremes
        ruled_margins=("first four-bar closure at B",),  # the Grashof rules make it assemble
        accel_extremes=6,  # two four-bars add acceleration extremes of note
    )
    BODIES = (
        Body("crank", ("O2", "A"), "bar"),
        Body("coupler", ("A", "B"), "bar"),
        Body("bell-crank", ("O4", "B", "E"), "plate"),  # the follower and its arm at alpha: one rigid link
        Body("coupler 2", ("E", "F"), "bar"),
        Body("rocker", ("O6", "F", "G"), "bar"),  # along the ray O6->F, length max(r7, r8)
        Body("rod", ("G", "D"), "bar"),
        Body("ram", ("D",), "ram"),
    )
    GROUND = ("O2", "O4", "O6")
    OUTPUT_JOINT = "D"

    @classmethod
    def rules(cls, xp, p, grashof=None):
        """The first four-bar's Grashof class (the crank r2 shortest): it then assembles over the whole turn."""
        return grashof_rules(xp, p, grashof or cls.CLASS)

    def grashof(self):
        """The Grashof class of the first four-bar r1..r4 (a FOUR_BAR type has it: results report it)."""
        return grashof(*(self.params[k] for k in ("r1", "r2", "r3", "r4")))

    @staticmethod
    def loop(xp, theta2, p):
        a, o4, b, theta3, theta4, m1 = four_bar(xp, theta2, p)
        e = on_ray(xp, o4, theta4 + p["alpha"], p["r5"])
        o6 = (p["r1"] + p["x6"], p["y6"])
        f, theta7, m2 = circle_circle(xp, e, p["r6"], o6, p["r7"], p["sigma2"])
        g = on_ray(xp, o6, theta7, p["r8"])
        d, m3 = rod_to_line(xp, g, p["r9"], p["h"], p["sigma_slider"])
        return Loop(
            points={"O2": (0.0, 0.0), "A": a, "B": b, "O4": o4, "E": e, "F": f, "O6": o6, "G": g, "D": d},
            angles={
                "theta2": theta2,
                "theta3": theta3,
                "theta4": theta4,
                "theta6": xp.atan2(f[1] - e[1], f[0] - e[0]),
                "theta7": theta7,
                "theta9": xp.atan2(d[1] - g[1], d[0] - g[0]),
            },
            x=d[0],
            transmission={"B": joint_lines(a, o4, b), "F": joint_lines(e, o6, f), "D": rod_lines(g, d)},
            margins=[
                ("first four-bar closure at B", m1),
                ("second four-bar closure at F", m2),
                ("rod GD reaching the slide line", m3),
            ],
        )


NOMINAL = {
    "r1": 1.0,
    "r2": 0.3,
    "r3": 1.0,
    "r4": 0.8,
    "r5": 0.6,
    "r6": 1.0,
    "r7": 0.7,
    "r8": 0.7,
    "r9": 1.2,
    "x6": 0.2,
    "y6": 1.0,
    "h": 1.5,
    "alpha": math.radians(60.0),
}


def build() -> Problem:
    """TR 1.4 and a stroke of 0.5 m: the crank, coupler and second rocker free (the rest as NOMINAL), both branches
    of the second four-bar tried, the largest gamma_min over its three transmitting joints."""
    free = {"r2": (0.1, 0.6), "r3": (0.5, 1.6), "r7": (0.4, 1.2)}
    return Problem(
        mechanism=WattSixBarShaper,
        fixed={k: v for k, v in NOMINAL.items() if k not in free},
        free=free,
        targets={"time_ratio": 1.4, "stroke": 0.5},
        branches={"sigma2": (-1, 1)},
        objective="max_gamma_min",
        name="user_watt_sixbar",
    )
