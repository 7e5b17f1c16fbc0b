"""The cut-window criterion: how uniform the ram's speed is over a window of the working stroke.

``cut_speed_variation`` = (v_max - v_min) / v_mean over the crank angles where the ram is inside the window, with v
the ram's speed along the working direction and v_mean = (the window's length) / (the time the ram takes through
it), both at the same omega2: dimensionless and independent of omega2 (its sign sets which dead centre starts the
working stroke). A shaper's cutting speed should stay nearly constant over the cut, a press's ram slow and even
through its forming window. Objective ``min_cut_speed_variation``, bound condition ``max_cut_speed_variation``.

The window does not depend on where the design sits: it is measured along the working direction from the working
stroke's start dead centre (the one the ram leaves at the start of the working stroke, for the crank's sense):

- ``cut=(f0, f1)``: fractions of the stroke, 0 <= f0 < f1 <= 1. The registered criterion takes ``(0.1, 0.9)``: the
  middle 80 % of the stroke, 10 % approach and 10 % overrun. The ram starts each stroke at rest, so a window that
  reaches a dead centre has v_min = 0 and measures the peak speed over the stroke (``peak_velocity``), not the
  cut's uniformity; a tool also clears the work before the ram reverses.
- ``cut=qropt.Window(x=(x0, x1), stroke="working")``: distances (the mechanism's length unit) from the start dead
  centre, 0 <= x0 < x1; a design whose stroke is shorter than x1 has no such window (the value raises).

A window of another cut is a criterion of its own: ``window((0.2, 0.8))`` registers (or returns) the criterion named
``cut_speed_variation_20_80`` (objective ``min_cut_speed_variation_20_80``).

Exact value: the window's edges are the crank angles where the ram passes them in the working stroke
(``Mechanism.working_angle_at``: Newton on the exact position, bracketed), the speed's extremes inside are its
exact stationary points (``Mechanism.velocity_extremes``, refined by Newton) or the edges.

In the NLP (at omega2 = 1, derivatives in theta2): the two edges are lifted crank angles phi0 < phi1, like the
dead centres, each on an equality x(phi) = x_start + s d (s the working way along x, d the edge's distance from the
start dead centre; an edge at a dead centre is that dead centre's angle); the largest and the smallest speed over
the window are two epigraph variables over the edges and sample angles phi0 + w (phi1 - phi0) at the problem's
working-arc fractions w, which this criterion reads as fractions of its window (the exchange loop adds the
fractions of the exact extremes the NLP missed); the measure is (z_max + z_-min) (phi1 - phi0) / (d1 - d0). Its
interior speed extremes are not lifted (one need not exist: a window on one side of the speed's peak has its
extremes at its edges, where a stationarity row has no solution), so the exchange loop closes the gap by samples.
"""

from __future__ import annotations

import math

import numpy as np

from qropt.dynamics.model import Window
from qropt.errors import InvalidParameter
from qropt.synthesis import dynamic  # noqa: F401 - the dynamic criteria come first in the registry
from qropt.synthesis.criteria import CRITERIA, Criterion, Exchange, register

TWO_PI = 2.0 * math.pi
DEFAULT_CUT = (0.1, 0.9)  # fractions of the stroke from the working stroke's start: 10 % approach and overrun
NAME = "cut_speed_variation"


def _cut(cut) -> tuple[str, float, float]:
    """('fraction' | 'distance', lo, hi) of a window given as fractions or as a ``Window``; InvalidParameter naming it
    where it is empty, outside [0, 1] (fractions) or before the start (distances)."""
    if isinstance(cut, (Window, dict)):
        w = Window.of(cut)
        if w.x is None or w.stroke != "working" or w.theta2 is not None:
            raise InvalidParameter(
                f"a cut window is a Window(x=(x0, x1), stroke='working') (distances from the working stroke's start "
                f"dead centre), got {w!r:.100}"
            )
        kind, (lo, hi) = "distance", w.x
        if not (lo >= 0 and math.isfinite(hi)):
            raise InvalidParameter(f"a cut window's distances from the start dead centre need 0 <= x0 < x1, got {w.x}")
        return kind, lo, hi
    try:
        lo, hi = (float(v) for v in cut)
    except (TypeError, ValueError):
        raise InvalidParameter(
            f"a cut window is (f0, f1), fractions of the stroke, or a qropt.Window, got {cut!r:.80}"
        ) from None
    if any(isinstance(v, bool) for v in cut) or not (0.0 <= lo < hi <= 1.0):
        raise InvalidParameter(
            f"a cut window (f0, f1) needs 0 <= f0 < f1 <= 1 (fractions of the stroke), got {cut!r:.80}"
        )
    return "fraction", lo, hi


class CutSpeedVariation(Criterion):
    """(v_max - v_min) / v_mean of the ram's speed over a window of the working stroke (dimensionless); minimised.

    cut: the window, as fractions (f0, f1) of the stroke or a ``Window(x=(x0, x1), stroke="working")`` of distances,
    both measured along the working direction from the working stroke's start dead centre (module docstring)."""

    unit, label, slider_only = "1", "cut speed variation", True

    def __init__(self, cut=DEFAULT_CUT, name: str = NAME):
        self.kind, self.lo, self.hi = _cut(cut)
        self.reported = self.kind == "fraction"  # a window of distances may not fit every design: only its problems
        if not isinstance(name, str) or not name.isidentifier():
            raise InvalidParameter(f"a criterion's name is an identifier, got {name!r:.60}")
        self.name = name

    def __repr__(self):
        unit = "of the stroke" if self.kind == "fraction" else "from the start"
        return f"<criterion {self.name} [{self.unit}] window {self.lo:g}..{self.hi:g} {unit}>"

    # ---- the window: distances from the counter-clockwise start of the working arc ------------------------------
    def _distances(self, stroke, forward: bool) -> tuple:
        """(d0, d1), d0 < d1: the window's edges as distances along the working way from the dead centre the
        working arc starts at counter-clockwise (``forward``: the crank turns counter-clockwise, so that is the
        working stroke's start), for a stroke (a number or an NLP expression)."""
        lo, hi = (self.lo * stroke, self.hi * stroke) if self.kind == "fraction" else (self.lo, self.hi)
        return (lo, hi) if forward else (stroke - hi, stroke - lo)

    def _at_dead_centre(self, forward: bool) -> tuple[bool, bool]:
        """Whether each ccw edge is the working arc's start, resp. end, dead centre (then no lift)."""
        full = self.kind == "fraction" and self.hi == 1.0
        start = self.lo == 0.0
        return (start, full) if forward else (full, start)

    def baked(self, problem):  # the crank's sense sets which dead centre starts the working stroke
        return (self.name, problem.omega2 > 0)

    # ---- exact -------------------------------------------------------------------------------------------
    def edges(self, problem, m) -> tuple:
        """(theta0, theta1, d0, d1, speed sign): the window's edge crank angles (counter-clockwise, unwrapped from
        the working arc's start), their distances from that arc's start dead centre and the sign turning dx/dtheta2
        into the speed along the working way (per |omega2|)."""
        d = m.dead_centres()
        start, _ = m.working_arc()
        xa, xb = (d.x_max, d.x_min) if start == d.theta_max else (d.x_min, d.x_max)
        s = 1.0 if xb > xa else -1.0
        stroke = d.x_max - d.x_min
        d0, d1 = self._distances(stroke, problem.omega2 > 0)
        if d1 > stroke * (1 + 1e-12):
            raise InvalidParameter(
                f"{self.name}: the cut window reaches {self.hi:g} from the start dead centre, past the stroke "
                f"{stroke:.6g} of {m!r}"
            )
        t = m.working_angle_at(np.clip(xa + s * np.array([d0, d1]), d.x_min, d.x_max))
        return float(min(t)), float(max(t)), d0, d1, s

    def speeds(self, problem, m) -> tuple[np.ndarray, np.ndarray, tuple]:
        """(crank angles, speeds per |omega2|): the window's edges and its speed's interior extremes, exact; and
        ``edges``' tuple."""
        w = t0, t1, _, _, s = self.edges(problem, m)
        ex = m.velocity_extremes()
        ts = np.concatenate([ex.maxima[0], ex.minima[0]])
        u = t0 + (ts - t0) % TWO_PI
        inside = u[u < t1]
        t = np.concatenate([[t0, t1], inside])
        v = s * np.asarray(m.slider(t).v, float)
        return t, v, w

    def value(self, problem, m):
        t, v, (t0, t1, d0, d1, _) = self.speeds(problem, m)
        return float((v.max() - v.min()) * (t1 - t0) / (d1 - d0))

    def _fractions(self, problem, m, above=None, below=None) -> list:
        """Window fractions of the exact speed extremes above ``above`` and below ``below`` (NLP terms; None: the
        largest and the smallest)."""
        t, v, (t0, t1, *_) = self.speeds(problem, m)
        if above is None:
            picks = [int(np.argmax(v)), int(np.argmin(v))]
        else:
            picks = [i for i in range(v.size) if v[i] > above or -v[i] > below]
        return [float((t[i] - t0) / (t1 - t0)) for i in picks]

    # ---- NLP ---------------------------------------------------------------------------------------------
    def _nlp_window(self, f):
        """The NLP's window: (phi0, phi1, d0, d1, s, xa) (expressions; s the working way along x, xa the position
        at the working arc's counter-clockwise start)."""
        (x_max, *_), (x_min, *_) = f.dead
        d0, d1 = self._distances(x_max - x_min, f.ccw)
        ends = iter(f.lifted.get(self.name, []))
        start, length = f.working_arc()
        at_start, at_end = self._at_dead_centre(f.ccw)
        phi0 = start if at_start else next(ends)
        phi1 = start + length if at_end else next(ends)
        falling = f.orientation > 0  # the working arc falls from theta_max, else rises from theta_min
        return phi0, phi1, d0, d1, (-1.0 if falling else 1.0), (x_max if falling else x_min)

    def lifts(self, f, role):  # the window's edges inside the stroke
        return sum(not e for e in self._at_dead_centre(f.ccw))

    def epigraph(self, f):
        phi0, phi1, *_, s, _ = self._nlp_window(f)
        outs = [f.at(phi0), f.at(phi1)] + [f.at(phi0 + w * (phi1 - phi0)) for w in f.fractions()]
        return [("cut speed max", [s * o.v for o in outs]), ("cut speed -min", [-s * o.v for o in outs])]

    def lift_terms(self, f, k, phi, out):
        _, _, d0, d1, s, xa = self._nlp_window(f)
        d = [d for d, at in zip((d0, d1), self._at_dead_centre(f.ccw), strict=True) if not at][k]
        f.row(f"{self.name}: window edge {k} at its position", out.x - (xa + s * d), 0.0, 0.0, kind="lift")
        f.row(f"{self.name}: window edge {k} in the working stroke", f.in_working(phi), 0.0, 1.0, kind="lift")
        return []

    def measure(self, f, z):
        phi0, phi1, d0, d1, *_ = self._nlp_window(f)
        return (z[0] + z[1]) * (phi1 - phi0) / (d1 - d0)

    def lift_start(self, f, problem, m, n):
        t0, t1, *_ = self.edges(problem, m)
        at_start, at_end = self._at_dead_centre(problem.omega2 > 0)
        return ([] if at_start else [t0]) + ([] if at_end else [t1])

    def exchange(self, f, problem, m, z, value_nlp, gap_tol):
        exact = self.value(problem, m)
        nlp = value_nlp
        gap = exact - nlp if nlp is not None else 0.0
        frac = self._fractions(problem, m, z[0], z[1]) if gap > gap_tol else []
        if gap > gap_tol and not frac:
            frac = self._fractions(problem, m)
        return Exchange(nlp, exact, gap, [], frac)

    def exceeded(self, problem, m):
        return [], self._fractions(problem, m)


def window(cut, name: str | None = None) -> CutSpeedVariation:
    """The cut-window criterion of another window, registered under ``name`` (default from the window, e.g.
    ``cut_speed_variation_20_80`` for the fractions (0.2, 0.8)), or the one already registered under that name with
    the same window. InvalidParameter for a bad window or a name taken by another window."""
    kind, lo, hi = _cut(cut)
    if name is None:
        tag = f"{round(100 * lo):d}_{round(100 * hi):d}" if kind == "fraction" else f"x{lo:g}_{hi:g}".replace(".", "p")
        name = f"{NAME}_{tag}".replace("-", "m")
    have = CRITERIA.get(name)
    if have is not None:
        if isinstance(have, CutSpeedVariation) and (have.kind, have.lo, have.hi) == (kind, lo, hi):
            return have
        raise InvalidParameter(f"criterion {name!r} is registered already with another meaning: {have!r}")
    return register(CutSpeedVariation(cut, name))


CUT = register(CutSpeedVariation(), built_in=True)

__all__ = ["CutSpeedVariation", "CUT", "DEFAULT_CUT", "window"]
