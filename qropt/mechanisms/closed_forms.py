"""Closed forms: the paper's relations under their own names, the synthesis formulas that exist, and the closed-form
starts of each shipped type (``qropt.synthesis.analytic`` re-exports them).

They are independent of the general numerical machinery of the types: they serve as warm starts and as test
oracles. A type names the closed forms that give its starts in ``Mechanism.SYNTHESIS.closed_forms``: each is
a function of a ``Context`` (what it reads of a problem) returning ``WarmStarts``, or None where it does not apply.
Angles in radians, lengths in any consistent unit. Equation numbers refer to Podhorodeski, Nokleby and Wittchen,
"Quick-return mechanism design and analysis projects" (2004).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import NamedTuple

import numpy as np


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


def drag_link_tr_range(r1: float, r2: float, r4: float, r3_lo: float, r3_hi: float) -> tuple[float, float]:
    """(low, high) of eq. (5)'s TR over the coupler lengths r3 in [r3_lo, r3_hi] that keep a Grashof drag-link
    (r1 shortest, s + l <= p + q: r3 in [r1 + |r2 - r4|, r2 + r4 - r1]): a dense scan refined by bounded Brent
    at the best samples; (nan, nan) where no r3 is a drag-link."""
    from scipy.optimize import minimize_scalar

    a, b = max(r3_lo, r1, r1 + abs(r2 - r4)), min(r3_hi, r2 + r4 - r1)
    if not a <= b or r1 > min(r2, r4):
        return math.nan, math.nan
    r3 = np.linspace(a, b, 2001)
    with np.errstate(invalid="ignore"):
        t2a = np.arccos(np.clip((r2**2 + (r4 + r1) ** 2 - r3**2) / (2 * r2 * (r4 + r1)), -1, 1))
        t2b = np.arccos(np.clip((r2**2 + (r4 - r1) ** 2 - r3**2) / (2 * r2 * (r4 - r1)), -1, 1))
    tr = (math.pi - t2a + t2b) / (math.pi + t2a - t2b)
    out = []
    for sign in (1.0, -1.0):
        i = int(np.argmin(sign * tr))
        best = float(tr[i])
        lo_, hi_ = r3[max(i - 1, 0)], r3[min(i + 1, r3.size - 1)]
        if hi_ > lo_:
            res = minimize_scalar(
                lambda x, sign=sign: sign * paper_time_ratio(r1, r2, x, r4),
                bounds=(lo_, hi_),
                method="bounded",
                options={"xatol": 1e-13},
            )
            best = min(best, sign * res.fun, key=lambda v: sign * v) if res.success else best
        out.append(best)
    return out[0], out[1]


def drag_link_r3(time_ratio: float, r1: float, r2: float, r4: float) -> list[DragLinkR3]:
    """Eqs. (7)-(13): every positive r3 giving the time ratio (Grashof not checked).

    The slow interval runs from TDC to BDC (theta2b = theta2a + phi, eq. 7); 0, 1 or 2 roots.
    Roots of eq. (11) whose theta2a or theta2b leaves [0, pi] (the range of eqs. 3a, 3b) are spurious:
    their r3 gives another TR, so they are dropped.
    """
    out = []
    for phi in (tr_deviation(time_ratio),):
        a = (r4 + r1) - (r4 - r1) * math.cos(phi)
        b = (r4 - r1) * math.sin(phi)
        c = 2.0 * r4 * r1 / r2
        disc = a * a + b * b - c * c
        if disc < 0:
            continue
        for t in sorted({math.atan2(b, a) + s * math.atan2(math.sqrt(disc), c) for s in (1.0, -1.0)}):
            r3sq = r2**2 + (r4 + r1) ** 2 - 2 * r2 * (r4 + r1) * math.cos(t)
            if r3sq > 0 and 0.0 <= t <= math.pi and 0.0 <= t + phi <= math.pi:
                out.append(DragLinkR3(math.sqrt(r3sq), t))
    return sorted(out)


def drag_link_discriminant(time_ratio: float, r1: float, r2: float, r4: float) -> float:
    """A^2 + B^2 - C^2 of eq. (12): > 0 two r3 solutions, = 0 one (a fold), < 0 none.

    (The mirrored timing, phi -> -phi, has the same discriminant.)
    """
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


def _roots(g, lo, hi, n):
    """Every root of g on [lo, hi] that changes sign between n grid points, refined by brentq."""
    from scipy.optimize import brentq

    xs = np.linspace(lo, hi, n)
    v = np.array([g(x) for x in xs])
    return [brentq(g, xs[i], xs[i + 1], xtol=1e-15) for i in np.flatnonzero(np.sign(v[:-1]) != np.sign(v[1:]))]


def crank_rocker_r3(time_ratio: float, r1: float, r2: float, r4: float, n: int = 160) -> list[float]:
    """Every coupler r3 of a Grashof crank-rocker (crank r2 shortest; r1, r4 given) whose rocker has this TR:
    the closed-form TR of ``crank_rocker_extremes`` on n values of r3, roots refined by brentq."""
    lo, hi = max(r2, r4 - r1 + r2, r1 - r4 + r2) * (1 + 1e-9), (r1 + r4 - r2) * (1 - 1e-9)
    if not lo < hi:
        return []
    return _roots(lambda r3: crank_rocker_extremes(r1, r2, r3, r4).time_ratio - time_ratio, lo, hi, n)


def rocker_slider_r5(stroke: float, r1: float, r2: float, r3: float, r4: float, r6: float, n: int = 100) -> list[float]:
    """Every output arm r5 of a crank-rocker slider with its slide line through the pivots (h = 0) and rod r6
    giving this stroke: a slider that reverses once does so with the rocker, so the stroke is the slider's
    travel between the rocker's limits."""
    e = crank_rocker_extremes(r1, r2, r3, r4)

    def travel(r5):
        def x(t4):
            return r5 * math.cos(t4) + math.sqrt(max(r6 * r6 - (r5 * math.sin(t4)) ** 2, 0.0))

        return abs(x(e.theta4_extended) - x(e.theta4_folded)) - stroke

    return _roots(travel, 1e-3 * r6, 0.95 * r6, n)


# ---- synthesis families -----------------------------------------------------------------------
class SliderCrankDesign(NamedTuple):
    """An offset slider-crank meeting a TR and stroke: r2, r3, e."""

    r2: float
    r3: float
    e: float


def slider_crank_design(time_ratio: float, stroke: float, r2: float) -> list[SliderCrankDesign]:
    """Offset slider-crank with crank r2 giving TR and stroke (e > 0 and its mirror e < 0).

    Triangle O2, D_max, D_min: sides r3 + r2 and r3 - r2 enclose phi (eq. 7) opposite the stroke.
    """
    phi = tr_deviation(time_ratio)
    k = 1.0 - math.cos(phi)
    if k == 0.0:  # TR = 1: in-line, stroke 2 r2 for any r3 > r2; no isolated design
        return []
    # 2k L^2 + 4 r2 k L + (4 r2^2 - S^2) = 0 for L = r3 - r2
    a, b, c = 2 * k, 4 * r2 * k, 4 * r2 * r2 - stroke * stroke
    disc = b * b - 4 * a * c
    if disc < 0:
        return []
    low = (-b + math.sqrt(disc)) / (2 * a)
    if low <= 0:
        return []
    high = low + 2 * r2
    e = high * low * math.sin(phi) / stroke
    r3 = low + r2
    if abs(e) >= r3 - r2:  # the crank would not turn fully (a slider-crank needs r3 >= r2 + |e|)
        return []
    if high * high - e * e < stroke * stroke:
        # the triangle would put the folded dead centre behind O2 (x < 0), on the other side of the crank
        # pin from where the slider is: this slider-crank's stroke is then shorter and its TR smaller
        return []
    return [SliderCrankDesign(r2, r3, e), SliderCrankDesign(r2, r3, -e)]


WINDOW_STEPS = 60  # bisection steps for the end of the slider-crank's family (a 2^-60 part of the bounds' ratio)


def slider_crank_window(time_ratio: float, stroke: float, lo: float, hi: float) -> tuple[float, float] | None:
    """The cranks r2 in [lo, hi] for which the stroke triangle gives a slider-crank: an interval from the crank
    that just turns fully (|e| = r3 - r2, a toggle) up to stroke/2. It narrows as TR grows (0.47 to 0.5 strokes at
    TR 2.85), so a scan of the bounds alone can miss it. None where no crank in [lo, hi] gives one."""
    # just below stroke/2 (where r3 - r2 and e vanish, rounding can break the triangle's last test)
    tops = [t for k in (12, 9, 6, 3) if lo < (t := min(hi, 0.5 * stroke * (1.0 - 10.0**-k)))]
    top = next((t for t in tops if slider_crank_design(time_ratio, stroke, t)), None)
    if top is None:
        return None
    if slider_crank_design(time_ratio, stroke, lo):
        return lo, top
    a, b = lo, top  # a gives none, b gives one
    for _ in range(WINDOW_STEPS):
        m = math.sqrt(a * b)
        a, b = (a, m) if slider_crank_design(time_ratio, stroke, m) else (m, b)
    return b, top


class CrankRockerDesign(NamedTuple):
    """A crank-rocker four-bar for a TR and swing (either branch sigma: they are mirror images)."""

    r1: float
    r2: float
    r3: float
    r4: float


def crank_rocker_design(time_ratio: float, swing: float, r1: float, position: float) -> CrankRockerDesign | None:
    """Classical crank-rocker synthesis: the family of designs with ground r1, by ``position`` in (0, 1).

    The rocker limits B1, B2 (|O4B| = 1, swing apart) are seen from O2 under phi (eq. 7): O2 lies on
    the circle through B1, B2 with that inscribed angle; ``position`` walks along its major arc. With
    B1 extended (|O2B1| = r3 + r2) and B2 folded, r2 and r3 follow; everything is scaled to ground r1.
    Positions p and 1 - p are mirror images (the same lengths). Returns None where r2 vanishes.
    """
    phi = tr_deviation(time_ratio)
    if not 0 < phi < math.pi or not 0 < swing < math.pi:
        return None
    b1 = complex(math.cos(-swing / 2), math.sin(-swing / 2))
    b2 = complex(math.cos(swing / 2), math.sin(swing / 2))
    chord = abs(b2 - b1)
    radius = chord / (2 * math.sin(phi))
    mid = (b1 + b2) / 2
    # centre on the x-axis, on the side of O2 (the major arc for phi < pi/2, minor beyond)
    centre = mid - radius * math.cos(phi)
    start = math.atan2((b1 - centre).imag, (b1 - centre).real)
    stop = math.atan2((b2 - centre).imag, (b2 - centre).real)
    span = (start - stop) % (2 * math.pi)
    o2 = centre + radius * complex(math.cos(stop + position * span), math.sin(stop + position * span))
    l1, l2 = abs(b1 - o2), abs(b2 - o2)
    r3, r2, ground = (l1 + l2) / 2, abs(l1 - l2) / 2, abs(o2)
    if r2 <= 0 or ground <= 0:
        return None
    scale = r1 / ground
    return CrankRockerDesign(r1, r2 * scale, r3 * scale, scale)


# ---- warm starts ----------------------------------------------------------------------------------
class WarmStarts(NamedTuple):
    """Free-parameter values from the closed forms that apply to a problem.

    kind: 'enumeration' (the points are every solution of the targets within the problem's structure),
    'family' (points along a closed-form one-parameter family that holds every solution, in order),
    'partial' (starting points only) or 'none'; how: which closed form, in words.
    """

    points: list
    kind: str
    how: str
    ranges: dict = {}  # target -> (low, high) over the free bounds, where the closed form gives it
    walk: Walk | None = None  # a family's designs as a function of its parameter, where the closed form has one


class Walk(NamedTuple):
    """A closed-form family as a function: ``at(x)`` the free values of its designs at parameter x (a list, in the
    order the points were emitted at that x: mirror images are several), ``positions`` each point's x, ``name``
    what x is."""

    at: Callable[[float], list]
    positions: tuple
    name: str


FAMILY_POINTS = 17  # closed-form family points scanned when a family holds every solution


class Context:
    """What every closed form reads of a problem (``fixed``, ``free`` bounds, targets ``tg``; ``val`` the fixed
    values and the free ones at mid-bounds; ``tr`` and ``stroke`` the targets or None; ``square`` as many free
    parameters as targets): ``emit`` adds a start (its free values), ``result`` closes the starts with their kind."""

    def __init__(self, problem):
        self.fixed, self.free, self.tg = problem.fixed, problem.free, problem.targets
        self.val = {**self.fixed, **{k: 0.5 * (lo + hi) for k, (lo, hi) in self.free.items()}}
        self.tr, self.stroke = self.tg.get("time_ratio"), self.tg.get("stroke")
        self.square = len(self.free) == len(self.tg)
        self.kind = problem.mechanism.CLASS  # the four-bar's Grashof class, if the type has one
        self.out, self.positions = [], []
        self.position = None  # a family's parameter at the points emitted next (``result``'s walk)

    def point(self, **set_) -> dict | None:
        """The free values with ``set_`` given (every other free parameter at mid-bounds); None where ``set_``
        names a parameter that is not free."""
        if not all(k in self.free for k in set_):
            return None
        v = {**self.val, **set_}
        return {k: v[k] for k in self.free}

    def emit(self, **set_):
        v = self.point(**set_)
        if v is not None:
            self.out.append(v)
            self.positions.append(self.position)

    def result(self, kind, how, walk=None, name=""):
        """The starts; walk: for a family, its designs' free values as a function of the parameter ``name``."""
        if kind == "enumeration":  # complete: no point is a proof that no design exists
            return WarmStarts(self.out, kind, how)
        if not self.out:
            return WarmStarts(self.out, "none", "no closed form applies")
        family = Walk(walk, tuple(self.positions), name) if walk is not None and kind == "family" else None
        return WarmStarts(self.out, kind, how, walk=family)

    def names(self):
        return self.fixed, self.free, self.tg, self.val, self.tr, self.stroke, self.square, self.emit, self.result


def crank_rocker_slider_starts(c: Context):
    """The rocker's TR gives r3 and the stroke r5 for each r4 (slide line through the pivots)."""
    fixed, free, tg, val, tr, stroke, square, emit, result = c.names()
    if set(free) == {"r3", "r4", "r5"} and fixed.get("h", 0.0) == 0.0 and tr and stroke:
        for k in (0, 1):  # each root of the rocker's TR in r3 is a branch of the family; r4 walks it
            for r4 in np.linspace(*free["r4"], FAMILY_POINTS):
                roots = crank_rocker_r3(tr, val["r1"], val["r2"], float(r4))
                if len(roots) > k:
                    for r5 in rocker_slider_r5(stroke, val["r1"], val["r2"], roots[k], float(r4), val["r6"]):
                        emit(r3=roots[k], r4=float(r4), r5=r5)
        how = "the rocker's TR gives r3 and the stroke r5 for each r4 (slide line through the pivots); r4 walks it"
        return result("family", how)
    return None


def drag_link_slider_starts(c: Context):
    """Eqs. (7)-(13): every r3 for the TR; r5 = stroke/2."""
    fixed, free, tg, val, tr, stroke, square, emit, result = c.names()
    lifted = {"r2", "r4", "r5"} <= set(free)  # every link of the four-bar and the arm free: the generic starts
    if tr is not None and "r3" in free and fixed.get("h", 0.0) == 0.0 and not lifted:
        r5 = {"r5": stroke / 2} if stroke is not None and "r5" in free else {}
        for s in drag_link_r3(tr, val["r1"], val["r2"], val["r4"]):
            emit(r3=s.r3, **r5)
        exact = square and set(free) <= {"r3", "r5"} and ("r5" not in free or fixed.get("r6", 0.0) > stroke / 2)
        how = "eqs. (7)-(13) give every r3 for the TR; r5 = stroke/2"
        if exact:
            lo, hi = free.get("r3", (val["r3"], val["r3"]))
            return WarmStarts(
                c.out, "enumeration", how, {"time_ratio": drag_link_tr_range(val["r1"], val["r2"], val["r4"], lo, hi)}
            )
        return result("partial", how)
    return None


def crank_shaper_starts(c: Context):
    """sin(beta) = r2/r1 fixes the TR; stroke = 2 r4 r2/r1."""
    fixed, free, tg, val, tr, stroke, square, emit, result = c.names()
    if tr is not None:
        ratio = crank_shaper_ratio(tr)
        lever = {"r4": stroke / (2 * ratio)} if stroke is not None and "r4" in free else {}
        yoke = "r6" not in fixed and "r6" not in free
        missing = _lever_outside(free, val, ratio, lever)  # every design shares r2/r1 and r4: none in the bounds
        if yoke and stroke is not None and set(free) == {"r1", "r2", "r4"}:  # r1 walks the family, r4 fixed
            how = "sin(beta) = r2/r1 fixes the TR; stroke = 2 r4 r2/r1; r1 walks the family"
            if missing:
                return result("enumeration", f"{how}: {missing}")
            for r1 in np.geomspace(*_crank_range(free, ratio), FAMILY_POINTS):
                emit(r1=float(r1), r2=float(ratio * r1), **lever)
            return result("family", how)
        if missing:  # with a rod too: its slider reverses where the lever does (or more than once a turn)
            return result(
                "enumeration", f"sin(beta) = r2/r1 fixes the TR and stroke = 2 r4 r2/r1 (with a rod too): {missing}"
            )
        rod = "r6" in free and "h" not in free and stroke is not None and len(free) == 3 and "r4" in free
        if rod and ("r2" in free) != ("r1" in free):  # the rod's slider reverses where the lever does
            for r6 in np.geomspace(*free["r6"], FAMILY_POINTS):
                crank = {"r2": ratio * val["r1"]} if "r2" in free else {"r1": val["r2"] / ratio}
                emit(**crank, **lever, r6=float(r6))
            return result(
                "family",
                "sin(beta) = r2/r1 fixes the TR and stroke = 2 r4 r2/r1 for every rod (a slider "
                "reversing once does so with the lever); the rod r6 walks the family",
            )
        if "r2" in free:
            emit(r2=ratio * val["r1"], **lever)
        elif "r1" in free:
            emit(r1=val["r2"] / ratio, **lever)
        elif stroke is not None and "r4" in free:
            emit(r4=stroke * val["r1"] / (2 * val["r2"]))
        exact = square and "r6" not in fixed and "r6" not in free
        return result("enumeration" if exact else "partial", "sin(beta) = r2/r1 fixes the TR; stroke = 2 r4 r2/r1")
    return None


def slot_ram_shaper_stroke(r1: float, r2: float, h: float) -> float:
    """Stroke 2 h r2 / sqrt(r1^2 - r2^2) of a slot-ram shaper: the lever's extremes (tangent to the crank circle,
    sin(beta) = r2/r1 from the vertical) cross the slide line at x = +/- h tan(beta); TR is the crank-shaper's."""
    return 2.0 * h * r2 / math.sqrt(r1 * r1 - r2 * r2)


def slot_ram_shaper_gamma_min(r1: float, r2: float) -> float:
    """gamma_min = acos(r2/r1) of a slot-ram shaper: at D, the lever at its extremes meets the slide line at
    pi/2 - beta (the block at A transmits at 90 degrees)."""
    return math.acos(r2 / r1)


def _crank_range(free, ratio) -> tuple[float, float]:
    """(lo, hi): the r1 in its bounds whose crank r2 = ratio r1 lies in r2's (lo > hi where none does)."""
    return max(free["r1"][0], free["r2"][0] / ratio), min(free["r1"][1], free["r2"][1] / ratio)


def _lever_outside(free, val, ratio, lever) -> str:
    """Why no crank-shaper (with or without a rod) with r2/r1 = ``ratio`` and the ``lever`` r4 it needs lies inside
    the bounds, or '' (also where r4 is not free or neither crank link is)."""
    if not lever:
        return ""
    if "r1" in free and "r2" in free:
        return _outside(free, lever, *_crank_range(free, ratio), "r1")
    if "r2" in free:
        return _outside(free, {**lever, "r2": ratio * val["r1"]}, 0.0, 0.0, "r1")
    if "r1" in free:
        return _outside(free, {**lever, "r1": val["r2"] / ratio}, 0.0, 0.0, "r1")
    return ""


def _outside(free, fixed_along, lo, hi, walker) -> str:
    """Why a family that holds every design has none inside the bounds (a value that every design shares lies
    outside its bounds, or no ``walker`` in [lo, hi] keeps the other crank link inside its own), or ''."""
    for k, v in fixed_along.items():  # v, or (v, -v) where the mirror image has -v
        a, b = free[k]
        values = v if isinstance(v, tuple) else (v,)
        if not any(a <= x <= b for x in values):
            shown = " or ".join(f"{x:.6g}" for x in values)
            return f"every design has {k} = {shown}, outside its bounds [{a:.6g}, {b:.6g}]"
    if lo > hi:
        return f"no {walker} inside its bounds keeps r2 = r1 sin(beta) inside r2's"
    return ""


def slot_ram_shaper_starts(c: Context):
    """sin(beta) = r2/r1 fixes the TR; h = stroke sqrt(r1^2 - r2^2) / (2 r2); with r1 and r2 free r1 walks the
    family (the motion depends on r2/r1 and h only: every kinematic criterion is the same along it)."""
    fixed, free, tg, val, tr, stroke, square, emit, result = c.names()
    crank = [k for k in ("r1", "r2") if k in free]
    if not crank:  # r2/r1 given: only the stroke can be met, by h
        if tr is None and stroke is not None and "h" in free:
            emit(h=stroke * math.sqrt(val["r1"] ** 2 - val["r2"] ** 2) / (2.0 * val["r2"]))
            return result("enumeration" if square else "partial", "h = stroke sqrt(r1^2 - r2^2) / (2 r2)")
        return None
    if tr is not None:
        ratio = crank_shaper_ratio(tr)
    elif stroke is not None and "h" not in free:
        q = stroke / (2.0 * val["h"])  # tan(beta) from the stroke at the given h
        ratio = q / math.sqrt(1.0 + q * q)
    else:
        return None
    if not 0.0 < ratio < 1.0:
        return None
    both = tr is not None and stroke is not None
    h = {"h": stroke * math.sqrt(1.0 - ratio * ratio) / (2.0 * ratio)} if both and "h" in free else {}
    how = "sin(beta) = r2/r1 fixes the TR; h = stroke sqrt(r1^2 - r2^2) / (2 r2)"
    if len(crank) == 2:  # the family: r1 over its bounds (and r2's over the ratio)
        lo, hi = _crank_range(free, ratio)
        exact = len(free) == len(tg) + 1 and ("h" in free) == both
        missing = _outside(free, {"h": (h["h"], -h["h"])}, lo, hi, "r1") if h else ""
        if missing and exact:  # the family holds every design: none inside the bounds
            return result("enumeration", f"{how}: {missing}")
        if lo <= hi:
            for r1 in np.geomspace(lo, hi, FAMILY_POINTS) if lo < hi else [lo]:
                emit(r1=float(r1), r2=float(ratio * r1), **h)
        return result("family" if exact else "partial", how + "; r1 walks the family (the least size at its least)")
    emit(**({"r2": ratio * val["r1"]} if "r2" in free else {"r1": val["r2"] / ratio}), **h)
    exact = square and ("h" in free) == both
    return result("enumeration" if exact else "partial", how)


def whitworth_starts(c: Context):
    """sin(beta) = r1/r2 fixes the TR; stroke = 2 r5."""
    fixed, free, tg, val, tr, stroke, square, emit, result = c.names()
    if tr is not None and fixed.get("h", 0.0) == 0.0:
        ratio = whitworth_ratio(tr)
        r5 = {"r5": stroke / 2} if stroke is not None and "r5" in free else {}
        rod = "r6" in free and "r5" in free and not square
        sweep = list(np.geomspace(*free["r6"], FAMILY_POINTS)) if rod else [val.get("r6")]
        for r6 in sweep:
            extra = {"r6": r6} if rod else {}
            if "r2" in free:
                emit(r2=val["r1"] / ratio, **r5, **extra)
            elif "r1" in free:
                emit(r1=ratio * val["r2"], **r5, **extra)
            elif r5:
                emit(**r5, **extra)
        how = "sin(beta) = r1/r2 fixes the TR; stroke = 2 r5 (rod longer than r5)"
        if square and stroke is not None and fixed.get("r6", 0.0) > stroke / 2:
            return result("enumeration", how)
        if rod and len(free) == len(tg) + 1 and stroke is not None:
            return result("family", how + "; the rod r6 walks the family")
        return result("partial", how)
    return None


def slider_crank_starts(c: Context):
    """The stroke triangle gives r3 and e for each r2."""
    fixed, free, tg, val, tr, stroke, square, emit, result = c.names()
    if tr is not None and stroke is not None:
        family = "r2" in free and len(free) == 3
        window = slider_crank_window(tr, stroke, *free["r2"]) if "r2" in free else None
        lo, hi = window or free.get("r2", (0.0, 0.0))
        n = FAMILY_POINTS if family else 7
        crank = (
            [val["r2"]]
            if "r2" not in free
            else list(np.geomspace(lo, hi, n + 2)[1:-1] if window else np.geomspace(lo, hi, n))
        )

        def designs(r2):  # the free values of the triangle's designs with crank r2
            return [
                {k: getattr(d, k) for k in ("r2", "r3", "e") if k in free} for d in slider_crank_design(tr, stroke, r2)
            ]

        for r2 in crank:
            c.position = float(r2)
            for v in designs(r2):
                emit(**v)
        how = "the stroke triangle (sides r3 + r2, r3 - r2, angle phi of eq. 7) gives r3 and e for each r2"
        if square and set(free) == {"r3", "e"}:
            return result("enumeration", how)

        def walk(r2):  # the designs as emit gives them
            return [c.point(**v) for v in designs(r2)]

        return result("family" if family else "partial", how + "; r2 walks the family", walk, "r2")
    return None


def four_bar_starts(c: Context):
    """The classical crank-rocker construction."""
    fixed, free, tg, val, tr, stroke, square, emit, result = c.names()
    if tr is not None and "swing" in tg:
        family = set(free) == {"r2", "r3", "r4"}
        for pos in np.linspace(0.01, 0.49, FAMILY_POINTS) if family else np.linspace(0.04, 0.46, 7):
            d = crank_rocker_design(tr, tg["swing"], val["r1"], float(pos))
            if d is not None:
                emit(**{k: getattr(d, k) for k in ("r2", "r3", "r4") if k in free})
        how = "the classical crank-rocker construction (O2 on the circle that sees the rocker chord under phi)"
        return result("family" if family else "partial", how)
    return None


def four_bar_slider_starts(c: Context):
    """Generic starts for a four-bar-driven slider with every link free."""
    fixed, free, tg, val, tr, stroke, square, emit, result = c.names()
    if tr is not None and stroke is not None and {"r2", "r3", "r4", "r5"} <= set(free):
        # the four-bar from its closed form, the slide line through the pivots (h = 0), the output arm r5 sized
        # for the stroke and a rod twice as long: starts near the targets for every other free parameter
        r1 = stroke if "r1" in free else val["r1"]

        def emit_free(**design):  # the fixed parameters keep their values
            emit(**{k: x for k, x in design.items() if k in free})

        if c.kind == "drag-link":
            for k2, k4 in ((2.0, 2.5), (3.0, 3.5), (2.5, 4.0)):
                for d in drag_link_r3(tr, r1, k2 * r1, k4 * r1):
                    emit_free(r1=r1, r2=k2 * r1, r3=d.r3, r4=k4 * r1, r5=stroke / 2, r6=stroke, h=0.0)
            how = "eqs. (7)-(13) give r3 for a few drag-links; r5 = stroke/2, h = 0"
        else:
            for swing in np.radians([40.0, 60.0, 80.0]):
                for pos in (0.15, 0.3):
                    d = crank_rocker_design(tr, float(swing), r1, pos)
                    if d is not None:
                        r5 = stroke / (2 * math.sin(swing / 2))
                        emit_free(r1=r1, r2=d.r2, r3=d.r3, r4=d.r4, r5=r5, r6=2 * r5, h=0.0)
            how = "the classical crank-rocker construction at swings 40-80 deg; r5 from the stroke, h = 0"
        return result("partial", how)
    return None
