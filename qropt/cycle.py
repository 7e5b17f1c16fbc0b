"""Exact extremes of smooth functions of the crank angle over a full turn.

A function is given as ``fun(theta2) -> Jet`` (value, d/dtheta2, d2/dtheta2^2).
Stationary points are bracketed on a uniform grid by sign changes of the first
derivative and refined by a vectorised, bisection-safeguarded Newton iteration
to machine precision.
"""

from __future__ import annotations

import numpy as np

from qropt.ops import Jet

TWO_PI = 2.0 * np.pi
GRID = 720


def grid(n: int = GRID) -> np.ndarray:
    """n crank angles 0, 2pi/n, ... (radians), including 0 and pi for even n."""
    return TWO_PI * np.arange(n) / n


def jet_of(fun, theta):
    """fun evaluated on the jet seeded at theta, broadcast to theta's shape."""
    j = fun(Jet.seed(theta))
    if not isinstance(j, Jet):
        j = Jet(np.asarray(j, float), 0.0, 0.0)
    return Jet(*(np.broadcast_to(c, np.shape(theta)) for c in (j.v, j.d1, j.d2)))


def brackets(theta, d1, kind):
    """Cells [theta_i, theta_i+1] (cyclic) where d1 changes sign: kind 'max' (+ to -) or 'min' (- to +)."""
    n = theta.size
    pos = d1 >= 0
    nxt = np.roll(pos, -1)
    hit = (pos & ~nxt) if kind == "max" else (~pos & nxt)
    hit &= np.isfinite(d1) & np.isfinite(np.roll(d1, -1))
    i = np.flatnonzero(hit)
    lo = theta[i]
    hi = np.where(i + 1 < n, theta[(i + 1) % n], theta[0] + TWO_PI)
    return lo, hi


def stationary(fun, lo, hi, iters: int = 100):
    """Refine the stationary points of fun bracketed in [lo, hi] (arrays). Returns theta2 arrays."""
    lo, hi = np.array(lo, float), np.array(hi, float)
    if lo.size == 0:
        return lo
    glo = jet_of(fun, lo).d1
    x = 0.5 * (lo + hi)
    for _ in range(iters):
        j = jet_of(fun, x)
        g, h = j.d1, j.d2
        same = np.sign(g) == np.sign(glo)
        lo, glo = np.where(same, x, lo), np.where(same, g, glo)
        hi = np.where(same, hi, x)
        with np.errstate(divide="ignore", invalid="ignore"):
            xn = x - g / h
        bad = ~np.isfinite(xn) | (xn <= lo) | (xn >= hi)
        xn = np.where(bad, 0.5 * (lo + hi), xn)
        xn = np.where(g == 0.0, x, xn)
        done = np.abs(xn - x) <= 4.0 * np.finfo(float).eps * np.maximum(1.0, np.abs(x))
        x = xn
        if done.all():
            break
    return x


def extremes(fun, kind, n: int = GRID):
    """All local maxima or minima of fun over a turn: (theta2 in [0, 2pi), values)."""
    theta = grid(n)
    lo, hi = brackets(theta, jet_of(fun, theta).d1, kind)
    t = wrap(stationary(fun, lo, hi))
    return t, jet_of(fun, t).v


def wrap(theta):
    """Crank angles reduced to [0, 2pi), with values within 1e-12 of 2pi sent to 0."""
    t = np.mod(theta, TWO_PI)
    return np.where(t > TWO_PI - 1e-12, 0.0, t)


def minimum(fun, n: int = GRID):
    """The global minimum of fun over a turn: (theta2, value); nan, nan if fun has no minimum."""
    t, v = extremes(fun, "min", n)
    ok = np.isfinite(v)
    if not ok.any():
        return float("nan"), float("nan")
    k = np.flatnonzero(ok)[np.argmin(v[ok])]
    return float(t[k]), float(v[k])


def negative_intervals(margin, n: int = 3600):
    """Crank-angle intervals (radians, lo < hi, possibly past 2pi) where the numpy function margin < 0."""
    from scipy.optimize import brentq

    theta = grid(n)
    with np.errstate(invalid="ignore"):
        m = margin(theta)
    bad = m < 0
    if not bad.any():
        return []
    if bad.all():
        return [(0.0, TWO_PI)]
    start = int(np.flatnonzero(~bad)[0])
    order = (np.arange(n) + start) % n
    out, i = [], 0
    b = bad[order]
    while i < n:
        if b[i]:
            j = i
            while j + 1 < n and b[j + 1]:
                j += 1
            t0, t1 = theta[order[i]], theta[order[j]]
            prev, nxt = t0 - TWO_PI / n, t1 + TWO_PI / n

            def f(t):
                with np.errstate(invalid="ignore"):
                    return float(margin(np.array([t]))[0])

            lo = brentq(f, prev, t0, xtol=1e-14) if np.isfinite(f(prev)) else t0
            hi = brentq(f, t1, nxt, xtol=1e-14) if np.isfinite(f(nxt)) else t1
            if hi < lo:
                hi += TWO_PI
            out.append((float(np.mod(lo, TWO_PI)), float(np.mod(lo, TWO_PI) + (hi - lo))))
            i = j + 1
        else:
            i += 1
    return out
