"""Math namespaces: every kinematic formula in qropt is written once over one of these.

``NUMPY`` evaluates on float arrays (vectorised over crank angles), ``JET`` on
second-order Taylor jets (value and first two derivatives with respect to the
seeded variable, so one formula gives position, velocity and acceleration
exactly), and ``CASADI`` builds CasADi SX/MX expressions for the NLP.
"""

from __future__ import annotations

from types import SimpleNamespace

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


class Jet:
    """Truncated Taylor jet (f, f', f'') of arrays, derivatives in the seeded variable.

    Stored as one array ``c`` of shape (3, ...) so that linear operations are single numpy calls.
    """

    __slots__ = ("c", "_sc")
    __array_ufunc__ = None  # ndarray * Jet defers to Jet.__rmul__ instead of building an object array

    def __init__(self, c):
        self.c = c
        self._sc = None

    def sincos(self):
        """(sin, cos) of the value, computed once per jet (positions take both of the same angle)."""
        if self._sc is None:
            self._sc = (np.sin(self.c[0]), np.cos(self.c[0]))
        return self._sc

    v = property(lambda self: self.c[0])
    d1 = property(lambda self: self.c[1])
    d2 = property(lambda self: self.c[2])

    @staticmethod
    def seed(x, d1=1.0, d2=0.0) -> Jet:
        """The independent variable: value x with derivatives d1, d2 (e.g. omega2, alpha2)."""
        x = np.asarray(x, dtype=float)
        c = np.empty((3,) + x.shape)
        c[0], c[1], c[2] = x, d1, d2
        return Jet(c)

    @staticmethod
    def of(v, d1, d2) -> Jet:
        """A jet from its three components (broadcast together)."""
        return Jet(np.array(np.broadcast_arrays(v, d1, d2), dtype=float))

    def _chain(self, g0, g1, g2) -> Jet:
        # f = g(u): f' = g'(u) u', f'' = g''(u) u'^2 + g'(u) u''
        u1 = self.c[1]
        c = np.empty_like(self.c)
        c[0] = g0
        c[1] = g1 * u1
        c[2] = g2 * u1 * u1 + g1 * self.c[2]
        return Jet(c)

    def _plus_value(self, o):
        c = self.c.copy()
        c[0] += o
        return Jet(c)

    def __add__(self, o):
        if isinstance(o, Jet):
            return Jet(self.c + o.c)
        if isinstance(o, float | int) or np.ndim(o) <= np.ndim(self.c) - 1:
            return self._plus_value(o)
        return Jet.of(self.c[0] + o, self.c[1], self.c[2])

    __radd__ = __add__

    def __neg__(self):
        return Jet(-self.c)

    def __sub__(self, o):
        if isinstance(o, Jet):
            return Jet(self.c - o.c)
        return self + (-o)

    def __rsub__(self, o):
        c = -self.c
        if isinstance(o, float | int) or np.ndim(o) <= np.ndim(c) - 1:
            c[0] += o
            return Jet(c)
        return Jet(c) + o

    def __mul__(self, o):
        if isinstance(o, Jet):
            a, b = self.c, o.c
            c = a * b[0]
            c[1] += a[0] * b[1]
            c[2] += a[0] * b[2] + 2.0 * a[1] * b[1]
            return Jet(c)
        return Jet(self.c * o)

    __rmul__ = __mul__

    def _reciprocal(self) -> Jet:
        r = 1.0 / self.c[0]
        return self._chain(r, -r * r, 2.0 * r * r * r)

    def __truediv__(self, o):
        if isinstance(o, Jet):
            return self * o._reciprocal()
        return Jet(self.c / o)

    def __rtruediv__(self, o):
        return self._reciprocal() * o

    def __pow__(self, n):
        if n == 2:
            return self * self
        raise ValueError("Jet supports only the power 2 (use the namespace's sqrt)")

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
    return Jet.of(x, 0.0, 0.0)


def _jsin(u):
    if not isinstance(u, Jet):
        return np.sin(u)
    s, c = u.sincos()
    return u._chain(s, c, -s)


def _jcos(u):
    if not isinstance(u, Jet):
        return np.cos(u)
    s, c = u.sincos()
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
    (x0, x1, x2), (y0, y1, y2) = x.c, y.c
    c = np.empty(np.broadcast_shapes(x.c.shape, y.c.shape))
    r = 1.0 / (x0 * x0 + y0 * y0)
    c[0] = np.arctan2(y0, x0)
    c[1] = n = (x0 * y1 - y0 * x1) * r
    # (x0 y2 - y0 x2) / d - n d'/d with d' = 2 (x0 x1 + y0 y1)
    c[2] = (x0 * y2 - y0 * x2 - 2.0 * n * (x0 * x1 + y0 * y1)) * r
    return Jet(c)


def _jfabs(u):
    if not isinstance(u, Jet):
        return np.abs(u)
    return Jet(np.where(u.c[0] < 0, -1.0, 1.0) * u.c)


def _jif_else(cond, a, b):
    cond = _val(cond)
    if not isinstance(a, Jet) and not isinstance(b, Jet):
        return np.where(cond, a, b)
    a, b = _lift(a), _lift(b)
    return Jet(np.where(cond, a.c, b.c))


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
