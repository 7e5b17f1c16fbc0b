"""Coupler-driven slider (Stephenson III six-bar): a coupler point P of the four-bar O2-A-B-O4 drives the ram D
through the rod PD on the slide line y = h."""

from __future__ import annotations

import dataclasses

from qropt.errors import GrashofError
from qropt.mechanisms.base import REQUIRED
from qropt.mechanisms.four_bar import SHORTEST, _FourBarBase, four_bar_linkage, grashof_rules

# the coupler point P at r5 from A, beta off A->B (the coupler a ternary plate ABP), the rod PD to the ram on y = h
LINKAGE = four_bar_linkage().coupler_point("P", "A", "B", "r5", angle="beta")
LINKAGE.rrp("D", ("P", "r6"), line_y="h", sign="sigma_slider").output("D")


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
    # sliders (exact_transmission), and the Grashof rules make the four-bar assemble (ruled_margins), both inherited;
    # a coupler point's path adds acceleration extremes beyond the four-bar sliders' four
    SYNTHESIS = dataclasses.replace(_FourBarBase.SYNTHESIS, accel_extremes=6)
    BODIES, GROUND, OUTPUT_JOINT = LINKAGE.bodies(), LINKAGE.ground_joints(), LINKAGE.output_joint()
    EXAMPLE = {
        **{"r1": 1.0561, "r2": 0.0827, "r3": 0.3681, "r4": 0.9933, "r5": 1.5, "beta": -0.5201, "r6": 1.0128},
        **{"h": 0.9477, "sigma": -1.0, "sigma_slider": 1.0},
    }
    loop = staticmethod(LINKAGE.loop)

    @classmethod
    def rules(cls, xp, p, grashof=None):
        """Any crank-rocker or drag-link builds; a problem requires one (its 'grashof' condition)."""
        return grashof_rules(xp, p, grashof) if grashof else []

    def validate(self):
        # the class whose shortest link is the shorter first: the other is then rarely evaluated
        if all(self.broken_rules(k) for k in sorted(SHORTEST, key=lambda k: self.params[SHORTEST[k]])):
            g = self.grashof()
            raise GrashofError(
                f"CouplerSlider needs a Grashof crank-rocker (r2 shortest) or drag-link (r1 shortest), "
                f"s + l <= p + q; got {g.kind}: shortest {g.shortest}={self.params[g.shortest]:g}, "
                f"s + l = {g.s_plus_l:g}, p + q = {g.p_plus_q:g}",
                params=self.params,
                kind=g.kind,
                required="crank-rocker or drag-link",
            )


__all__ = ["CouplerSlider"]
