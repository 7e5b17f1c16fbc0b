"""Closed forms: the paper's relations under their own names and the synthesis formulas that exist.

These are independent of the general numerical machinery in ``mechanisms``:
they serve as warm starts and as test oracles. Angles in radians, lengths in
any consistent unit. Equation numbers refer to Podhorodeski, Nokleby and
Wittchen, "Quick-return mechanism design and analysis projects" (2004).
"""

from __future__ import annotations

import math
from typing import NamedTuple


def _acos(c: float) -> float:
    if not -1.0 <= c <= 1.0:
        raise ValueError(f"no real angle: cosine {c:g} outside [-1, 1]")
    return math.acos(c)


def tr_deviation(time_ratio: float) -> float:
    """phi = (TR - 1) pi / (TR + 1), eq. (7): how far the two dead-centre crank positions are from opposite."""
    return (time_ratio - 1.0) * math.pi / (time_ratio + 1.0)


# ---- the paper's drag-link relations (h = 0, slide line through O2 and O4) -----------------
def paper_dead_centre_angles(r1: float, r2: float, r3: float, r4: float) -> tuple[float, float]:
    """Eqs. (3a), (3b): crank angles theta2a (TDC, follower along +x) and theta2b (BDC), in [0, pi].

    They are the angles of triangle O2-A-B at O2 (the cosine law of eqs. 2a, 2b), not
    signed crank positions.
    """
    t2a = _acos((r2**2 + (r4 + r1) ** 2 - r3**2) / (2 * r2 * (r4 + r1)))
    t2b = _acos((r2**2 + (r4 - r1) ** 2 - r3**2) / (2 * r2 * (r4 - r1)))
    return t2a, t2b


def paper_time_ratio(r1: float, r2: float, r3: float, r4: float) -> float:
    """Eqs. (4), (5): TR = (pi - theta2a + theta2b) / (pi + theta2a - theta2b) of the drag-link slider."""
    t2a, t2b = paper_dead_centre_angles(r1, r2, r3, r4)
    return (math.pi - t2a + t2b) / (math.pi + t2a - t2b)


def paper_transmission_at_dead_centres(r1: float, r2: float, r3: float, r4: float) -> tuple[float, float]:
    """Eqs. (14)-(17): coupler-follower transmission angles (rad) at TDC and BDC only.

    This is not gamma_min: the four-bar's transmission angle is extreme where the
    crank is collinear with the ground (theta2 = 0, pi), not at the dead centres.
    """
    g_tdc = _acos((r3**2 + (r4 + r1) ** 2 - r2**2) / (2 * r3 * (r4 + r1)))
    g_bdc = _acos((r3**2 + (r4 - r1) ** 2 - r2**2) / (2 * r3 * (r4 - r1)))
    return g_tdc, g_bdc


class DragLinkR3(NamedTuple):
    """One real solution of eqs. (11)-(13): coupler length r3 and the TDC crank angle theta2a (rad)."""

    r3: float
    theta2a: float


def drag_link_r3(time_ratio: float, r1: float, r2: float, r4: float) -> list[DragLinkR3]:
    """Eqs. (7)-(13): every positive r3 giving the time ratio (0, 1 or 2 solutions; Grashof not checked)."""
    f = tr_deviation(time_ratio)
    a = (r4 + r1) - (r4 - r1) * math.cos(f)
    b = (r4 - r1) * math.sin(f)
    c = 2.0 * r4 * r1 / r2
    disc = a * a + b * b - c * c
    if disc < 0:
        return []
    roots = {math.atan2(b, a) + s * math.atan2(math.sqrt(disc), c) for s in (1.0, -1.0)}
    out = []
    for t in sorted(roots):
        r3sq = r2**2 + (r4 + r1) ** 2 - 2 * r2 * (r4 + r1) * math.cos(t)
        if r3sq > 0:
            out.append(DragLinkR3(math.sqrt(r3sq), t))
    return sorted(out)


def drag_link_discriminant(time_ratio: float, r1: float, r2: float, r4: float) -> float:
    """A^2 + B^2 - C^2 of eq. (12): > 0 two r3 solutions, = 0 one (a fold), < 0 none."""
    f = tr_deviation(time_ratio)
    a = (r4 + r1) - (r4 - r1) * math.cos(f)
    b = (r4 - r1) * math.sin(f)
    return a * a + b * b - (2.0 * r4 * r1 / r2) ** 2


# ---- inverted slider-cranks -----------------------------------------------------------------
def crank_shaper_time_ratio(r1: float, r2: float) -> float:
    """TR of a crank-shaper: the lever's extremes are tangent to the crank circle, sin(beta) = r2/r1."""
    beta = math.asin(r2 / r1)
    return (math.pi + 2 * beta) / (math.pi - 2 * beta)


def crank_shaper_stroke(r1: float, r2: float, r4: float) -> float:
    """Stroke 2 r4 r2 / r1 (yoke, or rod whenever the dead centres are the lever's extremes)."""
    return 2.0 * r4 * r2 / r1


def crank_shaper_ratio(time_ratio: float) -> float:
    """r2 / r1 of a crank-shaper with the given TR."""
    return math.sin(tr_deviation(time_ratio) / 2.0)


def whitworth_time_ratio(r1: float, r2: float) -> float:
    """TR of a Whitworth with the slide line through O4 (h = 0): the dead centres have the lever horizontal."""
    beta = math.asin(r1 / r2)
    return (math.pi + 2 * beta) / (math.pi - 2 * beta)


def whitworth_ratio(time_ratio: float) -> float:
    """r1 / r2 of a Whitworth (h = 0) with the given TR; its stroke is 2 r5 when r6 > r5."""
    return math.sin(tr_deviation(time_ratio) / 2.0)


# ---- offset slider-crank --------------------------------------------------------------------
class SliderCrankCentres(NamedTuple):
    """Dead centres of an offset slider-crank (sigma_slider = +1): crank angles (rad) and positions."""

    theta_max: float
    theta_min: float
    x_max: float
    x_min: float


def slider_crank_dead_centres(r2: float, r3: float, e: float) -> SliderCrankCentres:
    """Extended (crank along the rod) and folded (crank against the rod) positions."""
    x_max = math.sqrt((r3 + r2) ** 2 - e * e)
    x_min = math.sqrt((r3 - r2) ** 2 - e * e)
    t_max = math.atan2(e, x_max) % (2 * math.pi)
    t_min = math.atan2(-e, -x_min) % (2 * math.pi)
    return SliderCrankCentres(t_max, t_min, x_max, x_min)


def time_ratio_from_centres(theta_max: float, theta_min: float) -> float:
    """The contract's TR from two dead-centre crank angles (rad)."""
    a = (theta_min - theta_max) % (2 * math.pi)
    return max(a, 2 * math.pi - a) / min(a, 2 * math.pi - a)


# ---- crank-rocker four-bar ------------------------------------------------------------------
class RockerExtremes(NamedTuple):
    """Crank angles (rad) at the rocker's extended and folded limits, theta4 there, swing and TR."""

    theta2_extended: float
    theta2_folded: float
    theta4_extended: float
    theta4_folded: float
    swing: float
    time_ratio: float


def crank_rocker_extremes(r1: float, r2: float, r3: float, r4: float, sigma: float = -1.0) -> RockerExtremes:
    """Limits of a crank-rocker's rocker: crank and coupler collinear (O2B = r3 + r2 or r3 - r2).

    theta4 is measured like ``FourBar``: continuous around pi (O4 = (r1, 0)).
    """
    out = []
    for d, sign in ((r3 + r2, 1.0), (r3 - r2, -1.0)):
        # B on circles about O2 (radius d) and O4 (radius r4); A on line O2B, towards B when extended
        ang = _acos((r1 * r1 + d * d - r4 * r4) / (2 * r1 * d))
        for up in (1.0, -1.0):
            bx, by = d * math.cos(ang), up * d * math.sin(ang)
            ax, ay = sign * r2 * bx / d, sign * r2 * by / d
            if math.copysign(1.0, (ax - r1) * by - ay * (bx - r1)) == sigma:
                break
        out.append((math.atan2(ay, ax) % (2 * math.pi), math.pi + math.atan2(-by, r1 - bx)))
    (t2e, t4e), (t2f, t4f) = out
    return RockerExtremes(t2e, t2f, t4e, t4f, abs(t4e - t4f), time_ratio_from_centres(t2e, t2f))
