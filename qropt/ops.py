"""Math namespaces: every kinematic formula in qropt is written once over one of these.

``NUMPY`` evaluates on float arrays (vectorised over crank angles), ``JET`` on
second-order Taylor jets (value and first two derivatives with respect to the
seeded variable, so one formula gives position, velocity and acceleration
exactly), and ``CASADI`` builds CasADi SX/MX expressions for the NLP.
"""

from __future__ import annotations

from dataclasses import dataclass
from types import SimpleNamespace
from typing import Any

import casadi
import numpy as np

__all__ = ["NUMPY", "CASADI", "JET", "Jet"]


def _np_if_else(cond, a, b):
    return np.where(cond, a, b)


NUMPY = SimpleNamespace(
    name="numpy",
    sin=np.sin,
    cos=np.cos,
    atan2=np.arctan2,
    sqrt=np.sqrt,
    acos=np.arccos,
    asin=np.arcsin,
    fabs=np.abs,
    fmin=np.minimum,
    fmax=np.maximum,
    if_else=_np_if_else,
    pi=np.pi,
)

CASADI = SimpleNamespace(
    name="casadi",
    sin=casadi.sin,
    cos=casadi.cos,
    atan2=casadi.atan2,
    sqrt=casadi.sqrt,
    acos=casadi.acos,
    asin=casadi.asin,
    fabs=casadi.fabs,
    fmin=casadi.fmin,
    fmax=casadi.fmax,
    if_else=casadi.if_else,
    pi=np.pi,
)


@dataclass(frozen=True, slots=True)
class Jet:
    """Truncated Taylor jet (f, f', f'') of arrays, derivatives in the seeded variable."""

    v: Any
    d1: Any
    d2: Any

    @staticmethod
    def seed(x, d1=1.0, d2=0.0) -> Jet:
        """The independent variable: value x with derivatives d1, d2 (e.g. omega2, alpha2)."""
        x = np.asarray(x, dtype=float)
        return Jet(x, np.broadcast_to(np.asarray(d1, float), x.shape), np.broadcast_to(np.asarray(d2, float), x.shape))

    def _chain(self, g0, g1, g2) -> Jet:
        # f = g(u): f' = g'(u) u', f'' = g''(u) u'^2 + g'(u) u''
        return Jet(g0, g1 * self.d1, g2 * self.d1 * self.d1 + g1 * self.d2)

    def __add__(self, o):
        if isinstance(o, Jet):
            return Jet(self.v + o.v, self.d1 + o.d1, self.d2 + o.d2)
        return Jet(self.v + o, self.d1, self.d2)

    __radd__ = __add__

    def __neg__(self):
        return Jet(-self.v, -self.d1, -self.d2)

    def __sub__(self, o):
        return self + (-o)

    def __rsub__(self, o):
        return (-self) + o

    def __mul__(self, o):
        if isinstance(o, Jet):
            return Jet(
                self.v * o.v,
                self.d1 * o.v + self.v * o.d1,
                self.d2 * o.v + 2.0 * self.d1 * o.d1 + self.v * o.d2,
            )
        return Jet(self.v * o, self.d1 * o, self.d2 * o)

    __rmul__ = __mul__

    def _reciprocal(self) -> Jet:
        r = 1.0 / self.v
        return self._chain(r, -r * r, 2.0 * r * r * r)

    def __truediv__(self, o):
        if isinstance(o, Jet):
            return self * o._reciprocal()
        return Jet(self.v / o, self.d1 / o, self.d2 / o)

    def __rtruediv__(self, o):
        return self._reciprocal() * o

    def __pow__(self, n):
        if n == 2:
            return self * self
        if n == 0.5:
            return _jsqrt(self)
        raise ValueError("Jet supports only the powers 2 and 0.5")

    def __lt__(self, o):
        return self.v < _val(o)

    def __le__(self, o):
        return self.v <= _val(o)

    def __gt__(self, o):
        return self.v > _val(o)

    def __ge__(self, o):
        return self.v >= _val(o)


def _val(x):
    return x.v if isinstance(x, Jet) else x


def _lift(x) -> Jet:
    if isinstance(x, Jet):
        return x
    x = np.asarray(x, dtype=float)
    z = np.zeros_like(x)
    return Jet(x, z, z)


def _jsin(u):
    if not isinstance(u, Jet):
        return np.sin(u)
    s, c = np.sin(u.v), np.cos(u.v)
    return u._chain(s, c, -s)


def _jcos(u):
    if not isinstance(u, Jet):
        return np.cos(u)
    s, c = np.sin(u.v), np.cos(u.v)
    return u._chain(c, -s, -c)


def _jsqrt(u):
    if not isinstance(u, Jet):
        return np.sqrt(u)
    r = np.sqrt(u.v)
    return u._chain(r, 0.5 / r, -0.25 / (r * u.v))


def _jacos(u):
    if not isinstance(u, Jet):
        return np.arccos(u)
    w = 1.0 - u.v * u.v
    g1 = -1.0 / np.sqrt(w)
    return u._chain(np.arccos(u.v), g1, g1 * u.v / w)


def _jasin(u):
    if not isinstance(u, Jet):
        return np.arcsin(u)
    w = 1.0 - u.v * u.v
    g1 = 1.0 / np.sqrt(w)
    return u._chain(np.arcsin(u.v), g1, g1 * u.v / w)


def _jatan2(y, x):
    if not isinstance(y, Jet) and not isinstance(x, Jet):
        return np.arctan2(y, x)
    y, x = _lift(y), _lift(x)
    d = x.v * x.v + y.v * y.v
    n = x.v * y.d1 - y.v * x.d1
    dn = x.v * y.d2 - y.v * x.d2
    dd = 2.0 * (x.v * x.d1 + y.v * y.d1)
    return Jet(np.arctan2(y.v, x.v), n / d, (dn * d - n * dd) / (d * d))


def _jfabs(u):
    if not isinstance(u, Jet):
        return np.abs(u)
    s = np.where(u.v < 0, -1.0, 1.0)
    return Jet(s * u.v, s * u.d1, s * u.d2)


def _jif_else(cond, a, b):
    cond = _val(cond)
    if not isinstance(a, Jet) and not isinstance(b, Jet):
        return np.where(cond, a, b)
    a, b = _lift(a), _lift(b)
    return Jet(np.where(cond, a.v, b.v), np.where(cond, a.d1, b.d1), np.where(cond, a.d2, b.d2))


def _jfmin(a, b):
    return _jif_else(_val(a) <= _val(b), a, b)


def _jfmax(a, b):
    return _jif_else(_val(a) >= _val(b), a, b)


JET = SimpleNamespace(
    name="jet",
    sin=_jsin,
    cos=_jcos,
    atan2=_jatan2,
    sqrt=_jsqrt,
    acos=_jacos,
    asin=_jasin,
    fabs=_jfabs,
    fmin=_jfmin,
    fmax=_jfmax,
    if_else=_jif_else,
    pi=np.pi,
)
