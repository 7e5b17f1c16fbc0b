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
    return _least_transmission(lambda th: _transmissions(kind, p, th))


def _least_transmission(angles) -> float:
    """The smallest of every joint's transmission angle (``angles(th)``: joint -> array) over the turn: each
    joint's grid minimum refined by bounded Brent in the neighbouring cells; pi/2 without a joint."""
    best = np.pi / 2
    h = 2 * np.pi / N
    for name, g in angles(TH).items():
        i = int(np.argmin(g))
        r = minimize_scalar(
            lambda t, n=name: float(angles(np.array([t]))[n][0]),
            bounds=(TH[i] - h, TH[i] + h),
            method="bounded",
            options={"xatol": 1e-13},
        )
        best = min(best, float(r.fun), float(g[i]))
    return best


# ---- the two six-bar types, from scratch ------------------------------------------------------------------------
# Coupler slider: B from the triangle O4-A-B (the cosine law at O4, sigma = sign((A - O4) x (B - O4))); the coupler
# point P by rotating the unit vector A->B by beta; D from the rod's right triangle on y = h. Slot-ram shaper: the
# ram's pin D where the line O4-A meets y = -r1 + h, by similar triangles. Everything complex-safe (complex step).


def sixbar_joints(kind, p, th):
    """Joint coordinates of a coupler slider or a slot-ram shaper at crank angles th (complex-safe)."""
    ax, ay = p["r2"] * np.cos(th), p["r2"] * np.sin(th)
    if kind == "slot-ram-shaper":
        o4y = -p["r1"]
        t = p["h"] / (ay - o4y)  # D = O4 + t (A - O4) on y = o4y + h
        return {"A": (ax, ay), "O4": (0.0 + 0 * th, o4y + 0 * th), "D": (t * ax, o4y + p["h"] + 0 * th)}
    r1, r3, r4 = p["r1"], p["r3"], p["r4"]
    vx, vy = ax - r1, ay  # O4 -> A
    d = np.sqrt(vx * vx + vy * vy)
    c = (r4 * r4 + d * d - r3 * r3) / (2 * r4 * d)  # cosine of the angle at O4 between O4->A and O4->B
    s = p["sigma"] * np.sqrt(1 - c * c)
    bx, by = r1 + r4 * (c * vx - s * vy) / d, r4 * (s * vx + c * vy) / d
    ux, uy = (bx - ax) / r3, (by - ay) / r3
    cb, sb = np.cos(p["beta"]), np.sin(p["beta"])
    px, py = ax + p["r5"] * (ux * cb - uy * sb), ay + p["r5"] * (ux * sb + uy * cb)
    h = p.get("h", 0.0)
    dx = px + p.get("sigma_slider", 1.0) * np.sqrt(p["r6"] ** 2 - (h - py) ** 2)
    return {"A": (ax, ay), "B": (bx, by), "O4": (r1 + 0 * th, 0 * th), "P": (px, py), "D": (dx, h + 0 * th)}


def sixbar_x(kind, p, th):
    return sixbar_joints(kind, p, th)["D"][0]


def sixbar_transmissions(kind, p, th):
    """Transmission angles (rad) at each transmitting joint (the block at A of the slot-ram shaper is 90 degrees)."""
    j = sixbar_joints(kind, p, th)
    if kind == "slot-ram-shaper":  # the lever O4->A against the slide line (x)
        lx, ly = j["A"][0] - j["O4"][0], j["A"][1] - j["O4"][1]
        return {"D": np.arctan2(np.abs(ly), np.abs(lx))}
    (ax, ay), (bx, by), (px, py), (dx, dy) = j["A"], j["B"], j["P"], j["D"]
    ux, uy, wx, wy = ax - bx, ay - by, p["r1"] - bx, -by
    return {
        "B": np.arctan2(np.abs(ux * wy - uy * wx), np.abs(ux * wx + uy * wy)),
        "D": np.arctan2(np.abs(dx - px), np.abs(dy - py)),
    }


def sixbar_reversals(kind, p, n=N):
    """Local maxima of x over a turn on an n-point grid."""
    x = sixbar_x(kind, p, 2 * np.pi * np.arange(n) / n)
    return int(np.count_nonzero((x > np.roll(x, 1)) & (x >= np.roll(x, -1))))


def sixbar_cycle(kind, p):
    """(theta_max, theta_min, x_max, x_min, TR, stroke, gamma_min) by dense sampling (N points) refined by brentq on
    the complex-step dx/dtheta2 (dead centres) and bounded Brent (transmission minima)."""
    x = sixbar_x(kind, p, TH)
    h = 2 * np.pi / N

    def dx(t):
        return float(np.imag(sixbar_x(kind, p, t + 1j * STEP)) / STEP)

    ext = []
    for pick in (np.argmax, np.argmin):
        i = int(pick(x))
        t = brentq(dx, TH[i] - h, TH[i] + h, xtol=1e-15)
        ext.append((t % (2 * np.pi), float(sixbar_x(kind, p, t))))
    (t_max, x_max), (t_min, x_min) = ext
    best = _least_transmission(lambda th: sixbar_transmissions(kind, p, th))
    return t_max, t_min, x_max, x_min, time_ratio(t_max, t_min), x_max - x_min, best


SIXBARS = ("coupler-slider", "slot-ram-shaper")  # simulated by sixbar_*, the others by joints()


def task_values(kind, p):
    """(TR, stroke, gamma_min rad) of a design of any simulated type: a six-bar by its own simulation."""
    if kind in SIXBARS:
        return sixbar_cycle(kind, p)[4:]
    t_max, t_min, x_max, x_min = dead_centres(kind, p)
    return time_ratio(t_max, t_min), x_max - x_min, gamma_min(kind, p)


def sixbar_motion(kind, p, th, omega2=1.0, step=1e-3):
    """x, v, a at crank angles th for a constant omega2 by central finite differences (Richardson-extrapolated,
    O(step^4)); truncation ~ step^4 x^(6) and rounding ~ 1e-16 x / step^2: ~1e-11 for v, ~1e-8 for a at 1e-3."""
    th = np.asarray(th, float)

    def f(t):
        return sixbar_x(kind, p, t)

    def d1(k):
        return (f(th + k) - f(th - k)) / (2 * k)

    def d2(k):
        return (f(th + k) - 2 * f(th) + f(th - k)) / k**2

    v = (4 * d1(step / 2) - d1(step)) / 3
    a = (4 * d2(step / 2) - d2(step)) / 3
    return f(th), v * omega2, a * omega2**2
