"""Compiled exact cycle analysis: CasADi Functions built from each type's ``loop`` (the same source).

A mechanism's cycle quantities are smooth periodic functions of the crank angle. Their
extremes are bracketed on a uniform grid from one vectorised numpy evaluation of the loop,
started at the vertex of the grid parabola (error O(h^3)), and refined by Newton steps with
exact AD derivatives, all brackets in one compiled call. A refined point is accepted only if
its last Newton step is below 1e-10 rad, it stays inside its bracket and the curvature has the
extreme's sign; any other bracket is refined by the safeguarded Newton/false-position iteration
of ``cycle.stationary`` on the same exact derivatives. Four groups of quantities are compiled
on demand: ``cycle`` (output x, squared transmission cosines, assembly margins), ``accel``
(d2x/dtheta2, refined with exact third and fourth derivatives), ``velocity`` (dx/dtheta2) and ``coords`` (every joint
coordinate, for bounding boxes).

Kernels are pure functions of (type, parameter names): building one twice gives the same
numbers, so they are kept per type for the life of the process.
"""

from __future__ import annotations

import functools
import threading
from typing import NamedTuple

import casadi
import numpy as np

from qropt.errors import InvalidParameter
from qropt.kinematics import cycle, driver, native
from qropt.kinematics.closures import RIGHT_ANGLE, Loop, transmission_angle, transmission_cos2
from qropt.kinematics.ops import CASADI, NUMPY, Jet

NEWTON_STEPS = 2  # from the grid parabola's vertex (error <~1e-4 rad), two steps reach ~1e-16 rad
TWO_PI = 2.0 * np.pi
CSE = {"cse": True}  # common subexpressions of the nested derivatives merged: a third of the instructions
STEP_TOL = 1e-10  # rad: a last Newton step this small means the point is converged (error ~ step^2)
_KERNELS: dict = {}
_THREE = np.arange(3)


class Extremes(NamedTuple):
    """Refined local extremes of one quantity: crank angles (rad, [0, 2pi)) and precise values."""

    theta: np.ndarray
    value: np.ndarray


def kernel(cls, names: tuple) -> Kernel:
    """The compiled analysis of type ``cls`` with parameters ``names`` (built once per process)."""
    key = (cls, names)
    k = _KERNELS.get(key)
    if k is None:
        k = _KERNELS[key] = Kernel(cls, names)
    return k


class Batched:
    """A CasADi Function of one column z mapped over K columns, evaluated through CasADi's zero-copy
    FunctionBuffer (the Python conversions of an ordinary call cost more than the arithmetic here).

    A K that is used HOT times is compiled to machine code (``native``): the row function mapped over K, or,
    from WIDE rows up, the mapped function itself as one C loop. ``f`` stays the symbolic Function, for
    composing larger ones (and a Function made for one problem is never compiled: ``compiled=False``). Buffers
    are kept for at most KEPT shapes of up to MAX_ROWS rows, per thread: CasADi evaluates a buffer without Python's
    lock, and two threads sharing one would overwrite each other's rows, or one free a buffer the other evaluates.
    Every call, on the VM or compiled, gives the same numbers to the last bit."""

    HOT = 16  # calls with one K after which that K runs compiled (rarely used shapes stay on CasADi's VM)
    WIDE = 64  # rows from which the whole map is compiled as one loop
    MAX_ROWS = 20_000  # a larger K is evaluated in pieces of this many rows
    KEPT = 64  # shapes whose buffers are kept

    def __init__(self, f: casadi.Function, compiled: bool = True):
        if not f.sparsity_out(0).is_dense():  # the buffer holds nonzeros only: make every entry one
            z = f.mx_in(0)
            f = casadi.Function(f.name() + "_dense", [z], [casadi.densify(f(z))])
        self.f, self.m, self.r = f, f.size1_in(0), f.size1_out(0)
        self._local = threading.local()  # .by_k: K -> [z, out, evaluate, FunctionBuffer, uses when built, native?]
        self._uses: dict = {}
        self._native = None
        self.may_compile = compiled  # False: a Function of one problem (its constants in the code)

    def _compiled(self, k: int) -> tuple[casadi.Function, bool]:
        """The map over k rows as machine code, and whether it is (False: CasADi's VM, no compiler)."""
        if k >= self.WIDE:
            f = self.f.map(k)
            c = native.compiled(f)
            return c, c is not f
        if self._native is None:
            self._native = native.compiled(self.f)
        return self._native.map(k), self._native is not self.f

    @property
    def _by_k(self) -> dict:
        """This thread's buffers by K."""
        by_k = getattr(self._local, "by_k", None)
        if by_k is None:
            by_k = self._local.by_k = {}
        return by_k

    def _entry(self, k: int) -> list:
        e = self._by_k.get(k)
        uses = self._uses.get(k, 0)
        if e is None or (uses >= self.HOT > e[4]):  # new, or hot now: rebuilt once, compiled
            if len(self._by_k) >= self.KEPT:
                self._by_k.clear()
            fk, is_native = self._compiled(k) if uses >= self.HOT else (self.f.map(k), False)
            zin, out = np.zeros((k, self.m)), np.zeros((k, self.r))
            buf, ev = fk.buffer()
            buf.set_arg(0, memoryview(zin))
            buf.set_res(0, memoryview(out))
            e = self._by_k[k] = [zin, out, ev, buf, uses, is_native]
        return e

    def _count(self, k: int) -> int:
        """Counts a use with K rows (up to HOT; none for a Function that is never compiled)."""
        uses = self._uses.get(k, 0)
        if uses < self.HOT and self.may_compile:
            uses = self._uses[k] = uses + 1
        return uses

    def __call__(self, z: np.ndarray) -> np.ndarray:
        """z: (K, m) -> (K, r)."""
        k = z.shape[0]
        if k == 0:  # no rows (an empty array of crank angles): CasADi maps over one or more
            return np.empty((0, self.r))
        if k > self.MAX_ROWS:
            return np.concatenate([self(z[i : i + self.MAX_ROWS]) for i in range(0, k, self.MAX_ROWS)])
        zin, out, ev = self.buffers(k)
        zin[:] = z
        ev()
        return out.copy()

    def buffers(self, k: int) -> tuple[np.ndarray, np.ndarray, object]:
        """A call with K (<= MAX_ROWS) rows in place: (z (K, m), out (K, r), evaluate). Fill z, call evaluate(),
        read out before the next call with K rows (it is overwritten)."""
        self._count(k)
        e = self._entry(k)
        return e[0], e[1], e[2]


class _Quantity:
    """One scalar q(theta; p): exact derivatives at points, and a batched Newton refinement of its extremes."""

    def __init__(self, t, P, q, precise):
        d1 = casadi.jacobian(q, t)
        d2 = casadi.jacobian(d1, t)
        n = P.numel()
        z = casadi.SX.sym("z", 1 + n)
        d = casadi.Function("d", [t, P], [q, d1, d2])
        self.derivs = Batched(casadi.Function("dz", [z], [casadi.vertcat(*d(z[0], z[1:]))], CSE))
        # one bracket: the grid samples vm <= v0 > vp (of sign * q) around theta = th, spacing h; the start is the
        # grid parabola's vertex (no shift where it is not finite or beyond half a step)
        zn = casadi.SX.sym("z", 6 + n)
        th, h, vm, v0, vp, sgn, pz = zn[0], zn[1], zn[2], zn[3], zn[4], zn[5], zn[6:]
        shift = 0.5 * (vm - vp) / (vm - 2.0 * v0 + vp)
        shift = casadi.if_else(casadi.fabs(shift) <= 0.5, shift, 0.0)
        lo, hi = th - h, th + h
        x = th + shift * h
        for _ in range(NEWTON_STEPS):
            _, g1, g2 = d(x, pz)
            x = casadi.fmin(casadi.fmax(x - g1 / g2, lo), hi)
        _, g1, g2 = d(x, pz)
        value = casadi.Function("v", [t, P], [precise])
        # accepted: a last step below STEP_TOL, strictly inside the bracket, with the curvature of its kind
        ok = casadi.logic_and(
            casadi.logic_and(casadi.fabs(g1 / g2) <= STEP_TOL, casadi.logic_and(x > lo, x < hi)), sgn * g2 < 0
        )
        wrapped = casadi.fmod(x, TWO_PI)
        wrapped = casadi.if_else(wrapped < 0, wrapped + TWO_PI, wrapped)
        wrapped = casadi.if_else(wrapped > TWO_PI - 1e-12, 0.0, wrapped)
        self.newton = casadi.Function("n", [zn], [casadi.vertcat(wrapped, ok, value(x, pz))], CSE)  # switched (refine)
        self.value = Batched(casadi.Function("vz", [z], [value(z[0], z[1:])], CSE))

    def at(self, theta, p):
        """(q, dq/dtheta, d2q/dtheta2) at the crank angles theta (rad): three arrays."""
        theta = np.atleast_1d(np.asarray(theta, float))
        out = self.derivs(np.column_stack([theta, np.broadcast_to(p, (theta.size, p.size))]))
        return out[:, 0], out[:, 1], out[:, 2]


class Kernel:
    """Compiled cycle analysis of one mechanism structure: quantities in three groups."""

    def __init__(self, cls, names):
        self.cls, self.names = cls, tuple(names)
        t, P = casadi.SX.sym("t"), casadi.SX.sym("p", len(names))
        p = {k: P[i] for i, k in enumerate(names)}
        lp = cls.loop(CASADI, t, p)
        if not isinstance(lp, Loop):
            raise InvalidParameter(
                f"{cls.__name__}.loop must return a Loop (qropt.mechanisms.Loop: points, angles, x, transmission, "
                f"margins), got {type(lp).__name__}"
            )
        self.joints = [j for j, lines in lp.transmission.items() if lines is not RIGHT_ANGLE]
        self.right_joints = [j for j, lines in lp.transmission.items() if lines is RIGHT_ANGLE]
        self.margin_names = [what for what, _ in lp.margins]
        self.point_names = list(lp.points)
        nj, nm = len(self.joints), len(self.margin_names)
        # the 'cycle' group's extremes: x's max and min, each varying joint's largest cos^2, each margin's least
        self.cycle_requests = (
            ((0, "max"), (0, "min"))
            + tuple((1 + j, "max") for j in range(nj))
            + tuple((1 + nj + m, "min") for m in range(nm))
        )
        self._t, self._P, self._lp = t, P, lp
        self._groups: dict = {}
        self._drivers: dict = {}  # group -> its refinement in C (``driver``), built once the group is refined HOT times
        self._refines: dict = {}  # group -> refinements made so far (up to HOT)

    def group(self, name: str) -> list[_Quantity]:
        """'cycle': x, cos^2 of each varying joint (precise value: its transmission angle), margins;
        'accel': d2x/dtheta2; 'velocity': dx/dtheta2; 'coords': every joint coordinate. Compiled on first use."""
        g = self._groups.get(name)
        if g is None:
            t, P, lp = self._t, self._P, self._lp
            if name == "cycle":
                pairs = [(lp.x, lp.x)]
                lines = [lp.transmission[j] for j in self.joints]
                pairs += [(transmission_cos2(CASADI, v), transmission_angle(CASADI, v)) for v in lines]
                pairs += [(m, m) for _, m in lp.margins]
            elif name == "accel":
                a = casadi.jacobian(casadi.jacobian(lp.x, t), t)
                pairs = [(a, a)]
            elif name == "velocity":
                v = casadi.jacobian(lp.x, t)
                pairs = [(v, v)]
            else:
                pairs = [
                    (c, c) for pt in lp.points.values() for c in (casadi.SX(pt[0]) + 0 * t, casadi.SX(pt[1]) + 0 * t)
                ]
            g = self._groups[name] = [_Quantity(t, P, q, v) for q, v in pairs]
        return g

    def vector(self, params: dict) -> np.ndarray:
        return np.array([params[k] for k in self.names], float)

    # ---- grid pass -------------------------------------------------------------------------
    def grid_values(self, p: np.ndarray, theta):
        """Cycle quantities (Q, n) at the parameter vector p (``vector``) on the crank angles theta: x, cos^2 of
        each varying joint, the margins (the loop compiled, one row per angle)."""
        f = self._groups.get("grid")
        if f is None:
            t, P, lp = self._t, self._P, self._lp
            q = [lp.x] + [transmission_cos2(CASADI, lp.transmission[j]) for j in self.joints]
            q += [m for _, m in lp.margins]
            z = casadi.SX.sym("z", 1 + P.numel())
            fn = casadi.Function("grid", [t, P], [casadi.vertcat(*q)])
            f = self._groups["grid"] = Batched(casadi.Function("grid_values", [z], [fn(z[0], z[1:])], CSE))
        if theta.size > f.MAX_ROWS:
            return np.ascontiguousarray(f(np.column_stack([theta, np.broadcast_to(p, (theta.size, p.size))])).T)
        z, out, evaluate = f.buffers(theta.size)
        z[:, 0] = theta
        z[:, 1:] = p
        evaluate()
        return out.T.copy()

    def rates(self, params, theta, omega2: float, alpha2: float, which: str):
        """Compiled time rates at crank angles theta (rad), crank rate omega2 (rad/s) and acceleration alpha2
        (rad/s^2): which = 'x' gives (x, v, a), 'all' gives them and then each link angle, omega, alpha in
        ``angle_names`` order, as rows of an array (3 q, n). On CasADi's VM until a shape of call is hot, then
        machine code: the same numbers to the last bit at every call (the jets, a little faster for a first call,
        differ from both in the last bits)."""
        key = "rates " + which
        f = self._groups.get(key)
        if f is None:
            t, P, lp = self._t, self._P, self._lp
            w, al = casadi.SX.sym("w"), casadi.SX.sym("al")
            out = []
            for q in [lp.x] if which == "x" else [lp.x, *lp.angles.values()]:
                q = casadi.SX(q) + 0 * t
                d1 = casadi.jacobian(q, t)
                d2 = casadi.jacobian(d1, t)
                out += [q, d1 * w, d2 * w * w + d1 * al]
            z = casadi.SX.sym("z", 3 + P.numel())
            fn = casadi.Function("r", [t, w, al, P], [casadi.vertcat(*out)])
            f = self._groups[key] = Batched(casadi.Function(f"rates_{which}", [z], [fn(z[0], z[1], z[2], z[3:])], CSE))
        return f(self._rows(theta, params, omega2, alpha2)).T

    def _rows(self, theta, params, *scalars) -> np.ndarray:
        """The rows z = (theta2, scalars..., parameters) of a compiled call, one per crank angle."""
        theta = np.asarray(theta, float).ravel()
        z = np.empty((theta.size, 1 + len(scalars) + len(self.names)))
        z[:, 0] = theta
        for i, v in enumerate(scalars):
            z[:, 1 + i] = v
        z[:, 1 + len(scalars) :] = self.vector(params)
        return z

    @property
    def angle_names(self) -> list[str]:
        return list(self._lp.angles)

    def grid_coords(self, params, theta):
        """Every joint coordinate (2 per joint, x then y) on the crank angles theta: (C, n)."""
        lp = self.cls.loop(NUMPY, theta, params)
        c = [v for pt in lp.points.values() for v in pt]
        out = np.empty((len(c), theta.size))
        for i, v in enumerate(c):
            out[i] = v
        return out

    # ---- refinement --------------------------------------------------------------------------
    def _switch(self, group: str) -> Batched:
        """One batched Newton call for every slot of a group: each slot runs its own quantity's steps."""
        key = "switch " + group
        f = self._groups.get(key)
        if f is None:
            fs = [q.newton for q in self.group(group)]
            z = casadi.MX.sym("z", 1 + fs[0].size1_in(0))
            sw = casadi.Function.conditional(f"{group}_switch", fs, fs[0])
            f = self._groups[key] = Batched(casadi.Function(f"{group}_newton", [z], [sw(z[0], z[1:])]))
        return f

    def _plan(self, requests):
        """Rows of the grid and signs (+1 max, -1 min) of a request list (kept per list: a handful exist)."""
        key = ("plan", tuple(requests))
        plan = self._groups.get(key)
        if plan is None:
            rows = np.array([q for q, _ in requests], np.int64)
            sgn = np.array([1.0 if kind == "max" else -1.0 for _, kind in requests])
            plan = self._groups[key] = (rows, sgn, sgn[:, None], np.arange(rows.size + 1))
        return plan

    def _driver(self, group: str) -> driver.Driver | None:
        """The group's refinement in C once refined Batched.HOT times (None before, or without a compiler)."""
        if group in self._drivers:
            return self._drivers[group]
        uses = self._refines[group] = self._refines.get(group, 0) + 1
        if uses < Batched.HOT:
            return None
        d = self._drivers[group] = driver.build(self._switch(group).f, f"{group}_refine")
        return d

    def refine(self, group: str, grid_q, requests, p):
        """Extremes of a group's quantities. requests: [(quantity index, 'max' | 'min')].

        grid_q: the quantities on ``cycle.grid(n)`` (Q, n). Returns [Extremes] in request order.
        """
        n = grid_q.shape[1]
        h = TWO_PI / n
        rows, sgn, sgn_col, edges = self._plan(requests)
        d = self._driver(group)
        found = None
        if d is not None and _is_c_float(grid_q) and _is_c_float(p):  # the driver reads them as C arrays
            found = d.refine(grid_q, h, rows, sgn, p)
        if found is None:
            r, theta0, x, ok, val = self._newton(group, grid_q, h, rows, sgn, sgn_col, p)
            if r is None:
                return [Extremes(np.zeros(0), np.zeros(0)) for _ in requests]
            bounds = np.searchsorted(r, edges).tolist()  # r is sorted: each request's slice
            bad = not ok.all()
        else:
            hits, bounds = found
            bad = bounds.pop()  # how many did not converge
            x, val = hits[2].copy(), hits[4].copy()
            if bad:
                r, theta0, ok = hits[0].astype(np.intp), hits[1] * h, hits[3].copy()
        keep = None
        if bad:  # rare: flat, narrow or no extremes; the safeguarded iteration
            quantity_of, keep = rows[r], np.ones(r.size, bool)
            lo, hi = theta0 - h, theta0 + h
            failed = ok == 0
            for q in np.unique(quantity_of[failed]):
                j = np.flatnonzero(failed & (quantity_of == q))
                quantity = self.group(group)[q]
                # a true extreme turns the slope inside its bracket; a jump (an angle wrapping at +-pi) does not
                a, b, turns = _turning(quantity, lo[j], hi[j], sgn[r[j]], p)
                keep[j[~turns]] = False
                j, a, b = j[turns], a[turns], b[turns]
                if j.size:
                    xj = np.mod(self._safeguarded(quantity, a, b, p), TWO_PI)
                    xj[xj > TWO_PI - 1e-12] = 0.0
                    x[j] = xj
                    val[j] = quantity.value(np.column_stack([xj, np.broadcast_to(p, (j.size, p.size))]))[:, 0]
        if keep is None:
            return [Extremes(x[a:b], val[a:b]) for a, b in zip(bounds[:-1], bounds[1:], strict=True)]
        return [Extremes(x[a:b][keep[a:b]], val[a:b][keep[a:b]]) for a, b in zip(bounds[:-1], bounds[1:], strict=True)]

    def _newton(self, group, grid_q, h, rows, sgn, sgn_col, p):
        """The refinement in numpy around one batched Newton call (the driver's loops where none is compiled):
        (request of each hit, its grid angle, theta, converged, value), or Nones where nothing is sampled."""
        n = grid_q.shape[1]
        ext = np.empty((rows.size, n + 2))  # every request as a search for maxima, padded cyclically
        v = ext[:, 1:-1]
        np.multiply(grid_q[rows], sgn_col, out=v)
        ext[:, 0], ext[:, -1] = v[:, -1], v[:, 0]
        hit = v >= ext[:, :-2]  # comparisons with nan are False: a sample next to a nan is never a peak
        hit &= v > ext[:, 2:]
        r, i = np.nonzero(hit)
        if not r.size:
            return None, None, None, None, None
        switch = self._switch(group)
        if r.size <= switch.MAX_ROWS:  # the rows written in place
            z, res, evaluate = switch.buffers(r.size)
        else:
            z, res, evaluate = np.empty((r.size, 7 + p.size)), None, None
        z[:, 0] = rows[r]
        np.multiply(i, h, out=z[:, 1])
        z[:, 2] = h
        z[:, 3:6] = ext[r[:, None], i[:, None] + _THREE]
        z[:, 6] = sgn[r]
        z[:, 7:] = p
        if evaluate is None:
            res = switch(z)
        else:
            evaluate()
        return r, z[:, 1].copy(), res[:, 0].copy(), res[:, 1].copy(), res[:, 2].copy()

    @staticmethod
    def _safeguarded(quantity, lo, hi, p):
        """Bracketed Newton / false position (cycle.stationary) on the exact derivatives."""

        def fun(tj):
            return Jet.of(*quantity.at(tj.v, p))

        return cycle.stationary(fun, lo, hi, iters=60, xtol=1e-14)

    # ---- parameter sensitivities, and many nearby mechanisms at once ---------------------------------------
    TRACK_STEPS = 5  # from a nearby mechanism's stationary point (~1e-3 rad off): 1e-3 -> 1e-6 -> 1e-12 -> rounding
    TRACK_TOL = 1e-11  # rad: a tracked point whose last step is larger is analysed on its own

    def parametric(self, what: str) -> Batched:
        """Exact values and parameter gradients at given crank angles, z = (theta2, p) -> one row (compiled on
        first use). 'x': x, x', x'' (primes d/dtheta2), then dx/dp, dx'/dp, dx''/dp (3 + 3 n entries); a varying
        joint's name: its transmission angle (rad) and d/dp (1 + n)."""
        key = "parametric " + what
        f = self._groups.get(key)
        if f is None:
            t, P, lp = self._t, self._P, self._lp
            if what == "x":
                d = [casadi.SX(lp.x) + 0 * t]
                for _ in range(2):
                    d.append(casadi.jacobian(d[-1], t))
                outs = [*d, *(casadi.jacobian(q, P).T for q in d)]
            elif what in self.joints:
                g = transmission_angle(CASADI, lp.transmission[what])
                outs = [g, casadi.jacobian(g, P).T]
            else:
                raise KeyError(f"no parametric quantity {what!r}: 'x' or one of {self.joints}")
            z = casadi.SX.sym("z", 1 + P.numel())
            fn = casadi.Function("par", [t, P], [casadi.vertcat(*outs)])
            f = self._groups[key] = Batched(casadi.Function(f"parametric_{what}", [z], [fn(z[0], z[1:])], CSE))
        return f

    def tracker(self, group: str, index: int) -> Batched:
        """z = (theta0, p) -> (theta, last Newton step, d2q/dtheta2 there, precise value): TRACK_STEPS exact
        Newton steps on the stationary condition of quantity ``index`` of ``group`` from theta0, unbracketed
        (for a stationary point followed from a nearby mechanism's)."""
        key = f"track {group} {index}"
        f = self._groups.get(key)
        if f is None:
            q = self.group(group)[index]
            d, value = q.derivs.f, q.value.f
            z = casadi.SX.sym("z", 1 + self._P.numel())
            x, p = z[0], z[1:]
            step = casadi.SX(0)
            for _ in range(self.TRACK_STEPS):
                g = d(casadi.vertcat(x, p))
                step = g[1] / g[2]
                x = x - step
            g = d(casadi.vertcat(x, p))
            out = casadi.vertcat(x, step, g[2], value(casadi.vertcat(x, p)))
            f = self._groups[key] = Batched(casadi.Function(f"track_{group}_{index}", [z], [out], CSE))
        return f

    def track(self, group: str, index: int, theta0, P: np.ndarray, sign: float):
        """The stationary points of a quantity near the crank angles theta0 (K,) for the parameter rows P (K, n),
        a maximum (sign +1) or minimum (-1): theta (rad, unwrapped), precise values, and whether each converged
        (last step <= TRACK_TOL rad with the curvature of its kind)."""
        theta0 = np.broadcast_to(np.asarray(theta0, float), (P.shape[0],))
        res = self.tracker(group, index)(np.column_stack([theta0, P]))
        with np.errstate(invalid="ignore"):
            ok = (np.abs(res[:, 1]) <= self.TRACK_TOL) & (sign * res[:, 2] < 0)
        return res[:, 0], res[:, 3], ok

    def grid_many(self, P: np.ndarray, n: int, transmission: bool = True):
        """The loop on ``cycle.grid(n)`` for every parameter row of P (K, n_params), one numpy evaluation:
        x (n, K), each varying joint's transmission angle (n, K) in ``joints`` order (if ``transmission``, else
        []) and each assembly margin."""
        theta = cycle.grid(n)[:, None]
        params = {k: P[:, i][None, :] for i, k in enumerate(self.names)}
        shape = (theta.size, P.shape[0])
        with np.errstate(invalid="ignore", divide="ignore"):
            lp = self.cls.loop(NUMPY, theta, params)
            lines = [lp.transmission[j] for j in self.joints] if transmission else []
            gammas = [np.broadcast_to(transmission_angle(NUMPY, v), shape) for v in lines]
        margins = [np.broadcast_to(m, shape) for _, m in lp.margins]
        return np.broadcast_to(lp.x, shape), gammas, margins


def _is_c_float(a) -> bool:
    return type(a) is np.ndarray and a.dtype == np.float64 and a.flags.c_contiguous


TURN_SAMPLES = 16  # slopes sampled across a bracket whose ends do not turn (another extreme inside it)


def _turning(quantity: _Quantity, lo, hi, sign, p):
    """Brackets [a, b] in [lo, hi] where sign * dq/dtheta2 turns from >= 0 to <= 0 (a maximum of sign * q): the
    whole bracket where its ends turn, else the turn among TURN_SAMPLES sub-intervals nearest its middle (a
    second extreme, less than a grid step away, turns the slope back before the end: the crank shaper whose rod
    nears its reach has two close maxima with a shallow dip between). Returns (a, b, whether any turns)."""
    ends = quantity.at(np.concatenate([lo, hi]), p)[1]
    d_lo, d_hi = sign * ends[: lo.size], sign * ends[lo.size :]
    turns = (d_lo >= 0) & (d_hi <= 0)
    a, b = lo.copy(), hi.copy()
    odd = np.flatnonzero(~turns)
    if odd.size:
        u = np.linspace(0.0, 1.0, TURN_SAMPLES + 1)
        t = lo[odd, None] + (hi - lo)[odd, None] * u
        d = sign[odd, None] * quantity.at(t.ravel(), p)[1].reshape(t.shape)
        turn = (d[:, :-1] >= 0) & (d[:, 1:] <= 0)  # nan compares False: no turn next to a nan
        middle = np.abs(np.arange(TURN_SAMPLES) + 0.5 - TURN_SAMPLES / 2)
        k = np.where(turn, middle, np.inf).argmin(axis=1)
        found = turn[np.arange(odd.size), k]
        rows = np.arange(odd.size)[found]
        a[odd[found]], b[odd[found]] = t[rows, k[found]], t[rows, k[found] + 1]
        turns[odd[found]] = True
    return a, b, turns


RESOLVED = 1e-9  # spectrum tail / largest mode below which the grid resolves a quantity
_ALL, _MAX = np.logical_and.reduce, np.maximum.reduce  # the ufuncs' reductions (the array methods wrap them)


def spectrum(q) -> np.ndarray | None:
    """The discrete Fourier spectrum (rfft) of each row of uniform periodic samples q (Q, n); None if a sample
    is nan or inf."""
    if not _ALL(np.isfinite(q), axis=None):
        return None
    return np.fft.rfft(q, axis=1)


def resolved_spectrum(c) -> bool:
    """Whether spectra c (Q, n // 2 + 1) of finite samples resolve every row: the top quarter of each row's
    modes is below RESOLVED times its largest non-constant mode (so the trigonometric interpolant matches the
    function to that relative level and no extreme hides between samples)."""
    a = np.abs(c)
    scale = _MAX(a[:, 1:], axis=1)
    scale *= RESOLVED
    return bool(_ALL(_MAX(a[:, -(a.shape[1] // 4) :], axis=1) <= scale))


@functools.cache
def spectral_derivative(n: int, order: int) -> np.ndarray:
    """The factors (i k)^order that turn the rfft of n uniform periodic samples into their order-th derivative's
    (d/dtheta2; the Nyquist mode has no odd derivative on the grid). Read-only."""
    k = np.arange(n // 2 + 1)
    if order % 2 and n % 2 == 0:
        k[-1] = 0
    f = (1j * k) ** order
    f.flags.writeable = False
    return f


__all__ = ["kernel", "Kernel", "Extremes", "resolved_spectrum", "spectrum", "spectral_derivative"]
