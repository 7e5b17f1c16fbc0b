"""Coupler-driven slider (Stephenson III six-bar): a coupler point P of the four-bar O2-A-B-O4 drives the ram D
through the rod PD on the slide line y = h."""

from __future__ import annotations

from qropt.errors import GrashofError
from qropt.kinematics.closures import joint_lines, rod_lines, rod_to_line
from qropt.mechanisms.base import REQUIRED, Body, Loop
from qropt.mechanisms.four_bar import SHORTEST, _FourBarBase, four_bar, grashof_rules


class CouplerSlider(_FourBarBase):
    """Four-bar r1 ground (O4 = (r1, 0)), r2 crank, r3 coupler AB, r4 follower O4B (branch sigma); the coupler point
    P at r5 from A, beta (rad, counter-clockwise from A->B, any sign) off the coupler; the rod r6 from P to the ram D
    on y = h (``sigma_slider = +1``: D on the +x side of P). Here r5 and r6 name AP and PD.

    The four-bar's Grashof class is a crank-rocker or a drag-link (a problem's 'grashof' condition chooses); a
    design whose ram reverses more than once a turn has no time ratio (``dead_centres().reversals > 1``)."""

    KIND = "coupler-slider"
    PARAMS = {
        **{k: REQUIRED for k in ("r1", "r2", "r3", "r4", "r5")},
        "beta": REQUIRED,
        "r6": REQUIRED,
        "h": 0.0,
        "sigma": -1.0,
        "sigma_slider": 1.0,
    }
    LENGTHS = ("r1", "r2", "r3", "r4", "r5", "r6")  # beta is an angle and h an offset: neither is a length
    ANGLES = ("beta",)  # rad: not scaled with the lengths (Mechanism.kinds(), where the base has it)
    CLASS = ""  # crank-rocker or drag-link: the problem's 'grashof' condition (default crank-rocker)
    # B's coupler-follower angle depends on |O4A| only, extreme with the crank along the ground line: as the four-bar
    # sliders (EXACT_TRANSMISSION), and the Grashof rules make the four-bar assemble (RULED_MARGINS), both inherited.
    ACCEL_EXTREMES = 6  # a coupler point's path adds acceleration extremes beyond the four-bar sliders' four
    BODIES = (
        Body("crank", ("O2", "A"), "bar"),
        Body("coupler", ("A", "B", "P"), "plate"),  # ternary: the rigid union of bars AB and AP
        Body("follower", ("O4", "B"), "bar"),
        Body("rod", ("P", "D"), "bar"),
        Body("ram", ("D",), "ram"),
    )
    GROUND = ("O2", "O4")
    OUTPUT_JOINT = "D"

    @classmethod
    def rules(cls, xp, p, grashof=None):
        """Any crank-rocker or drag-link builds; a problem requires one (its 'grashof' condition)."""
        return grashof_rules(xp, p, grashof) if grashof else []

    def validate(self):
        if all(self.broken_rules(kind) for kind in SHORTEST):
            g = self.grashof()
            raise GrashofError(
                f"CouplerSlider needs a Grashof crank-rocker (r2 shortest) or drag-link (r1 shortest), "
                f"s + l <= p + q; got {g.kind}: shortest {g.shortest}={self.params[g.shortest]:g}, "
                f"s + l = {g.s_plus_l:g}, p + q = {g.p_plus_q:g}",
                params=self.params,
                kind=g.kind,
                required="crank-rocker or drag-link",
            )

    @staticmethod
    def loop(xp, theta2, p):
        a, o4, b, theta3, theta4, m4 = four_bar(xp, theta2, p)
        phi = theta3 + p["beta"]
        pp = (a[0] + p["r5"] * xp.cos(phi), a[1] + p["r5"] * xp.sin(phi))
        d, m6 = rod_to_line(xp, pp, p["r6"], p["h"], p["sigma_slider"])
        return Loop(
            points={"O2": (0.0, 0.0), "A": a, "B": b, "O4": o4, "P": pp, "D": d},
            angles={
                "theta2": theta2,
                "theta3": theta3,
                "theta4": theta4,
                "theta6": xp.atan2(d[1] - pp[1], d[0] - pp[0]),
            },
            x=d[0],
            transmission={"B": joint_lines(a, o4, b), "D": rod_lines(pp, d)},
            margins=[("four-bar closure at B", m4), ("rod PD reaching the slide line", m6)],
        )


__all__ = ["CouplerSlider"]
