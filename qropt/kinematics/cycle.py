"""Crank-angle grids and the safeguarded refinement of stationary points over a full turn.

A function is given as ``fun(theta2) -> Jet`` (value, d/dtheta2, d2/dtheta2^2). ``stationary`` refines
stationary points bracketed in given cells to machine precision by a vectorised Newton iteration,
safeguarded by false position inside the bracket (the compiled kernel's fallback); ``negative_intervals``
finds where an assembly margin is negative.
"""

from __future__ import annotations

import functools

import numpy as np

from qropt.kinematics.ops import Jet

TWO_PI = 2.0 * np.pi
GRID = 720
GRIDS = (180, 720, 2880)  # grids tried in turn for the compiled analysis (the first that resolves)
MARGIN_TOL = 1e-12  # an assembly margin this far below zero is rounding (a change point), not a failure
DWELL = 1e-5  # an output that turns back inside a stroke by less than this part of its travel dwells there


@functools.lru_cache(maxsize=16)
def _grid(n: int) -> np.ndarray:
    g = TWO_PI * np.arange(n) / n
    g.flags.writeable = False
    return g


def grid(n: int = GRID) -> np.ndarray:
    """n crank angles 0, 2pi/n, ... (radians), including 0 and pi for even n (a read-only array)."""
    return _grid(n)


def jet_of(fun, theta):
    """fun evaluated on the jet seeded at theta, broadcast to theta's shape."""
    j = fun(Jet.seed(theta))
    if not isinstance(j, Jet):
        return Jet.of(np.broadcast_to(np.asarray(j, float), np.shape(theta)), 0.0, 0.0)
    return Jet(np.broadcast_to(j.c, (3,) + np.shape(theta)))


def stationary(fun, lo, hi, iters: int = 100, xtol: float = 0.0):
    """Refine the stationary points of fun bracketed in [lo, hi] (arrays). Returns theta2 arrays.

    Stops where the Newton step falls below 4 ulp (or xtol, for derivatives that carry noise).
    """
    lo, hi = np.array(lo, float), np.array(hi, float)
    if lo.size == 0:
        return lo
    glo, ghi = jet_of(fun, lo).d1, jet_of(fun, hi).d1
    x = 0.5 * (lo + hi)
    eps = 4.0 * np.finfo(float).eps
    for _ in range(iters):
        j = jet_of(fun, x)
        g, h = j.d1, j.d2
        with np.errstate(divide="ignore", invalid="ignore"):
            step = g / h
        done = (g == 0.0) | (np.abs(step) <= np.maximum(xtol, eps * np.maximum(1.0, np.abs(x))))
        if done.all():
            break
        same = np.sign(g) == np.sign(glo)
        lo, glo = np.where(same, x, lo), np.where(same, g, glo)
        hi, ghi = np.where(same, hi, x), np.where(same, ghi, g)
        xn = x - step
        with np.errstate(divide="ignore", invalid="ignore"):
            xf = lo - glo * (hi - lo) / (ghi - glo)  # false position: lands on a root at a bracket end
        xf = np.where(np.isfinite(xf) & (xf >= lo) & (xf <= hi), xf, 0.5 * (lo + hi))
        bad = ~np.isfinite(xn) | (xn <= lo) | (xn >= hi)
        x = np.where(done, x, np.where(bad, xf, xn))
    return x


def negative_intervals(margin, n: int = 3600):
    """Crank-angle intervals (radians, lo < hi, possibly past 2pi) where the numpy function margin < -MARGIN_TOL."""
    from scipy.optimize import brentq

    theta = grid(n)
    with np.errstate(invalid="ignore"):
        m = margin(theta)
    bad = m < -MARGIN_TOL
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
                    return float(margin(np.array([t]))[0]) + MARGIN_TOL

            lo = brentq(f, prev, t0, xtol=1e-14) if np.isfinite(f(prev)) else t0
            hi = brentq(f, t1, nxt, xtol=1e-14) if np.isfinite(f(nxt)) else t1
            if hi < lo:
                hi += TWO_PI
            out.append((float(np.mod(lo, TWO_PI)), float(np.mod(lo, TWO_PI) + (hi - lo))))
            i = j + 1
        else:
            i += 1
    return out


def dwells(tmax, xmax, tmin, xmin):
    """The output's local maxima and minima (crank angles rad, values) without its dwells: a maximum and the
    minimum next to it that differ by less than DWELL of the travel, both strictly inside it (neither within that
    of the largest or the least value), are a turn back of the output inside a stroke too small to be a reversal
    (an optimum whose velocity touches zero mid-stroke ends on either side of it by about 1e-6 of the stroke). A
    pair at an end of the travel is kept: it moves the dead centre. Maxima and minima that do not alternate
    around the turn are returned as they are."""
    if tmax.size < 2 or tmax.size != tmin.size:
        return tmax, xmax, tmin, xmin
    points = sorted(
        [(t, x, 1, i) for i, (t, x) in enumerate(zip(tmax.tolist(), xmax.tolist(), strict=True))]
        + [(t, x, -1, i) for i, (t, x) in enumerate(zip(tmin.tolist(), xmin.tolist(), strict=True))]
    )
    if any(a[2] == b[2] for a, b in zip(points, points[1:] + points[:1], strict=True)):
        return tmax, xmax, tmin, xmin
    top, bottom = max(xmax.tolist()), min(xmin.tolist())
    tol = DWELL * (top - bottom)
    merged = True
    while merged and len(points) > 2:
        merged = False
        for i in range(len(points)):
            a, b = points[i], points[(i + 1) % len(points)]
            hi, lo = max(a[1], b[1]), min(a[1], b[1])
            if hi - lo < tol and hi < top - tol and lo > bottom + tol:
                points = [q for k, q in enumerate(points) if k not in (i, (i + 1) % len(points))]
                merged = True
                break
    if len(points) == tmax.size + tmin.size:
        return tmax, xmax, tmin, xmin
    keep_max, keep_min = np.zeros(tmax.size, bool), np.zeros(tmin.size, bool)  # the kept ones, in their order
    for *_, kind, i in points:
        (keep_max if kind == 1 else keep_min)[i] = True
    return tmax[keep_max], xmax[keep_max], tmin[keep_min], xmin[keep_min]
