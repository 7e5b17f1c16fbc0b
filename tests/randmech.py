"""Seeded random valid mechanisms of every type (rejection sampling through the public constructors)."""

from __future__ import annotations

import numpy as np

import qropt
from tests.brute import SIXBARS  # drawn too (their brute force is sixbar_*)

KINDS = ("slider-crank", "crank-shaper", "whitworth", "crank-rocker-slider", "drag-link-slider", "four-bar")


def _draw(kind, rng):
    u = rng.uniform
    if kind == "slider-crank":
        r2 = u(0.05, 1.0)
        e = u(-1.5, 1.5) * r2
        return {"r2": r2, "e": e, "r3": (r2 + abs(e)) * u(1.02, 4.0), "sigma_slider": rng.choice([-1.0, 1.0])}
    if kind == "crank-shaper":
        r1 = u(0.2, 1.0)
        p = {"r1": r1, "r2": r1 * u(0.05, 0.95), "r4": r1 * u(1.0, 3.0)}
        if rng.random() < 0.5:
            p.update(r6=p["r4"] * u(0.3, 2.0), h=p["r4"] * u(0.6, 1.2), sigma_slider=rng.choice([-1.0, 1.0]))
        return p
    if kind == "whitworth":
        r1 = u(0.05, 0.5)
        r5 = u(0.1, 1.0)
        return {
            "r1": r1,
            "r2": r1 * u(1.05, 4.0),
            "r5": r5,
            "r6": r5 * u(1.1, 3.0),
            "h": u(-0.1, 0.1) * r5,
            "sigma_slider": rng.choice([-1.0, 1.0]),
        }
    if kind == "slot-ram-shaper":
        r1 = u(0.1, 1.0)
        return {"r1": r1, "r2": r1 * u(0.05, 0.9), "h": r1 * u(0.1, 3.0)}
    r = u(0.1, 1.0, size=4)
    if kind == "coupler-slider":  # a crank-rocker or a drag-link four-bar, a coupler point, a long rod
        r[int(rng.random() < 0.5)] = r.min() * u(0.3, 0.95)
        return {
            "r1": r[0],
            "r2": r[1],
            "r3": r[2],
            "r4": r[3],
            "r5": u(0.2, 1.2) * r[2],
            "beta": u(-np.pi, np.pi),
            "r6": u(2.0, 4.0),
            "h": u(-0.5, 0.5),
            "sigma": rng.choice([-1.0, 1.0]),
            "sigma_slider": rng.choice([-1.0, 1.0]),
        }
    if kind in ("crank-rocker-slider", "four-bar"):
        r[1] = r.min() * u(0.3, 0.99)
    else:
        r[0] = r.min() * u(0.3, 0.99)
    p = {"r1": r[0], "r2": r[1], "r3": r[2], "r4": r[3], "sigma": rng.choice([-1.0, 1.0])}
    if kind != "four-bar":
        p.update(r5=u(0.2, 1.5) * r[3], r6=u(0.5, 3.0), h=u(-0.5, 0.5), sigma_slider=rng.choice([-1.0, 1.0]))
    return p


def _one_reversal(kind, p):
    """True if the brute-force output rises once and falls once per turn (a proper quick-return)."""
    from tests import brute

    if kind in SIXBARS:
        return brute.sixbar_reversals(kind, p) == 1
    if kind == "four-bar":
        g = brute.output(kind, p, brute.TH)
        return int(np.count_nonzero(np.sign(g) != np.sign(np.roll(g, -1)))) == 2
    x = brute.output(kind, p, brute.TH)
    d = np.sign(np.roll(x, -1) - x)
    return int(np.count_nonzero(d != np.roll(d, -1))) == 2


def random_mechanisms(kind, n, seed=0):
    """n valid mechanisms of a kind: list of (params, mechanism)."""
    rng = np.random.default_rng(seed)
    cls = qropt.mechanism_type(kind)
    out = []
    while len(out) < n:
        p = _draw(kind, rng)
        try:
            m = cls(**p)
        except qropt.QroptError:
            continue
        if m.assembly_failures():
            continue
        full = {**m.params}
        g = m.grashof() if hasattr(m, "grashof") else None
        if g is not None and g.kind == "change-point":
            continue
        if not _one_reversal(kind, full):
            continue
        out.append((full, m))
    return out
