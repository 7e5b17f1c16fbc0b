"""Closures shared by every mechanism type, each written once over a math namespace ``xp``.

Points are ``(x, y)`` tuples of numbers, arrays, jets or CasADi expressions.
Each closure returns its result and an assembly ``margin``: >= 0 where the
closure has a real solution, < 0 where it cannot assemble.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple


def circle_circle(xp, p, a, q, b, sigma, around=0.0):
    """RRR: the point X with |X - P| = a and |X - Q| = b on branch sigma.

    ``sigma = sign((P - Q) x (X - Q))``. Returns ``(X, angle of X - Q, margin)``.
    The angle is continuous except where P - Q points along ``around + pi``.
    """
    ux, uy = p[0] - q[0], p[1] - q[1]
    ll = ux * ux + uy * uy
    c = (b * b + ll - a * a) / (2.0 * b * xp.sqrt(ll))
    if around == 0.0:
        psi = xp.atan2(uy, ux)
    elif around == math.pi:
        psi = around + xp.atan2(-uy, -ux)
    else:
        ca, sa = math.cos(around), math.sin(around)
        psi = around + xp.atan2(uy * ca - ux * sa, ux * ca + uy * sa)
    angle = psi + sigma * xp.acos(c)
    x = (q[0] + b * xp.cos(angle), q[1] + b * xp.sin(angle))
    return x, angle, 1.0 - c * c


def rod_to_line(xp, p, r, h, sigma):
    """RRP: the end D of a rod of length r from pin P that slides on the line y = h.

    ``sigma = +1`` puts D on the +x side of P. Returns ``(D, margin)``.
    """
    dy = h - p[1]
    w = r * r - dy * dy
    return (p[0] + sigma * xp.sqrt(w), h + 0.0 * p[0]), w / (r * r)


def pin_in_slot(xp, pivot, pin):
    """RPR: the angle of a slotted lever that turns about ``pivot`` and carries the block at ``pin``."""
    return xp.atan2(pin[1] - pivot[1], pin[0] - pivot[0])


def on_ray(xp, origin, angle, length):
    """The point at ``length`` from ``origin`` along ``angle``."""
    return (origin[0] + length * xp.cos(angle), origin[1] + length * xp.sin(angle))


def acute_angle(xp, u, w):
    """The acute angle (radians, in [0, pi/2]) between the lines along vectors u and w."""
    cross = u[0] * w[1] - u[1] * w[0]
    dot = u[0] * w[0] + u[1] * w[1]
    return xp.atan2(xp.fabs(cross), xp.fabs(dot))


# A transmitting joint is described by its two lines: the line along which the driving element
# carries force and the velocity direction of the driven point (or None: a block in a slot or a
# yoke, whose transmission angle is 90 degrees). Angle and cosine are derived here, once.
RIGHT_ANGLE = None


def joint_lines(a, o, b):
    """Coupler-follower joint B: force along B->A, driven point B moves normal to O->B (so use B->O)."""
    return (a[0] - b[0], a[1] - b[1]), (o[0] - b[0], o[1] - b[1])


def rod_lines(pin, slider):
    """Rod pin -> slider on a +x slide line: force along the rod, compared with the line's normal."""
    return (slider[0] - pin[0], slider[1] - pin[1]), (0.0, 1.0)


def transmission_angle(xp, lines):
    """Transmission angle (rad, [0, pi/2]) of a joint given by its lines; pi/2 for RIGHT_ANGLE."""
    return math.pi / 2 if lines is None else acute_angle(xp, *lines)


def transmission_cos(xp, lines):
    """Signed cosine of the angle between a joint's lines: gamma >= g  <=>  |cos| <= cos(g). Smooth."""
    if lines is None:
        return 0.0
    (ux, uy), (wx, wy) = lines
    return (ux * wx + uy * wy) / xp.sqrt((ux * ux + uy * uy) * (wx * wx + wy * wy))


def transmission_cos2(xp, lines):
    """Squared cosine of the angle between a joint's lines (smooth; 0 for RIGHT_ANGLE): gamma = acos(sqrt(.))."""
    if lines is None:
        return 0.0
    (ux, uy), (wx, wy) = lines
    d = ux * wx + uy * wy
    return d * d / ((ux * ux + uy * uy) * (wx * wx + wy * wy))


def slot_to_line(xp, pivot, pin, h):
    """PP: the pin D that rides in a slotted lever (about ``pivot``, its slot along the ray through ``pin``) and on
    the slide line y = h: where the lever's line crosses the slide line. Returns ``(D, t)``, ``t`` D's distance
    from the pivot along the ray in units of ``|pin - pivot|`` (> 0: D on the ray; the lever must not be parallel
    to the slide line)."""
    t = (h - pivot[1]) / (pin[1] - pivot[1])
    return (pivot[0] + t * (pin[0] - pivot[0]), h + 0.0 * pin[0]), t


def slot_line_lines(pivot, pin):
    """A slotted lever driving a pin on a +x slide line: the lever pushes along its normal and the pin moves along
    x, so the transmission angle is the acute angle between the lever (pivot -> pin) and the slide line."""
    return (pin[0] - pivot[0], pin[1] - pivot[1]), (1.0, 0.0)


class Loop(NamedTuple):
    """One evaluation of a mechanism's closed-form loop.

    points: joint name -> (x, y); angles: link angle name -> angle (direction
    from the first-named joint to the second, e.g. theta3 = A->B); x: the output
    (slider position along +x, or theta4 for FourBar); transmission: joint -> its
    lines (see the functions above) or RIGHT_ANGLE; margins: (closure, margin >= 0 if it assembles).
    """

    points: dict
    angles: dict
    x: Any
    transmission: dict
    margins: list
