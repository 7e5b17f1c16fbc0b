"""A rigid body's motion from its joints' motion: one formula for the exact analysis (on the jets' arrays), its
compiled kernel and the NLP (on CasADi expressions).

A joint's motion is a pair of triples ((x, x', x''), (y, y', y'')): numbers, arrays or CasADi expressions, the
derivatives in time (or per unit crank angle). A body's frame has its origin at its first joint and its x-axis
along the body: towards its second joint; a block's along its slot's line from the pivot (its second joint) to
the pin (its first); a ram or a yoke does not turn (the yoke's origin on y = 0 under its joint).
"""

from __future__ import annotations

import casadi
import numpy as np

NO_TURN = (1.0, 0.0, 0.0, 0.0)


def is_zero(v) -> bool:
    return isinstance(v, (int, float)) and v == 0


def rotation(dx, dy) -> tuple:
    """(cos phi, sin phi, phi', phi'') of the direction (dx, dy) (triples), without an arctangent:
    phi' = (x y' - y x') / r^2, phi'' = (x y'' - y x'' - 2 phi' (x x' + y y')) / r^2."""
    (x0, x1, x2), (y0, y1, y2) = dx, dy
    r2 = x0 * x0 + y0 * y0
    inv = 1.0 / r2
    r = casadi.sqrt(r2) if isinstance(r2, casadi.SX) else np.sqrt(r2)
    w = (x0 * y1 - y0 * x1) * inv
    return x0 / r, y0 / r, w, (x0 * y2 - y0 * x2 - 2.0 * w * (x0 * x1 + y0 * y1)) * inv


def _minus(a, b) -> tuple:
    return tuple(p - q for p, q in zip(a, b, strict=True))


def frame(body, pts) -> tuple:
    """The body's frame: (origin (x, y) triples, (cos phi, sin phi, phi', phi''))."""
    first = pts[body.joints[0]]
    if body.kind == "ram":
        return first, NO_TURN
    if body.kind == "yoke":
        return (first[0], (0.0, 0.0, 0.0)), NO_TURN
    if body.kind == "block":
        pivot = pts[body.joints[1]]
        return first, rotation(_minus(first[0], pivot[0]), _minus(first[1], pivot[1]))
    second = pts[body.joints[1]]
    return first, rotation(_minus(second[0], first[0]), _minus(second[1], first[1]))


def body_motion(body, com, pts) -> tuple:
    """The centre of mass G = o + R(phi) c of ``body`` (``com`` = c, in its frame) from its joints' triples
    (``pts``: joint -> ((x, x', x''), (y, y', y''))): (G, v_G, a_G, (cos phi, sin phi, phi', phi'')), each point
    an (x, y) pair. v_G = o' + phi' J R c, a_G = o'' + phi'' J R c - phi'^2 R c."""
    (ox, oy), rot = frame(body, pts)
    cx, cy = com
    if is_zero(cx) and is_zero(cy):
        return (ox[0], oy[0]), (ox[1], oy[1]), (ox[2], oy[2]), rot
    c, sn, w, al = rot
    rx, ry = (c * cx, sn * cx) if is_zero(cy) else (c * cx - sn * cy, sn * cx + c * cy)
    w2 = w * w
    v = (ox[1] - w * ry, oy[1] + w * rx)
    a = (ox[2] - al * ry - w2 * rx, oy[2] + al * rx - w2 * ry)
    return (ox[0] + rx, oy[0] + ry), v, a, rot


def shaking(kin) -> tuple:
    """(fx, fy, moment about O2) of the shaking: -sum(m a_G), -sum(r_G x m a_G + I alpha) (kin: body -> (G, a_G,
    alpha, mass, inertia), numbers, arrays or expressions alike)."""
    sfx, sfy, sm = 0.0, 0.0, 0.0
    for (gx, gy), (ax, ay), alpha, mass, inertia in kin.values():
        if not is_zero(mass):
            sfx, sfy = sfx - mass * ax, sfy - mass * ay
            sm = sm - mass * (gx * ay - gy * ax)
        if not is_zero(inertia):
            sm = sm - inertia * alpha
    return sfx, sfy, sm


__all__ = ["body_motion", "frame", "rotation", "shaking", "is_zero"]
