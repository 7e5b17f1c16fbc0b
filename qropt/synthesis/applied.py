"""The general loads (``Loads.forces``, ``Loads.torques``, a gravity vector, ``Masses.points``) at one crank angle of
the synthesis NLP, as CasADi expressions: which body carries a load and where its point is and how fast it moves
are ``qropt.dynamics.applied``'s (``resolve``, ``geometry``); the rules that give its amount and direction (windows,
tables, each direction kind) are the exact side's written for a point of the formulation (``Kin``: the output x in
the mechanism's unit, every joint's coordinates and their derivatives in theta2).

Each load is an ``applied.Applied`` of expressions, its velocities per unit crank angle (SI, m/rad); a force's power
at omega2 is ``F . v omega2``. A window's edge and a force against a velocity are steps in the design and the crank
angle: the NLP states them with ``if_else`` and the exact certificate (which splits at the edges) decides.
"""

from __future__ import annotations

import math

import casadi

from qropt.dynamics import applied as exact
from qropt.dynamics.model import Force, Loads

TWO_PI = 2 * math.pi


def resolved(link, system, loads: Loads) -> list[tuple]:
    """(load, body) for each force and torque, checked as the exact analysis checks them (``applied.resolve``;
    the linkage stands for the mechanism: it names the output joint)."""
    return exact.resolve(link, system, link, loads)


def _table(name: str, rows: tuple):
    xs, fs = [float(r[0]) for r in rows], [float(r[1]) for r in rows]
    if len(xs) == 1:
        return lambda at: fs[0]
    f = casadi.interpolant(name, "linear", [xs], fs)
    return lambda at: f(casadi.fmin(casadi.fmax(at, xs[0]), xs[-1]))


def _mod(a):
    return a - TWO_PI * casadi.floor(a / TWO_PI)


def magnitude(load, out, tables: dict):
    """The load's magnitude at the point: its constant or its table against x (the mechanism's unit) or theta2
    (in [0, 2 pi)), linear between rows and constant beyond them as ``level``."""
    if not isinstance(load.magnitude, tuple):
        return load.magnitude
    key = id(load)
    if key not in tables:
        tables[key] = _table(f"load_{len(tables)}", load.magnitude)
    return tables[key](out.x if load.against == "x" else _mod(out.theta2))


def active(window, out, working, moving):
    """1 where the window holds at the point, else 0: ``working`` True/False where the point's stroke is known,
    None to decide by ``moving`` (the output's velocity along the working way, > 0 on the working stroke)."""
    on = 1
    if window.stroke != "both":
        if working is None:
            w = moving > 0 if window.stroke == "working" else moving <= 0
            on = casadi.if_else(w, 1, 0)
        elif working != (window.stroke == "working"):
            return 0
    if window.x is not None:
        on = on * casadi.if_else(casadi.logic_and(out.x >= window.x[0], out.x <= window.x[1]), 1, 0)
    if window.theta2 is not None:
        a, b = window.theta2
        on = on * casadi.if_else(_mod(out.theta2 - a) <= b - a, 1, 0)
    return on


def at(s, pairs, out, working, way: float, omega2: float, tables: dict) -> list[exact.Applied]:
    """The resolved loads (``resolved``) at one point of the formulation ``s`` (``_Symbolic``); ``way`` the working
    stroke's direction along x (+1 or -1) at this omega2 (rad/s)."""
    bodies = {b.name: b for b in s.bodies}
    sense = math.copysign(1.0, omega2)
    size = 0  # the mechanism's size here (m): a point slower than AT_REST of it per radian is at rest
    for j in s.f.joint_index:
        px, py = s.point(out, j)
        size = casadi.fmax(size, casadi.sqrt(px * px + py * py))
    rest = exact.AT_REST * size
    moving = way * out.v * omega2
    pts = {j: tuple(tuple(s.point(out, j, k)[i] for k in range(3)) for i in (0, 1)) for j in s.f.joint_index}
    out_list = []
    for (load, name), ((px, py), v, spin) in zip(pairs, exact.geometry(s.system(), pairs, pts), strict=True):
        amount = magnitude(load, out, tables) * active(load.window, out, working, moving)
        if not isinstance(load, Force):
            out_list.append(exact.Applied(name, (px, py), (0, 0), (0, 0), amount, spin))
            continue
        b = bodies[name]
        d = load.direction
        if d == "against" and b.kind in ("ram", "yoke"):  # along the slide: against the stroke's way
            along = casadi.sign(moving) if working is None else (1.0 if working else -1.0)
            force = (-amount * way * along, 0)
        elif d == "against":
            speed = casadi.sqrt(v[0] * v[0] + v[1] * v[1])
            inv = casadi.if_else(speed > rest, -sense / casadi.if_else(speed > rest, speed, 1), 0)
            force = (amount * v[0] * inv, amount * v[1] * inv)
        elif d == "slide":
            force = (amount, 0)
        else:
            n = math.hypot(*d)
            force = (amount * (d[0] / n), amount * (d[1] / n))
        out_list.append(exact.Applied(name, (px, py), v, force, 0, spin))
    return out_list


__all__ = ["resolved", "magnitude", "active", "at"]
