"""Independent brute-force kinematics for the tests: plain Cartesian formulas, no qropt code.

Positions are written with complex-safe operations only, so the exact derivative
d x / d theta2 comes from the complex step; dead centres are its roots found by
brentq in the cells of a dense grid where it changes sign.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import brentq, minimize_scalar

N = 20000
TH = 2 * np.pi * np.arange(N) / N
STEP = 1e-30


def _rrr(px, py, a, qx, qy, b, sigma):
    ux, uy = px - qx, py - qy
    ll = np.sqrt(ux * ux + uy * uy)
    c = (b * b + ll * ll - a * a) / (2 * b * ll)
    s = np.sqrt(1 - c * c)
    ex, ey = ux / ll, uy / ll
    return qx + b * (c * ex - sigma * s * ey), qy + b * (c * ey + sigma * s * ex)


def joints(kind, p, th):
    """Joint coordinates of a mechanism (complex-safe in th). Returns dict and the output pin pair."""
    ax, ay = p["r2"] * np.cos(th), p["r2"] * np.sin(th)
    out = {"A": (ax, ay)}
    if kind == "slider-crank":
        dy = p["e"] - ay
        out["D"] = (ax + p["sigma_slider"] * np.sqrt(p["r3"] ** 2 - dy * dy), p["e"] + 0 * th)
        out["pin"] = out["A"]
        out["rod"] = p["r3"]
        return out
    if kind in ("crank-shaper", "whitworth"):
        o4 = (0.0, -p["r1"])
        ux, uy = ax - o4[0], ay - o4[1]
        ll = np.sqrt(ux * ux + uy * uy)
        arm = p["r4"] if kind == "crank-shaper" else p["r5"]
        cx, cy = o4[0] + arm * ux / ll, o4[1] + arm * uy / ll
        out["C"] = (cx, cy)
        if p.get("r6") is None:
            out["D"] = (cx, cy)
            return out
        line = -p["r1"] + p.get("h", 0.0)
        out["D"] = (cx + p["sigma_slider"] * np.sqrt(p["r6"] ** 2 - (line - cy) ** 2), line + 0 * th)
        out["pin"], out["rod"] = out["C"], p["r6"]
        return out
    bx, by = _rrr(ax, ay, p["r3"], p["r1"], 0.0, p["r4"], p["sigma"])
    out["B"] = (bx, by)
    if kind == "four-bar":
        return out
    cx, cy = p["r1"] + p["r5"] * (bx - p["r1"]) / p["r4"], p["r5"] * by / p["r4"]
    out["C"] = (cx, cy)
    out["D"] = (cx + p["sigma_slider"] * np.sqrt(p["r6"] ** 2 - (p["h"] - cy) ** 2), p["h"] + 0 * th)
    out["pin"], out["rod"] = out["C"], p["r6"]
    return out


def output(kind, p, th):
    """Slider x (or, for the four-bar, the crank-coupler cross product whose roots are the rocker limits)."""
    j = joints(kind, p, th)
    if kind == "four-bar":
        (ax, ay), (bx, by) = j["A"], j["B"]
        return ax * (by - ay) - ay * (bx - ax)
    return j["D"][0]


def _dx(kind, p, t):
    return float(np.imag(output(kind, p, t + 1j * STEP)) / STEP)


def dead_centres(kind, p):
    """(theta_max, theta_min, x_max, x_min) by grid + brentq on the complex-step derivative."""
    if kind == "four-bar":
        g = output(kind, p, TH)
        cells = np.flatnonzero(np.sign(g) != np.sign(np.roll(g, -1)))
        roots = [brentq(lambda t: float(output(kind, p, t)), TH[i], TH[i] + 2 * np.pi / N, xtol=1e-15) for i in cells]
        bx, by = (np.real(v) for v in joints(kind, p, np.array(roots))["B"])
        th4 = np.pi + np.arctan2(-by, p["r1"] - bx)
        i, k = int(np.argmax(th4)), int(np.argmin(th4))
        return roots[i] % (2 * np.pi), roots[k] % (2 * np.pi), th4[i], th4[k]
    x = output(kind, p, TH)
    best = []
    for pick in (np.argmax, np.argmin):
        i = int(pick(x))
        lo, hi = TH[i] - 2 * np.pi / N, TH[i] + 2 * np.pi / N
        t = brentq(lambda t: _dx(kind, p, t), lo, hi, xtol=1e-15)
        best.append((t % (2 * np.pi), float(output(kind, p, t))))
    return best[0][0], best[1][0], best[0][1], best[1][1]


def time_ratio(theta_max, theta_min):
    a = (theta_min - theta_max) % (2 * np.pi)
    return max(a, 2 * np.pi - a) / min(a, 2 * np.pi - a)


def _transmissions(kind, p, th):
    j = joints(kind, p, th)
    out = {}
    if "B" in j:
        (ax, ay), (bx, by) = j["A"], j["B"]
        ux, uy, wx, wy = ax - bx, ay - by, p["r1"] - bx, -by
        out["B"] = np.arctan2(np.abs(ux * wy - uy * wx), np.abs(ux * wx + uy * wy))
    if "pin" in j:
        (cx, cy), (dx, dy) = j["pin"], j["D"]
        out["D"] = np.arctan2(np.abs(dx - cx), np.abs(dy - cy))
    return out


def gamma_min(kind, p):
    """Smallest transmission angle: grid minimum refined by bounded Brent in the neighbouring cells."""
    best = np.pi / 2
    for name in _transmissions(kind, p, TH[:1]):
        g = _transmissions(kind, p, TH)[name]
        i = int(np.argmin(g))
        h = 2 * np.pi / N
        r = minimize_scalar(
            lambda t, n=name: float(_transmissions(kind, p, np.array([t]))[n][0]),
            bounds=(TH[i] - h, TH[i] + h),
            method="bounded",
            options={"xatol": 1e-13},
        )
        best = min(best, float(r.fun), float(g[i]))
    return best
