"""The four-bar O2-A-B-O4 with O4 = (r1, 0): Grashof class, toggle positions, the FourBar type,
and the shared loop of the four-bar-driven sliders (C on ray O4->B at r5, rod CD to y = h)."""

from __future__ import annotations

import dataclasses
import functools
import math
from typing import ClassVar, NamedTuple

from qropt.errors import GrashofError
from qropt.kinematics.closures import circle_circle
from qropt.mechanisms import closed_forms
from qropt.mechanisms.base import REQUIRED, Mechanism
from qropt.mechanisms.builder import Linkage
from qropt.mechanisms.hints import SynthesisHints
from qropt.mechanisms.values import Rule

LINKS = ("r1", "r2", "r3", "r4")


class Grashof(NamedTuple):
    """Grashof class of r1..r4: kind, the shortest link's name, s + l and p + q."""

    kind: str
    shortest: str
    s_plus_l: float
    p_plus_q: float


def grashof(r1: float, r2: float, r3: float, r4: float, rtol: float = 1e-12) -> Grashof:
    """Classify a four-bar: 'drag-link' (r1 shortest), 'crank-rocker' (r2), 'double-rocker' (r3),
    'rocker-crank' (r4), 'change-point' (s + l = p + q) or 'non-Grashof' (s + l > p + q)."""
    r = {"r1": r1, "r2": r2, "r3": r3, "r4": r4}
    v = sorted(r.values())
    shortest = min(r, key=r.get)
    sl, pq = v[0] + v[3], v[1] + v[2]
    if abs(sl - pq) <= rtol * pq:
        kind = "change-point"
    elif sl > pq:
        kind = "non-Grashof"
    else:
        kind = {"r1": "drag-link", "r2": "crank-rocker", "r3": "double-rocker", "r4": "rocker-crank"}[shortest]
    return Grashof(kind, shortest, sl, pq)


def four_bar(xp, theta2, p):
    """The driving four-bar: (A, O4, B, theta3, theta4, margin) on branch p['sigma']."""
    o4 = (p["r1"], 0.0)
    a = (p["r2"] * xp.cos(theta2), p["r2"] * xp.sin(theta2))
    b, theta4, m = circle_circle(xp, a, p["r3"], o4, p["r4"], p["sigma"], around=math.pi)
    theta3 = xp.atan2(b[1] - a[1], b[0] - a[0])
    return a, o4, b, theta3, theta4, m


def four_bar_linkage() -> Linkage:
    """The driving four-bar as a Linkage (no output yet): B on branch sigma, O4 declared after B (O2, A, B, O4)."""
    L = Linkage()
    L.ground("O2", (0, 0))
    L.crank("A", about="O2", length="r2")
    L.rrr("B", ("A", "r3"), ("O4", "r4"), sign="sigma", around=math.pi)
    L.ground("O4", ("r1", 0))
    return L


FOUR_BAR = four_bar_linkage().output("theta4")
# C on the follower along O4->B at r5 (follower length max(r4, r5)), the rod CD to the ram D on y = h
SLIDER = four_bar_linkage().on_ray("C", "O4", "B", "r5").rrp("D", ("C", "r6"), line_y="h", sign="sigma_slider")
SLIDER.output("D")

SHORTEST = {"drag-link": "r1", "crank-rocker": "r2"}


def grashof_rules(xp, p, kind: str) -> list[Rule]:
    """Grashof with a given shortest link, as smooth inequalities: s <= r_i and 2 (s + r_i) <= r1 + r2 + r3 + r4."""
    s = SHORTEST[kind]
    total = p["r1"] + p["r2"] + p["r3"] + p["r4"]
    out = []
    for k, shorter, sum_ in _grashof_names(kind):
        out.append(Rule(shorter, p[k] - p[s]))
        out.append(Rule(sum_, total - 2 * (p[s] + p[k])))
    return out


@functools.cache
def _grashof_names(kind: str) -> tuple[tuple[str, str, str], ...]:
    """(link, name of 'shortest <= link', name of the sum rule) for each link but the shortest of a class."""
    s = SHORTEST[kind]
    return tuple(
        (k, f"grashof {kind}: {s} <= {k}", f"grashof {kind}: 2({s} + {k}) <= r1 + r2 + r3 + r4")
        for k in LINKS
        if k != s
    )


class _FourBarBase(Mechanism):
    LENGTHS: ClassVar[tuple[str, ...]] = LINKS
    FOUR_BAR = True
    SYNTHESIS = SynthesisHints(
        exact_transmission={"B": (0.0, math.pi)},  # coupler-follower extremes with the crank along the ground line
        ruled_margins=("four-bar closure at B",),  # the Grashof rules make it assemble
    )

    def grashof(self) -> Grashof:
        """Grashof class and shortest link of r1..r4."""
        return grashof(*(self.params[k] for k in LINKS))

    def toggle_positions(self) -> list[tuple[float, str]]:
        """Crank angles (rad, [0, 2pi)) where coupler and follower are collinear: 'extended' or 'folded'."""
        r1, r2, r3, r4 = (self.params[k] for k in LINKS)
        out = []
        for d, kind in ((r3 + r4, "extended"), (abs(r3 - r4), "folded")):
            c = (r1 * r1 + r2 * r2 - d * d) / (2 * r1 * r2)
            if -1.0 <= c <= 1.0:
                t = math.acos(c)
                out += [(t, kind)] + ([(2 * math.pi - t, kind)] if 0.0 < t < math.pi else [])
        return sorted(out)


class FourBar(_FourBarBase):
    """Four-bar r1 ground, r2 crank, r3 coupler, r4 follower; output theta4 (rad), branch sigma.

    Any Grashof class may be built (non-Grashof too); dead centres, swing and
    time ratio need a crank that turns fully and a follower that rocks.
    """

    KIND = "four-bar"
    PARAMS = {"r1": REQUIRED, "r2": REQUIRED, "r3": REQUIRED, "r4": REQUIRED, "sigma": -1.0}
    REQUIRES_FULL_TURN = False
    OUTPUT = "follower"
    TRAVEL = "swing"
    BODIES, GROUND = FOUR_BAR.bodies(), FOUR_BAR.ground_joints()
    SYNTHESIS = dataclasses.replace(
        _FourBarBase.SYNTHESIS, one_reversal=True, closed_forms=(closed_forms.four_bar_starts,)
    )
    EXAMPLE = {"r1": 0.3, "r2": 0.1, "r3": 0.35, "r4": 0.3, "sigma": -1.0}
    loop = staticmethod(FOUR_BAR.loop)

    @classmethod
    def rules(cls, xp, p, grashof=None):
        """Any class builds; a problem may require one (its 'grashof' condition)."""
        return grashof_rules(xp, p, grashof) if grashof else []

    def follower(self, theta2, omega2: float = 1.0, alpha2: float = 0.0):
        """Follower angle theta4 (x), omega4 (v), alpha4 (a) and all link rates; see ``motion``."""
        return self.motion(theta2, omega2, alpha2)

    def swing(self) -> float:
        """theta4_max - theta4_min (rad)."""
        return self.stroke()


class FourBarSlider(_FourBarBase):
    """Four-bar-driven slider: C on ray O4->B at r5, rod r6 from C to D on y = h. Subclasses fix the class."""

    PARAMS = {
        **{k: REQUIRED for k in ("r1", "r2", "r3", "r4", "r5", "r6")},
        "h": 0.0,
        "sigma": -1.0,
        "sigma_slider": 1.0,
    }
    LENGTHS = ("r1", "r2", "r3", "r4", "r5", "r6")
    SHORTEST: ClassVar[str] = ""
    BODIES, GROUND, OUTPUT_JOINT = SLIDER.bodies(), SLIDER.ground_joints(), SLIDER.output_joint()
    # the four-bar adds acceleration extremes of note
    SYNTHESIS = dataclasses.replace(_FourBarBase.SYNTHESIS, one_reversal=True, accel_extremes=4)

    @classmethod
    def rules(cls, xp, p, grashof=None):
        return grashof_rules(xp, p, grashof or cls.CLASS)

    def validate(self):
        if self.broken_rules():
            g = self.grashof()
            p = {k: self.params[k] for k in LINKS}
            raise GrashofError(
                f"{type(self).__name__} needs a Grashof {self.CLASS} ({self.SHORTEST} shortest, s + l <= p + q); "
                f"got {g.kind}: shortest {g.shortest}={p[g.shortest]:g}, s + l = {g.s_plus_l:g}, "
                f"p + q = {g.p_plus_q:g}",
                params=self.params,
                kind=g.kind,
                required=self.CLASS,
            )

    loop = staticmethod(SLIDER.loop)


__all__ = ["FourBar", "FourBarSlider", "Grashof", "grashof", "grashof_rules", "four_bar"]
