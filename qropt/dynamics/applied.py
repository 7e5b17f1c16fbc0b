"""General loads at crank angles: where each ``Force`` and ``Torque`` of a ``Loads`` acts, on which body, with what
force vector (N) and torque (N m), and the velocity of its point (what the inverse dynamics and the generalised
load ``Q`` read). SI units: points in metres, the ram's position for windows and tables in the mechanism's unit.

A joint's load acts on the body that carries the joint (``carrier``): the output body (the ram, the yoke) for the
output's joint, else the first body in the linkage's order whose joints include it (the crank-pin block aside).
A force at "ram" (``RAM``) is at the output's joint, whatever the type names it (C or D), unless the type has a
joint of that name.
"""

from __future__ import annotations

import dataclasses
from typing import NamedTuple

import numpy as np
from scipy.optimize import brentq

from qropt.dynamics.model import TWO_PI, Force, Loads, level
from qropt.dynamics.rigid import body_motion, frame
from qropt.errors import InvalidParameter

AT_REST = 1e-9  # a point is at rest where its speed is below this times |omega2| times the mechanism's size
RAM = "ram"  # a force's joint that names the output's, in every type
EDGE_GRID = 720  # crank angles where the ram's crossings of a window's or a table's x are bracketed


class Applied(NamedTuple):
    """One load at n crank angles: the body it acts on, its point (x, y) (m), the point's velocity (x, y) (m/s or m
    per unit crank angle, as the joints' rates), the force (fx, fy) (N), the torque (N m) and the body's angular
    velocity (rad/s or per unit crank angle)."""

    body: str
    point: tuple
    velocity: tuple
    force: tuple
    torque: object
    spin: object


def joints_of(link) -> list[str]:
    return sorted({j for b in link.bodies() for j in b.joints})


def carrier(m, link, joint: str) -> str:
    """The body that carries ``joint`` (see the module); InvalidParameter naming the joints for an unknown one."""
    bodies = link.bodies()
    if joint == m.output_joint():
        out = next((b.name for b in bodies if b.kind in ("ram", "yoke")), None)
        if out is not None:
            return out
    for b in bodies:
        if b.kind != "block" and joint in b.joints:
            return b.name
    raise InvalidParameter(f"{type(m).__name__} has no joint {joint!r}; its joints: {joints_of(link)}")


def resolve(m, s, link, loads: Loads) -> list[tuple]:
    """Each force and torque with the body it acts on, checked against the mechanism: (load, body), a force at
    ``RAM`` given the output's joint. InvalidParameter naming the load for an unknown joint or body, a body the
    system does not hold (a massless block), a torque on the ram (it does not turn) or a window or table on the
    ram's position without a ram."""
    names = [b.name for b in link.bodies()]
    held = {b.name for b in s.bodies}
    out = []
    for load in (*loads.forces, *loads.torques):
        if isinstance(load, Force) and load.at == RAM and RAM not in joints_of(link):
            if m.output_joint() is None:
                raise InvalidParameter(f"{load}: {type(m).__name__} has no ram; its joints: {joints_of(link)}")
            load = dataclasses.replace(load, at=m.output_joint())
        at = load.at if isinstance(load, Force) else (load.on,)
        if isinstance(load, Force) and isinstance(at, str):
            try:
                body = carrier(m, link, at)
            except InvalidParameter as e:
                raise InvalidParameter(f"{load}: {e}") from None
        else:
            body = at[0]
            if body not in names:
                raise InvalidParameter(f"{load}: {type(m).__name__} has no body {body!r}; its bodies: {names}")
        if body not in held:
            raise InvalidParameter(
                f"{load}: the {body} is massless and passes its force straight on; give it a mass to load it "
                "(Masses(block=...))"
            )
        if not isinstance(load, Force) and s.kind(body) == "ram":
            raise InvalidParameter(f"{load}: the ram does not turn (its guide carries a torque on it)")
        table = isinstance(load.magnitude, tuple) and load.against == "x"
        if (table or load.window.x is not None) and m.output_joint() is None:
            raise InvalidParameter(f"{load}: {type(m).__name__} has no ram: no window or table on its position x")
        out.append((load, body))
    return out


def evaluate(m, s, resolved, pts, t, working, x, sense: float, rate: float, ends=None) -> list[Applied]:
    """The resolved loads (``resolve``) at crank angles t (rad): ``pts`` joint -> ((x, x', x''), (y, y', y''))
    in metres with the rates of the actual motion (or per unit crank angle), ``working`` (bool, on the working
    stroke; None where no load needs it), x the ram's positions (the mechanism's unit; None without a ram),
    ``sense``: the sign that turns the rates into the motion's direction (1 for the actual motion's rates, the sense
    of rotation for rates per unit crank angle), ``rate``: |omega2| (rad/s), or 1 per unit crank angle; ``ends``:
    the way (+1 or -1 along x) the output moves at each angle where its stroke is given (a stroke closed at its
    dead centres), which a force against the output's velocity resists where the output is at rest, or None.
    ``geometry`` and then ``act``."""
    size = max(float(np.max(np.hypot(px[0], py[0]))) for px, py in pts.values())
    return act(s, resolved, geometry(s, resolved, pts), t, working, x, sense, rest(size, rate), ends)


def rest(size: float, rate: float) -> float:
    """The speed (m/s, or m per unit crank angle) below which a point is at rest, for a mechanism whose joints lie
    within ``size`` (m) of the origin at crank speed ``rate``."""
    return AT_REST * rate * max(size, 1e-300)


def geometry(s, resolved, pts, coords=None) -> list[tuple]:
    """Each resolved load's point (x, y) (m), the point's velocity (x, y) and its body's angular velocity, from the
    joints' triples ``pts``: numbers, arrays or CasADi expressions alike (the compiled dynamics computes them in its
    kernel). A torque's point is its body's origin, its velocity zero. ``coords``: per load, the body point's
    (x, y) in its frame to use instead of the load's own (the kernel's inputs), or None."""
    bodies = {b.name: b for b in s.bodies}
    out = []
    for i, (load, name) in enumerate(resolved):
        b = bodies[name]
        (ox, oy), rot = frame(b, pts)
        spin = rot[2]
        if not isinstance(load, Force):
            out.append(((ox[0], oy[0]), (0.0, 0.0), spin))
        elif isinstance(load.at, str):
            px, py = pts[load.at][0][0], pts[load.at][1][0]
            out.append(((px, py), (ox[1] - spin * (py - oy[0]), oy[1] + spin * (px - ox[0])), spin))
        else:
            p, v, _, _ = body_motion(b, load.at[1:] if coords is None else coords[i], pts)
            out.append((p, v, spin))
    return out


def act(s, resolved, geo, t, working, x, sense: float, still: float, ends=None) -> list[Applied]:
    """The resolved loads at crank angles t from their ``geometry`` (numpy, arrays or numbers): each one's amount
    (its magnitude or table times its window) and its force's direction; ``still``: the speed below which a point
    is at rest (``rest``); the other arguments as ``evaluate``'s."""
    out = []
    for (load, name), ((px, py), (vx, vy), spin) in zip(resolved, geo, strict=True):
        arg = x if load.against == "x" else np.mod(t, TWO_PI)
        amount = level(load.magnitude, arg) * load.window.active(t, working, x)
        if not isinstance(load, Force):
            zero = np.zeros(t.shape)
            out.append(Applied(name, (px + zero, py + zero), (zero, zero), (zero, zero), amount, spin))
            continue
        px, py, vx, vy = (_full(v, t.shape) for v in (px, py, vx, vy))
        d = load.direction
        if d == "against":
            speed = np.hypot(vx, vy)
            moving = speed > still
            inv = np.divide(-sense, speed, out=np.zeros(t.shape), where=moving)  # 0 at rest
            fx, fy = amount * vx * inv, amount * vy * inv
            if ends is not None and s.kind(name) in ("ram", "yoke"):  # at a dead centre: the limit along its stroke
                fx = np.where(moving, fx, -amount * ends)
        elif d == "slide":
            fx, fy = amount, np.zeros(t.shape)
        else:
            n = float(np.hypot(*d))
            fx, fy = amount * (d[0] / n), amount * (d[1] / n)
        out.append(Applied(name, (px, py), (vx, vy), (fx, fy), 0.0, spin))
    return out


def _full(v, shape):
    """v as an array of the given shape (itself where it is one)."""
    return v if getattr(v, "shape", None) == shape else np.broadcast_to(v, shape)


def rows(s, ap: Applied, centre) -> list[tuple]:
    """What a load takes off the Newton-Euler system's right-hand side (known external loads leave it), as
    (row, value): its force (fx, fy) on its body's x and y rows and its moment about the body's centre of mass
    ``centre`` (x, y) (m), (p - G) x F plus its torque, on the moment row (a point ram has none)."""
    r = s.rows[ap.body]
    (fx, fy), (px, py) = ap.force, ap.point
    if s.kind(ap.body) == "ram":
        return [(r, fx), (r + 1, fy)]
    return [(r, fx), (r + 1, fy), (r + 2, (px - centre[0]) * fy - (py - centre[1]) * fx + ap.torque)]


def edges(m, loads: Loads) -> list[float]:
    """The crank angles (rad, in [0, 2 pi)) where a force's or torque's window opens or closes, or its table
    turns a corner: the ends of theta2 windows and the theta2 rows of tables, and where the ram passes the x ends
    of windows and the x rows of tables (brentq on the positions). A quadrature splits its pieces there."""
    angles, xs = set(), set()
    for load in (*loads.forces, *loads.torques):
        w = load.window
        if w.theta2 is not None:
            angles.update(a % TWO_PI for a in w.theta2)
        if w.x is not None:
            xs.update(w.x)
        if isinstance(load.magnitude, tuple) and len(load.magnitude) > 1:
            rows = [r[0] for r in load.magnitude]
            if load.against == "x":
                xs.update(rows)
            else:
                angles.update(a % TWO_PI for a in rows)
    if xs and m.output_joint() is not None:
        t = np.linspace(0.0, TWO_PI, EDGE_GRID + 1)
        x = m.positions(t).x

        def at(th, v):
            return float(m.positions(np.array([th])).x[0]) - v

        for v in xs:
            d = x - v
            for i in np.flatnonzero(d[:-1] * d[1:] < 0):
                angles.add(brentq(at, t[i], t[i + 1], args=(v,), xtol=1e-14) % TWO_PI)
            angles.update(float(t[i]) % TWO_PI for i in np.flatnonzero(d == 0))
    return sorted(angles)


__all__ = ["Applied", "carrier", "resolve", "evaluate", "geometry", "act", "rows", "rest", "edges", "joints_of"]
