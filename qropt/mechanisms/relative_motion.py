"""Relative-motion analysis: the velocity and acceleration equations of a linkage, dyad by dyad, as its polygons.

For a type declared with the linkage builder, at one crank angle, omega2 and alpha2, every vector term of the
equations is written in the order the linkage is built (the paper's Analysis (1), Tables 1-3): for a joint X on
a link from P, ``V_X = V_P + V_X/P`` with ``V_X/P = omega x PX`` normal to the link, and
``A_X = A_P + A_X/P^n + A_X/P^t`` with the normal term ``-omega^2 PX`` (from X towards P, magnitude
``|V_X/P|^2 / |PX|``) and the tangential ``alpha x PX``; a point in a turning slot adds the sliding velocity along the
slot and the Coriolis term ``2 omega x V_slide``. Each term's rate comes from the link's own angle (its jet), so
that the sum of the terms against the joint's exact velocity and acceleration (its jet) is an independent check.
Lengths in the mechanism's unit, angles in rad, directions counter-clockwise from +x.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from qropt.errors import InvalidParameter
from qropt.kinematics.ops import JET, Jet
from qropt.validate import LIMIT, number


class Term(NamedTuple):
    """One vector of an equation: its name (``V_B/A``, ``A_B/A^n``, ...), kind ('absolute', 'relative',
    'normal', 'tangential', 'sliding', 'coriolis'), its components and whether its magnitude was solved from the
    polygon (False: known from what came before, or from the link's rate and length)."""

    name: str
    kind: str
    vector: np.ndarray
    solved: bool

    @property
    def magnitude(self) -> float:
        return float(np.hypot(*self.vector))

    @property
    def direction(self) -> float:
        """rad, counter-clockwise from +x."""
        return float(math.atan2(self.vector[1], self.vector[0]))


class Equation(NamedTuple):
    """``exact = sum(terms)`` for one joint: quantity 'velocity' or 'acceleration'; ``exact`` from the jets."""

    joint: str
    quantity: str
    terms: tuple
    exact: np.ndarray

    @property
    def residual(self) -> float:
        return float(np.hypot(*(sum(t.vector for t in self.terms) - self.exact)))


@dataclass(frozen=True)
class RelativeMotion:
    """The equations of a mechanism at theta2 (rad), omega2 (rad/s), alpha2 (rad/s^2), in build order."""

    theta2: float
    omega2: float
    alpha2: float
    equations: tuple

    def terms(self) -> dict:
        """Term name -> Term (each equation's terms, velocities first)."""
        return {t.name: t for e in self.equations for t in e.terms}

    def table(self) -> list[dict]:
        """One row a term, in the paper's form: equation, term, kind, magnitude, direction (deg), solved."""
        return [
            {
                "joint": e.joint,
                "quantity": e.quantity,
                "term": t.name,
                "kind": t.kind,
                "magnitude": t.magnitude,
                "direction_deg": math.degrees(t.direction) % 360.0,
                "solved": t.solved,
            }
            for e in self.equations
            for t in e.terms
        ]


def relative_motion(m, theta2: float, omega2: float = 1.0, alpha2: float = 0.0) -> RelativeMotion:
    """The velocity and acceleration equations of mechanism m at one crank angle theta2 (rad), omega2 (rad/s) and
    alpha2 (rad/s^2), each a finite number (|omega2|, |alpha2| <= 1e12); see the module docstring."""
    theta2 = number("theta2 (rad)", theta2)
    omega2, alpha2 = number("omega2 (rad/s)", omega2, limit=LIMIT), number("alpha2 (rad/s^2)", alpha2, limit=LIMIT)
    linkage = type(m).linkage(m.params)
    if linkage is None:
        raise InvalidParameter(f"{type(m).__name__} is not declared with the linkage builder: no polygons")
    t = m._angles(theta2)  # it assembles there (AssemblyError otherwise)
    lp = m.evaluate(JET, Jet.seed(t, omega2, alpha2))
    pos, vel, acc = {}, {}, {}
    for name, (x, y) in lp.points.items():
        parts = [_parts(x), _parts(y)]
        pos[name], vel[name], acc[name] = (np.array([parts[0][i], parts[1][i]]) for i in range(3))

    def rate(o, t):
        """(r = t - o, omega, alpha) of the link from o through t, from the jet of its angle."""
        (ox, oy), (tx, ty) = lp.points[o], lp.points[t]
        ang = JET.atan2(_jet(ty) - _jet(oy), _jet(tx) - _jet(ox))
        return pos[t] - pos[o], float(ang.d1[0]), float(ang.d2[0])

    def cross(w, r):
        return np.array([-w * r[1], w * r[0]])

    eqs = []

    def rigid(x, o, t, known):
        """x fixed on the link o -> t (x may be t): V_x = V_o + omega x ox, A_x = A_o + normal + tangential."""
        _, w, a = rate(o, t)
        r = pos[x] - pos[o]
        vt = [Term(f"V_{o}", "absolute", vel[o], False)] if np.any(vel[o]) else []
        at = [Term(f"A_{o}", "absolute", acc[o], False)] if np.any(acc[o]) else []
        rel = f"{x}/{o}"
        eqs.append(Equation(x, "velocity", (*vt, Term(f"V_{rel}", "relative", cross(w, r), not known)), vel[x]))
        eqs.append(
            Equation(
                x,
                "acceleration",
                (
                    *at,
                    Term(f"A_{rel}^n", "normal", -w * w * r, False),
                    Term(f"A_{rel}^t", "tangential", cross(a, r), not known),
                ),
                acc[x],
            )
        )

    def sliding(x, o, t):
        """x moving along the link o -> t (a block in a turning slot): V_x = V_x' + V_slide, with the Coriolis term."""
        r, w, a = rate(o, t)
        u = r / np.hypot(*r)
        s1 = float(np.dot(vel[x] - vel[o], u))  # the slide speed along the slot
        base_v = vel[o] + cross(w, pos[x] - pos[o])
        base_a = acc[o] - w * w * (pos[x] - pos[o]) + cross(a, pos[x] - pos[o])
        cor = cross(2 * w, s1 * u)
        s2 = float(np.dot(acc[x] - base_a - cor, u))
        eqs.append(
            Equation(
                x,
                "velocity",
                (Term(f"V_{x}'", "relative", base_v, False), Term(f"V_{x}/{x}' (slide)", "sliding", s1 * u, True)),
                vel[x],
            )
        )
        eqs.append(
            Equation(
                x,
                "acceleration",
                (
                    Term(f"A_{x}'", "relative", base_a, False),
                    Term(f"A_{x}/{x}' (slide)", "sliding", s2 * u, True),
                    Term(f"A_{x} (Coriolis)", "coriolis", cor, False),
                ),
                acc[x],
            )
        )

    for e in linkage.elements():
        k = e.kind
        if k == "crank":
            rigid(e.point, e.about, e.point, known=True)
        elif k == "rrr":
            rigid(e.point, e.p_, e.point, known=False)
            rigid(e.point, e.q_, e.point, known=False)
        elif k == "rrp":
            rigid(e.point, e.pin, e.point, known=False)
        elif k == "rpr":
            sliding(e.pin, e.pivot, e.pin)
        elif k == "slot_line":
            sliding(e.point, e.pivot, e.through)
        elif k in ("on_ray", "coupler_point"):
            rigid(e.point, e.origin, e.through, known=True)
    return RelativeMotion(theta2, omega2, alpha2, tuple(eqs))


def _jet(v):
    return v if isinstance(v, Jet) else Jet.of(np.array([float(v)]), 0.0, 0.0)


def _parts(v):
    if isinstance(v, Jet):
        return [float(np.ravel(v.v)[0]), float(np.ravel(v.d1)[0]), float(np.ravel(v.d2)[0])]
    return [float(v), 0.0, 0.0]


__all__ = ["relative_motion", "RelativeMotion", "Equation", "Term"]
