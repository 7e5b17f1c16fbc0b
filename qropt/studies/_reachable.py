"""What one adjustable parameter can reach: its feasible interval, the TR (and stroke) range with the
parameter values where the extremes occur, how many designs give a TR, and how far an adjustable link
must travel to cover a set of TRs."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np
from scipy.optimize import brentq, minimize_scalar

from qropt.errors import InvalidParameter, QroptError
from qropt.kinematics.ops import NUMPY
from qropt.mechanisms import Mechanism
from qropt.validate import MAGNITUDE

SPAN = 1000.0  # given bounds may span at most this many times the mechanism's largest other parameter


def _rule_interval(m: Mechanism, free: str, kind=None):
    """The free parameter's interval where the type's rules hold (each rule is linear in one parameter): lengths
    are positive, offsets (e, h) take either sign."""
    lo, hi = (0.0 if free in m.LENGTHS else -math.inf), math.inf
    p = dict(m.params)
    at0 = type(m).rules(NUMPY, {**p, free: 0.0}, kind)
    at1 = type(m).rules(NUMPY, {**p, free: 1.0}, kind)
    for r0, r1 in zip(at0, at1, strict=True):
        a, b = r1.value - r0.value, r0.value  # rule value a x + b >= 0
        if a > 0:
            lo = max(lo, -b / a)
        elif a < 0:
            hi = min(hi, -b / a)
        elif b < 0:
            return 0.0, 0.0
    return lo, hi


@dataclass(frozen=True)
class Adjustable:
    """The travel an adjustable link needs: its interval, the TRs covered, the worst gamma_min on it."""

    interval: tuple
    covers: tuple
    gamma_min: float
    explanation: str
    alternatives: list = field(default_factory=list)


class Range(NamedTuple):
    """The smallest and largest value of a quantity and the parameter values where they occur."""

    low: float
    low_at: float
    high: float
    high_at: float


@dataclass
class Reachable:
    """TR and stroke over one free parameter (the others from a mechanism)."""

    base: Mechanism
    free: str
    intervals: list
    grid: np.ndarray
    tr: np.ndarray
    stroke: np.ndarray
    time_ratio_range: Range | tuple
    stroke_range: Range | tuple

    def _tr_at(self, x):
        return _evaluate(self.base, self.free, x)[0]

    def solutions(self, time_ratio: float) -> list[float]:
        """Every value of the free parameter giving this TR (roots refined by brentq)."""
        time_ratio = _time_ratio(time_ratio)
        out = []
        ok = np.isfinite(self.tr)
        d = self.tr - time_ratio
        for i in range(len(self.grid) - 1):
            if ok[i] and ok[i + 1]:
                if d[i] == 0:
                    out.append(float(self.grid[i]))
                elif d[i] * d[i + 1] < 0:
                    out.append(
                        brentq(lambda x: self._tr_at(x) - time_ratio, self.grid[i], self.grid[i + 1], xtol=1e-14)
                    )
        lo, at_lo, hi, at_hi = self.time_ratio_range
        for v, at in ((lo, at_lo), (hi, at_hi)):
            if abs(v - time_ratio) <= 1e-12 and all(abs(at - s) > 1e-9 for s in out):
                out.append(at)
        return sorted(out)

    def count(self, time_ratio: float) -> int:
        """How many designs (values of the free parameter) give this TR: 0, 1, 2, ..."""
        return len(self.solutions(time_ratio))

    def branches(self):
        """Monotone pieces of TR(free): [(x_from, x_to, tr_from, tr_to)], split at interior TR extremes."""
        out = []
        for lo, hi in self.intervals:
            inside = (self.grid >= lo) & (self.grid <= hi) & np.isfinite(self.tr)
            x, y = self.grid[inside], self.tr[inside]
            if x.size < 2:
                continue
            cuts = [x[0]]
            for i in range(1, x.size - 1):
                if (y[i] - y[i - 1]) * (y[i + 1] - y[i]) < 0:
                    cuts.append(_refine_extreme(self, x[i - 1], x[i + 1], y[i] > y[i - 1])[0])
            cuts.append(x[-1])
            out += [(a, b, self._tr_at(a), self._tr_at(b)) for a, b in zip(cuts[:-1], cuts[1:], strict=True)]
        return out

    def adjustable(self, tr_low: float, tr_high: float | None = None) -> Adjustable:
        """The shortest travel of the free link reaching every TR in [tr_low, tr_high] on one monotone branch,
        preferring the branch with the best worst-case gamma_min; alternatives are listed."""
        tr_low = _time_ratio(tr_low, "tr_low")
        tr_high = tr_low if tr_high is None else _time_ratio(tr_high, "tr_high")
        if tr_low > tr_high:
            raise InvalidParameter(
                f"adjustable TR range {tr_low:g}..{tr_high:g} runs backwards: give the lower time ratio first"
            )
        cands = []
        for a, b, ya, yb in self.branches():
            lo_tr, hi_tr = min(ya, yb), max(ya, yb)
            if lo_tr - 1e-12 <= tr_low and tr_high <= hi_tr + 1e-12:
                xs = sorted(_inverse(self, a, b, t) for t in (tr_low, tr_high))
                g = min(_evaluate(self.base, self.free, x)[2] for x in np.linspace(xs[0], xs[1], 25))
                cands.append(((xs[0], xs[1]), g, (a, b)))
        if not cands:
            lo, _, hi, _ = self.time_ratio_range
            raise InvalidParameter(
                f"no single branch of {self.free} reaches TR {tr_low:g}..{tr_high:g}; reachable {lo:.6g}..{hi:.6g}"
            )
        cands.sort(key=lambda c: -c[1])
        (x0, x1), g, (a, b) = cands[0]
        why = (
            f"{self.free} from {x0:.6g} to {x1:.6g} covers TR {tr_low:g}..{tr_high:g} once, on the branch "
            f"{a:.6g}..{b:.6g} where TR is monotone; its worst gamma_min is {math.degrees(g):.2f} deg"
        )
        if len(cands) > 1:
            why += "; the other branch(es) " + ", ".join(
                f"{c[0][0]:.6g}..{c[0][1]:.6g} (worst gamma_min {math.degrees(c[1]):.2f} deg)" for c in cands[1:]
            )
        return Adjustable((x0, x1), (tr_low, tr_high), g, why, [c[0] for c in cands[1:]])


def _time_ratio(v, name="time ratio") -> float:
    """A time ratio given to a Reachable: a finite number (InvalidParameter otherwise)."""
    if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)) or not math.isfinite(v):
        raise InvalidParameter(f"{name} must be a finite number, got {v!r}")
    return float(v)


def _bounds(mechanism, free, bounds) -> tuple[float, float]:
    """The scanned interval: the given bounds (within the type's own rules: outside them no value works), or the
    rules' interval; InvalidParameter when it is empty, unbounded, beyond MAGNITUDE or too wide to scan."""
    if bounds is None:
        lo, hi = _rule_interval(mechanism, free, "crank-rocker" if mechanism.FOUR_BAR and not mechanism.CLASS else None)
        if not (math.isfinite(lo) and math.isfinite(hi)):
            side = " and ".join(w for w, v in (("below", lo), ("above", hi)) if not math.isfinite(v))
            raise InvalidParameter(f"give bounds for {free}: the type's rules do not bound it {side}")
        if not lo < hi:
            raise InvalidParameter(f"empty interval for {free}: ({lo:g}, {hi:g})")
        return lo, hi
    try:
        lo, hi = (float(b) for b in bounds)
    except (TypeError, ValueError):
        raise InvalidParameter(f"bounds of {free} must be two numbers (low, high), got {bounds!r}") from None
    if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
        raise InvalidParameter(f"empty interval for {free}: ({lo:g}, {hi:g})")
    if max(abs(lo), abs(hi)) > MAGNITUDE:
        raise InvalidParameter(f"bounds of {free} ({lo:g}, {hi:g}) are out of range: |bound| <= {MAGNITUDE:g}")
    rlo, rhi = _rule_interval(mechanism, free)  # the rules every value must satisfy: nothing works outside
    lo, hi = max(lo, rlo), min(hi, rhi)
    if not lo < hi:
        raise InvalidParameter(
            f"no value of {free} in the bounds {bounds!r} satisfies {type(mechanism).__name__}'s rules "
            f"(they leave {rlo:g}..{rhi:g})"
        )
    size = max((abs(v) for k, v in mechanism.params.items() if k != free and not k.startswith("sigma")), default=0)
    if hi - lo > SPAN * size:
        raise InvalidParameter(
            f"bounds of {free} ({lo:g}, {hi:g}) span more than {SPAN:g} times the mechanism's largest other "
            f"parameter ({size:g}): a scan that coarse steps over whole working intervals; give narrower bounds"
        )
    return lo, hi


def _evaluate(base, free, x):
    """(TR, stroke, gamma_min) of the base mechanism with free = x; nan where it does not work."""
    try:
        m = type(base)(**{**base.params, free: float(x)}, units=base.units)
        d = m.dead_centres()
        if d.reversals != 1:
            return math.nan, math.nan, math.nan
        return m.time_ratio(), m.stroke(), m.gamma_min().value
    except QroptError:
        return math.nan, math.nan, math.nan


def _refine_extreme(r, a, b, is_max):
    sign = -1.0 if is_max else 1.0
    res = minimize_scalar(lambda x: sign * r._tr_at(x), bounds=(a, b), method="bounded", options={"xatol": 1e-13})
    return float(res.x), float(sign * res.fun)


def _inverse(r, a, b, tr):
    fa, fb = r._tr_at(a) - tr, r._tr_at(b) - tr
    if abs(fa) <= 1e-12:
        return a
    if abs(fb) <= 1e-12:
        return b
    return brentq(lambda x: r._tr_at(x) - tr, a, b, xtol=1e-14)


def _edge(base, free, good, bad):
    """Bisection between a working and a failing value of the free parameter (to 1e-13 relative)."""
    for _ in range(200):
        mid = 0.5 * (good + bad)
        if abs(bad - good) <= 1e-13 * max(1.0, abs(good)) or mid in (good, bad):
            break
        if math.isfinite(_evaluate(base, free, mid)[0]):
            good = mid
        else:
            bad = mid
    return good


def reachable(
    mechanism: Mechanism, free: str = "r3", bounds: tuple | None = None, n: int = 301, progress=None
) -> Reachable:
    """TR and stroke reachable by varying ``free`` (the mechanism supplies the other parameters).

    bounds: the parameter's interval (cut to where the type's rules hold: no value works outside; at most SPAN
    times the mechanism's largest other parameter wide); without it the interval the type's rules leave it (e.g.
    its Grashof class; offsets such as e and h take either sign); progress: callable() once per scanned point.
    TR extremes are refined (bounded Brent) and interval ends located by bisection.
    """
    if not isinstance(mechanism, Mechanism):
        raise InvalidParameter(
            f"reachable takes a mechanism (e.g. qropt.examples.paper_mechanism()), got {type(mechanism).__name__}"
        )
    if not isinstance(free, str) or free not in mechanism.params or free.startswith("sigma"):
        raise InvalidParameter(f"{type(mechanism).__name__} has no continuous parameter {free!r}")
    if isinstance(n, bool) or not isinstance(n, int) or not 3 <= n <= 100_000:
        raise InvalidParameter(f"n (scan points) must be an integer in [3, 100000], got {n!r}")
    lo, hi = _bounds(mechanism, free, bounds)
    grid = np.linspace(lo, hi, n)
    tick = progress if callable(progress) else (lambda k=1: None)
    vals = np.array([(_evaluate(mechanism, free, x), tick())[0] for x in grid])
    ok = np.isfinite(vals[:, 0])
    intervals = []
    i = 0
    while i < n:
        if ok[i]:
            j = i
            while j + 1 < n and ok[j + 1]:
                j += 1
            a = grid[i] if i == 0 else _edge(mechanism, free, grid[i], grid[i - 1])
            b = grid[j] if j == n - 1 else _edge(mechanism, free, grid[j], grid[j + 1])
            intervals.append((float(a), float(b)))
            i = j + 1
        else:
            i += 1
    grid = np.unique(np.concatenate([grid, [x for iv in intervals for x in iv]]))
    vals = np.array([_evaluate(mechanism, free, x) for x in grid])
    tr, stroke = vals[:, 0], vals[:, 1]
    r = Reachable(mechanism, free, intervals, grid, tr, stroke, (), ())
    ext = []
    for k in np.flatnonzero(np.isfinite(tr)):
        ext.append((float(tr[k]), float(grid[k])))
        inner = 0 < k < len(grid) - 1 and np.isfinite(tr[k - 1]) and np.isfinite(tr[k + 1])
        if inner and (tr[k] <= min(tr[k - 1], tr[k + 1]) or tr[k] >= max(tr[k - 1], tr[k + 1])):
            x, v = _refine_extreme(r, grid[k - 1], grid[k + 1], tr[k] >= tr[k - 1])
            ext.append((v, x))
    if not ext:
        raise InvalidParameter(f"no value of {free} in ({lo:g}, {hi:g}) gives a working {type(mechanism).__name__}")
    (tmin, xmin), (tmax, xmax) = min(ext), max(ext)
    r.time_ratio_range = Range(tmin, xmin, tmax, xmax)
    ok = np.flatnonzero(np.isfinite(stroke))
    i, j = ok[np.argmin(stroke[ok])], ok[np.argmax(stroke[ok])]
    r.stroke_range = Range(float(stroke[i]), float(grid[i]), float(stroke[j]), float(grid[j]))
    return r
