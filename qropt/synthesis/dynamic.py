"""Dynamic criteria: the peak and RMS crank torque and the peak shaking force, at the problem's omega2 (constant
speed) with its masses and loads (``Problem.masses``, ``Problem.loads``), SI.

Exact values come from ``qropt.dynamics`` (Newton-Euler over the turn). In the NLP the torque at a crank angle is
the power balance ``T = omega2^2 sum(m v_G . a_G + I phi' phi'') + g sum(m v_Gy) + F max(0, w x' omega2) / omega2``
(derivatives in theta2; w the working direction), plus the slide's friction's power ``e x'`` (its load e on the ram
from the Newton-Euler system, ``friction_load``), written from the joints' coordinates and their first and second
derivatives, with the mass model following the design: each bar as long as its joints reach (a lever's sliding
crank pin at most |pivot - O2| + r2 from the pivot, a sliding output at most as far as at a dead centre). The RMS
torque is a Gauss-Legendre quadrature over each stroke on nodes that move with the dead centres, the same rule as
the exact one, so the NLP's value is the certified one.
"""

from __future__ import annotations

import functools
import math

import casadi
import numpy as np

from qropt import units as units_
from qropt.dynamics import applied as exact_loads
from qropt.dynamics.applied import carrier
from qropt.dynamics.model import slender_bar, union
from qropt.dynamics.rigid import body_motion
from qropt.errors import InvalidParameter
from qropt.mechanisms.base import working_sign
from qropt.synthesis import applied as symbolic_loads
from qropt.synthesis.criteria import Criterion, Exchange, register

TWO_PI = 2 * math.pi
LIFTS = (2, 4)  # extremes the NLP lifts for the peak torque and the peak shaking force: the design's degrees of
# freedom + 1 (a minimax optimum equalises that many peaks), at least two (one of two equal peaks is often sharp)
CW_X, CW_Y = "counterweight moment x", "counterweight moment y"  # a free counterweight's variables (kg m)
NO_LOCK = 0.99  # the NLP keeps mu |dN/dF| at most this wherever it states the friction (its closed form's domain)
EXCHANGE_PEAKS = 4  # local maxima the exchange loop looks at: each above the NLP's bound becomes a sample angle


def _abs_torque(d):
    return np.abs(d.torque)


def _shaking(d):
    return np.hypot(d.shaking_force[:, 0], d.shaking_force[:, 1])


def _problem_check(c, problem) -> str | None:
    loads = problem.loads
    if problem.masses is None and loads is None:
        return f"{c.objective} needs masses or loads (Problem(..., masses=qropt.Masses..., loads=qropt.Loads(...)))"
    what = f"the synthesis NLP ({c.objective})"
    if loads is not None and loads.pin_friction is not None:
        return (
            f"{what} cannot apply pin friction (Loads.pin_friction) yet: its friction moments depend on the joint "
            "forces, which it does not solve for exactly; inverse_dynamics, the cycle's extremes, the flywheel and "
            "the efficiency apply it"
        )
    if loads is not None and loads.working is not None:
        return (
            f"{what} takes the slow stroke as the working one; a named working stroke (Loads(working="
            f"{loads.working!r})) is for a mechanism of TR = 1, which a synthesis task does not ask for"
        )
    if loads is not None and (loads.forces or loads.torques):
        cls = problem.mechanism
        link = cls.linkage(dict(cls.PARAMS) | dict(problem.fixed) | {k: lo for k, (lo, _) in problem.free.items()})
        try:
            symbolic_loads.resolved(link, _system(link, cls.__name__, problem.masses), loads)
        except InvalidParameter as e:
            return str(e)
    return None


def _system(link, name, masses):
    """The Newton-Euler structure of the linkage (``qropt.dynamics.inverse._System``) for this mass model."""
    from qropt.dynamics.inverse import _System

    def massive(body):
        if masses is None:
            return False
        return masses.bodies[body].mass > 0 if body in masses.bodies else masses.block > 0

    return _System.of_linkage(link, name, massive)


def _cycle(problem, m):
    """The exact dynamics of design m; a free counterweight at its start (a start's score; a solve's certificate
    is given the problem with the counterweight it chose, ``Formulation.concrete``)."""
    from qropt.dynamics.cycle import CycleDynamics

    masses = problem.masses.started() if problem.masses is not None else None
    return CycleDynamics(m, problem.omega2, 0.0, masses, problem.loads)


class _Symbolic:
    """The formulation's bodies with their mass model as CasADi expressions of the design."""

    def __init__(self, f):
        link = f.mechanism.linkage(f.params)
        self.f, self.k = f, units_.to_metres(f.units)
        self.bodies = link.bodies()
        conns = link.connections()
        self.crank = next(b for b in self.bodies if b.name == "crank")
        self.sliding = {
            b.name: {c.joint for c in conns if c.kind == "slot" and b.name in (c.giver, c.receiver)}
            for b in self.bodies
        }

    def point(self, out, j, order=0):
        i = self.f.joint_index[j]
        c = (out.coords, out.dcoords, out.ddcoords)[order]
        return c[i] * self.k, c[i + 1] * self.k

    def _dist(self, out, a, b):
        (ax, ay), (bx, by) = self.point(out, a), self.point(out, b)
        return casadi.sqrt((bx - ax) ** 2 + (by - ay) ** 2)

    def mass_model(self, out, lengths=None):
        """body -> (mass, (cx, cy), inertia): the problem's overrides, else uniform bars of the density (a plate
        the union of bars from its first joint), the ram and block as points, the counterweight on the crank;
        ``lengths``: body -> a bar's length given (default: the NLP's length variable of each kinked bar)."""
        masses = self.f.masses
        out_models = {}
        if masses is None:
            return out_models
        if lengths is None:
            aux = getattr(self.f, "aux", {})
            lengths = {b: aux[_length_name(b)] for b in self.kinked() if _length_name(b) in aux}
        for b in self.bodies:
            if b.name in masses.bodies:
                bm = masses.bodies[b.name]
                model = (bm.mass, bm.com, bm.inertia)
            elif b.kind in ("ram", "yoke"):
                model = (masses.ram, (0.0, 0.0), 0.0)
            elif b.kind == "block":
                model = (masses.block, (0.0, 0.0), 0.0)
            else:
                model = self._bars(out, b, masses.density, (lengths or {}).get(b.name))
            if b.name == "crank" and masses.balancing:
                model = self._free_counterweight(model, masses.counterweight.radius)
            elif b.name == "crank" and masses.counterweight is not None and masses.counterweight.mass > 0:
                model = union(model, masses.counterweight.part())
            out_models[b.name] = model
        return out_models

    def _free_counterweight(self, crank, radius):
        """The crank with the NLP's counterweight: its first moment (u, v) kg m in the crank's frame is the pair
        of variables, its mass sqrt(u^2 + v^2) / radius (a point: the parallel axes through O2)."""
        u, v = self.f.aux[CW_X], self.f.aux[CW_Y]
        if not getattr(self, "_counterweight_row", False):  # its mass up to the largest
            self._counterweight_row = True
            top = self.f.masses.counterweight.mass * radius
            self.f.row("counterweight: at most its largest mass", u * u + v * v - top * top, -casadi.inf, 0.0)
        mc = casadi.sqrt(u * u + v * v) / radius
        ma, (ax, ay), ia = crank
        mass = ma + mc
        mx, my = ma * ax + u, ma * ay + v
        inertia = ia + ma * (ax * ax + ay * ay) + mc * radius * radius - (mx * mx + my * my) / mass
        return (mass, (mx / mass, my / mass), inertia)

    def _reach_terms(self, out, b, j) -> list:
        """The distances from body b's first joint whose largest is joint j's farthest reach (smooth each)."""
        first = b.joints[0]
        if j not in self.sliding[b.name]:
            return [self._dist(out, first, j)]
        if j == self.crank.joints[1]:  # the crank pin in the lever's slot: at most |pivot - O2| + r2 away
            return [self._dist(out, first, self.crank.joints[0]) + self._dist(out, self.crank.joints[0], j)]
        return [self._dist(d, first, j) for d in self.f.dead]  # a sliding output: at a dead centre

    def _reach(self, out, b, j):
        return _largest(self._reach_terms(out, b, j))

    def kinked(self) -> list:
        """The bars whose length is the largest of several smooth reaches (a kink of the mass model where two
        cross): the NLP gives each a length variable above them all (``_Dynamic.auxiliaries``)."""
        masses = self.f.masses
        if masses is None:
            return []
        if getattr(self, "_kinked", None) is None:
            self._kinked = self._find_kinked(masses)
        return self._kinked

    def _find_kinked(self, masses) -> list:
        return [
            b.name
            for b in self.bodies
            if b.name not in masses.bodies
            and b.kind in ("bar", "slot-lever")
            and sum(len(self._reach_terms(self.f.dead[0], b, j)) for j in b.joints[1:]) > 1
        ]

    def length_terms(self, name) -> list:
        b = next(x for x in self.bodies if x.name == name)
        return [t for j in b.joints[1:] for t in self._reach_terms(self.f.dead[0], b, j)]

    def _bars(self, out, b, density, length=None):
        reaches = [self._reach(out, b, j) for j in b.joints[1:]]
        if b.kind != "plate":
            return slender_bar(density, _largest(reaches) if length is None else length)
        (ox, oy), (sx, sy) = self.point(out, b.joints[0]), self.point(out, b.joints[1])
        phi = casadi.atan2(sy - oy, sx - ox)
        model = None
        for j, L in zip(b.joints[1:], reaches, strict=True):
            jx, jy = self.point(out, j)
            a = casadi.atan2(jy - oy, jx - ox) - phi
            part = slender_bar(density, L, casadi.cos(a), casadi.sin(a))
            model = part if model is None else union(model, part)
        return model

    def triples(self, out, b) -> dict:
        """joint -> ((x, x', x''), (y, y', y'')) (SI, per unit theta2) of body b's first two joints."""
        return {j: tuple(tuple(self.point(out, j, k)[i] for k in range(3)) for i in (0, 1)) for j in b.joints[:2]}

    def motion(self, out, b, com):
        """(G, v_G, a_G, (cos phi, sin phi, phi', phi'')) of body b per unit theta2 (SI), by ``body_motion``."""
        return body_motion(b, com, self.triples(out, b))

    def gravity(self) -> tuple:
        """(gx, gy) (m/s^2)."""
        return self.f.loads.gravity_vector if self.f.loads is not None else (0.0, 0.0)

    def general(self, out, working=None) -> list:
        """The forces and torques of ``Loads`` at one point (``symbolic_loads.at``; ``working`` as ``forces``)."""
        loads = self.f.loads
        if loads is None or not (loads.forces or loads.torques):
            return []
        if getattr(self, "_resolved", None) is None:
            self._resolved = symbolic_loads.resolved(self.f.mechanism.linkage(self.f.params), self.system(), loads)
            self._tables = {}
        way = working_sign(self.f.orientation > 0, self.f.omega2)
        return symbolic_loads.at(self, self._resolved, out, working, way, self.f.omega2, self._tables)

    def particles(self, out) -> list:
        """The point masses (``Masses.points``) at one point: (body that carries it, kg, its joint's (x, y), velocity
        and acceleration per unit theta2), SI."""
        masses = self.f.masses
        if masses is None or not masses.points:
            return []
        link = self.f.mechanism.linkage(self.f.params)
        return [
            (carrier(link, link, j), mass, self.point(out, j), self.point(out, j, 1), self.point(out, j, 2))
            for j, mass in masses.points.items()
        ]

    def kinematics(self, out, b, com):
        """(v_G, a_G, phi', phi'') of body b per unit theta2 (SI)."""
        _, v, a, rot = self.motion(out, b, com)
        return v, a, rot[2], rot[3]

    def centre(self, out, b, com):
        """The centre of mass G of body b (SI)."""
        return self.motion(out, b, com)[0]

    def system(self):
        """The Newton-Euler structure of the linkage (``qropt.dynamics.inverse._System``)."""
        if getattr(self, "_system", None) is None:
            link = self.f.mechanism.linkage(self.f.params)
            self._system = _system(link, self.f.mechanism.__name__, self.f.masses)
        return self._system

    def forces(self, out, working=None, lengths=None) -> tuple:
        """(x, e): the Newton-Euler unknowns at one crank angle at constant omega2 as expressions (the torque,
        every pin's force, a slot's and the guide's normal force), the system assembled by the same code as the
        exact analysis and solved by the structure's sparse elimination, and the slide's friction as a load on the
        ram's row (``friction_load``; 0 without friction). The cutting force on (``working`` True), off (False)
        or by the ram's velocity (None); the friction against the ram's velocity, or its stroke's direction where
        ``working`` is given; ``lengths`` as ``mass_model``."""
        from qropt.dynamics.elimination import Elimination
        from qropt.dynamics.inverse import friction_load

        self.no_lock()
        f, s = self.f, self.system()
        entries, rhs = self._assembled(out, lengths, working)
        ram = s.output
        force = self.cutting_force(out)
        way = working_sign(f.orientation > 0, f.omega2)
        if ram is not None and not (isinstance(force, (int, float)) and not force):  # against the working stroke
            r = s.rows[ram.name]
            on = -force * way
            load = casadi.if_else(way * out.v * f.omega2 > 0, on, 0.0) if working is None else on * working
            rhs[r] = rhs.get(r, 0.0) - load
        elim = Elimination(entries, s.n, None)
        x = elim.solve(rhs)
        col = self.guide()
        if col is None:
            return x, 0
        unit = elim.solve({s.load_row(): 1.0})  # the unknowns' change per newton on the ram's row
        self._no_lock_at(out, unit[col])
        sigma = casadi.sign(out.v * f.omega2) if working is None else (way if working else -way)
        e = friction_load(casadi, x[col], unit[col], f.loads.friction, sigma)
        return [p + q * e for p, q in zip(x, unit, strict=True)], e

    def _assembled(self, out, lengths=None, working=None) -> tuple:
        """The Newton-Euler system at one crank angle at constant omega2: (entries, right-hand sides) with the
        mass model (``lengths`` as ``mass_model``), gravity, the point masses and the general loads (``working``
        as ``forces``), no cutting force. A known force F at p and torque tau on a body leave its rows as
        -(F, (p - G) x F + tau); a point mass m at p adds m (a - g) and (p - G) x m (a - g)."""
        f, s = self.f, self.system()
        w2 = f.omega2**2
        models = self.mass_model(out, lengths)
        kin = {}
        for b in s.bodies:
            mass, com, inertia = models.get(b.name, (0.0, (0.0, 0.0), 0.0))
            _, a, _, al = self.kinematics(out, b, com)
            kin[b.name] = (self.centre(out, b, com), (a[0] * w2, a[1] * w2), al * w2, mass, inertia)
        P = {j: self.point(out, j) for j in f.joint_index}
        g = f.loads.gravity if f.loads is not None else 0.0
        tilted = isinstance(g, tuple)  # a gravity vector's weights go on the rows below
        entries, rows = s.assemble(P, kin, 0.0 if tilted else g, casadi.sqrt)
        rows = dict(rows)
        gx, gy = self.gravity()

        def add(body, fx, fy, at):
            r, G = s.rows[body], kin[body][0]
            rows[r] = rows.get(r, 0.0) + fx
            rows[r + 1] = rows.get(r + 1, 0.0) + fy
            if s.kind(body) != "ram":
                rows[r + 2] = rows.get(r + 2, 0.0) + (at[0] - G[0]) * fy - (at[1] - G[1]) * fx

        for b in s.bodies if tilted else ():
            mass = kin[b.name][3]
            add(b.name, -mass * gx, -mass * gy, kin[b.name][0])
        for body, mass, p, _, a in self.particles(out):
            add(body, mass * (a[0] * w2 - gx), mass * (a[1] * w2 - gy), p)
        for load in self.general(out, working):  # known loads leave the right-hand side
            for r, v in exact_loads.rows(s, load, kin[load.body][0]):
                rows[r] = rows.get(r, 0.0) - v
        return entries, rows

    def no_lock(self):
        """Rows that keep the slide from locking (mu |dN/dF| <= NO_LOCK, where ``friction_load`` holds) at every
        sample, once per formulation, from the first expression that needs them; none without friction."""
        from qropt.dynamics.elimination import Elimination

        col = self.guide()
        if col is None or getattr(self, "_no_lock", False):
            return
        self._no_lock = True
        s = self.system()
        for out in self.f.sampled:
            entries, _ = self._assembled(out)
            self._no_lock_at(out, Elimination(entries, s.n, None).solve({s.load_row(): 1.0})[col])

    def _no_lock_at(self, out, n1):
        """The no-lock row at one point where the friction is used (a sample, a stroke's or the quadrature's node,
        a lifted angle), once per point; n1: dN/dF there."""
        kept = self.__dict__.setdefault("_lock_points", [])
        if any(o is out for o in kept):
            return
        kept.append(out)
        mu = self.f.loads.friction
        self.f.row(f"the slide does not lock at point {len(kept)}", (mu * n1) ** 2, -casadi.inf, NO_LOCK**2)

    def guide(self) -> int | None:
        """The guide's normal force's column where the slide has friction, else None."""
        f = self.f
        if f.loads is None or not f.loads.friction:
            return None
        return next((col for c, col, _ in self.system().cols if c.kind == "guide"), None)

    def bearing_loads(self, out, working=None):
        """joint -> |force|^2 (N^2) at one crank angle at constant omega2: every pin and every block or pin in a
        slot (what its pin carries), from ``forces``."""
        s = self.system()
        x, _ = self.forces(out, working)
        loads = {}
        for c, col, _ in s.cols:
            if c.kind == "pin" and not (s.block_massive and s.kind(c.receiver) == "block"):
                loads[c.joint] = x[col] ** 2 + x[col + 1] ** 2
            elif c.kind == "slot":
                loads[c.joint] = x[col] ** 2
        return loads

    def torque(self, out, lengths=None):
        """The crank torque (N m) at constant omega2 at one crank angle (``lengths`` as ``mass_model``): the power
        balance, with the slide's friction's power ``e v`` (``friction_load``'s e on the ram's row) where it
        has friction."""
        f = self.f
        w2 = f.omega2**2
        g = f.loads.gravity if f.loads is not None else 0.0
        gx, gy = self.gravity()
        T = 0
        for name, (m, com, inertia) in self.mass_model(out, lengths).items():
            b = next(x for x in self.bodies if x.name == name)
            v, a, w, al = self.kinematics(out, b, com)
            weight = -m * (gx * v[0] + gy * v[1]) if isinstance(g, tuple) else g * m * v[1]
            T += w2 * (m * (v[0] * a[0] + v[1] * a[1]) + inertia * w * al) + weight
        for _, m, _, v, a in self.particles(out):
            T += m * (w2 * (v[0] * a[0] + v[1] * a[1]) - (gx * v[0] + gy * v[1]))
        for load in self.general(out):
            T -= load.force[0] * load.velocity[0] + load.force[1] * load.velocity[1] + load.torque * load.spin
        return T + self.load(out) + self.friction_torque(out, lengths)

    def friction_torque(self, out, lengths=None):
        """The torque (N m) the slide's friction takes: its power mu |N| |v| over omega2, which is e x' with e
        the friction as a load on the ram's row (``friction_load``) and x' = dx/dtheta2 (m/rad)."""
        if self.guide() is None:
            return 0
        return self.forces(out, None, lengths)[1] * out.v * self.k

    def load(self, out):
        f, loads = self.f, self.f.loads
        if loads is None:
            return 0
        force = self.cutting_force(out) if f.mechanism.OUTPUT == "slider" else loads.follower_torque
        if isinstance(force, (int, float)) and not force:
            return 0
        scale = self.k if f.mechanism.OUTPUT == "slider" else 1.0
        way = working_sign(f.orientation > 0, f.omega2)
        return force * casadi.fmax(0, way * out.v * scale * f.omega2) / f.omega2

    def cutting_force(self, out):
        """The cutting force's magnitude (N) at the ram's position: the constant, or the table interpolated as
        ``Loads.force_at`` does (linear between rows, constant beyond them)."""
        table = self.f.loads.cutting_force if self.f.loads is not None else 0.0
        if not isinstance(table, tuple):
            return table
        xs, fs = [float(r[0]) for r in table], [float(r[1]) for r in table]
        if len(xs) == 1:
            return fs[0]
        if getattr(self, "_table", None) is None:
            self._table = casadi.interpolant("cutting_force", "linear", [xs], fs)
        return self._table(casadi.fmin(casadi.fmax(out.x, xs[0]), xs[-1]))

    def shaking_squared(self, out):
        """|sum(m a_G)|^2 at constant omega2 (N^2)."""
        self.no_lock()  # the exact value, like every dynamic one, needs a slide that does not lock
        w2 = self.f.omega2**2
        sx = sy = 0
        for name, (m, com, _) in self.mass_model(out).items():
            b = next(x for x in self.bodies if x.name == name)
            _, a, _, _ = self.kinematics(out, b, com)
            sx, sy = sx + m * a[0] * w2, sy + m * a[1] * w2
        for _, m, _, _, a in self.particles(out):
            sx, sy = sx + m * a[0] * w2, sy + m * a[1] * w2
        return sx * sx + sy * sy


def _largest(terms):
    out = terms[0]
    for t in terms[1:]:
        out = casadi.fmax(out, t)
    return out


def _length_name(body: str) -> str:
    return f"length of the {body}"


def _symbolic(f) -> _Symbolic:
    s = getattr(f, "_dynamic_symbolic", None)
    if s is None:
        s = f._dynamic_symbolic = _Symbolic(f)
    return s


class _Dynamic(Criterion):
    """Shared by the dynamic criteria: a relative gap (they are in newtons), the problem's check."""

    needs_masses, kinematic = True, False

    def applies(self, cls) -> bool:  # a type declared with the builder (its bodies and joints are known)
        return cls.linkage(dict(cls.PARAMS)) is not None

    def why_not(self, cls) -> str:
        return (
            f"{cls.__name__} is not declared with the linkage builder (qropt.mechanisms.builder), so its bodies and "
            "joints, which the dynamics need, are unknown"
        )

    def check(self, problem) -> str | None:
        return _problem_check(self, problem)

    def auxiliaries(self, f):  # a kinked bar's length: a variable above each of its reaches and below the one that
        # is the farthest at the design the solve is at (smooth where they cross; the exchange loop moves the pick)
        s = _symbolic(f)
        out = [(_length_name(name), s.length_terms(name), 0.0, True) for name in s.kinked()]
        if f.masses is not None and f.masses.balancing:  # a free counterweight: its first moment, from its start
            cw = f.masses.counterweight
            out += [(CW_X, [], -cw.mass * cw.radius / 2, False), (CW_Y, [], 0.0, False)]
        return out

    def to_nlp(self, v, omega2):
        return v

    def from_nlp(self, y, omega2):
        return y


class _Squared(_Dynamic):
    """A criterion the NLP states squared (a force's magnitude: smooth where the magnitude's root is not)."""

    def to_nlp(self, v, omega2):
        return v * v

    def from_nlp(self, y, omega2):
        return math.sqrt(max(y, 0.0))


class PeakOverTurn(_Dynamic):
    """A peak over the turn (of ``quantity`` of the cycle's dynamics) whose largest extremes the NLP lifts
    (stationary in theta2) and whose exchange adds every extreme above the NLP's value; ``lifted`` gives the
    NLP's expression of it at one crank angle and the terms it bounds."""

    what = ""  # the extreme's name in the NLP's rows

    @staticmethod
    def quantity(d):  # pragma: no cover - abstract
        raise NotImplementedError

    def lifted(self, s, out) -> tuple:  # pragma: no cover - abstract
        """(the expression whose stationarity a lift states, the epigraph terms it gives)."""
        raise NotImplementedError

    def value(self, problem, m):
        return _cycle(problem, m).peak(self.quantity).value

    def epigraph(self, f):
        s = _symbolic(f)
        return [(self.epigraph_name, [t for out in f.sampled for t in self.lifted(s, out)[1]])]

    def lifts(self, f, role):  # the largest extremes, lifted like the peak acceleration's
        free = len(f.free) - len(f.targets) + (2 if f.masses is not None and f.masses.balancing else 0)
        return min(max(LIFTS[0], free + 1), LIFTS[1])

    def lift_terms(self, f, k, phi, out):
        expr, terms = self.lifted(_symbolic(f), out)
        f.row(f"lifted {self.what} extreme: stationary", casadi.jacobian(expr, phi), 0.0, 0.0, kind="lift")
        return terms

    def lift_start(self, f, problem, m, n):  # at the largest extremes exactly: the stationarity rows start met
        return [p.theta2 for p in _cycle(problem, m).peaks(self.quantity, n)]

    def exchange(self, f, problem, m, z, value_nlp, gap_tol):
        peaks = _cycle(problem, m).peaks(self.quantity, EXCHANGE_PEAKS)
        top = self.to_nlp(peaks[0].value, 1.0)
        gap = (top - z[0]) / max(1.0, top)
        add = [q.theta2 for q in peaks if self.to_nlp(q.value, 1.0) > z[0]] if gap > gap_tol else []
        return Exchange(self.from_nlp(z[0], 1.0), peaks[0].value, gap, add, [])

    def exceeded(self, problem, m):
        return [_cycle(problem, m).peak(self.quantity).theta2], []


class PeakTorque(PeakOverTurn):
    """The largest |crank torque| over the turn at constant omega2 (N m)."""

    name, unit, label = "peak_torque", "N m", "peak crank torque"
    what, epigraph_name = "torque", "peak |crank torque|"
    quantity = staticmethod(_abs_torque)
    # near a toggle the torque spikes between the NLP's samples and IPOPT's runs end at the iteration limit there:
    # the multi-start is run again with every transmission angle above this
    guard = math.radians(10.0)

    def lifted(self, s, out):
        T = s.torque(out)
        return T, [T, -T]


@functools.cache
def _rule(n: int | None):
    """The Gauss-Legendre rule of n nodes, or of the cycle module's (the certifier's) where n is None."""
    from qropt.dynamics.cycle import GAUSS

    return np.polynomial.legendre.leggauss(GAUSS if n is None else n)


def quadrature_rule(f):
    """The quadrature rule of formulation f: the certifier's, or its coarse rule of ``f.coarse`` nodes a stroke."""
    return _rule(f.coarse or None)


class RmsTorque(_Squared):
    """The root mean square of the crank torque over the turn at constant omega2 (N m): a quadrature, the same
    Gauss-Legendre rule on each stroke in the NLP as in the exact value; the NLP states the mean square."""

    name, unit, label = "rms_torque", "N m", "RMS crank torque"
    coarse = True

    def value(self, problem, m):
        return math.sqrt(_cycle(problem, m).quadrature(lambda d: d.torque**2) / TWO_PI)

    def measure(self, f, z):
        s = _symbolic(f)
        total = 0
        for out, w, arc in f.strokes(quadrature_rule(f)):
            total += 0.5 * arc * w * s.torque(out) ** 2
        return total / TWO_PI

    def exchange(self, f, problem, m, z, value_nlp, gap_tol):
        exact = self.value(problem, m)
        nlp = None if value_nlp is None else self.from_nlp(float(value_nlp), 1.0)
        gap = 0.0 if nlp is None else abs(exact**2 - float(value_nlp)) / max(1.0, exact**2)
        return Exchange(nlp, exact, gap, [], [])


class ShakingForce(_Squared, PeakOverTurn):
    """The largest shaking force |sum(m a_G)| over the turn at constant omega2 (N); the NLP bounds its square."""

    name, unit, label = "shaking_force", "N", "peak shaking force"
    what, epigraph_name = "shaking", "peak |shaking force|^2"
    quantity = staticmethod(_shaking)

    def lifted(self, s, out):
        s2 = s.shaking_squared(out)
        return s2, [s2]


class PeakBearingForce(_Squared):
    """The largest force a bearing carries over the turn at constant omega2 (N): every pin and every block or pin
    in a slot, or one named joint (``PeakBearingForce("O2")``, registered as ``peak_bearing_force_O2``)."""

    unit, label, slider_only = "N", "peak bearing force", True

    def __init__(self, joint: str | None = None):
        self.joint = joint
        self.name = "peak_bearing_force" + (f"_{joint}" if joint else "")
        self.label = "peak bearing force" + (f" at {joint}" if joint else "")

    def _peak(self, problem, m):
        def worst(d):
            keys = [k for k in d.joint_forces if k != "slide" and (self.joint is None or k == self.joint)]
            if not keys:
                raise InvalidParameter(f"{type(m).__name__} has no joint {self.joint!r}: {sorted(d.joint_forces)}")
            return np.max([np.hypot(*d.joint_forces[k].T) for k in keys], axis=0)

        return _cycle(problem, m).peak(worst, jumps=True)

    def value(self, problem, m):
        return self._peak(problem, m).value

    def epigraph(self, f):
        s = _symbolic(f)
        if (
            f.loads is not None and f.loads.jumps
        ):  # the loads jump at the dead centres: each stroke's samples with its own load
            outs = [(o, True) for o in f.working()] + [(o, False) for o in f.returning()]
        else:
            outs = [(o, None) for o in f.sampled]
        exprs = []
        for out, working in outs:
            loads = s.bearing_loads(out, working)
            exprs += [v for k, v in loads.items() if self.joint is None or k == self.joint]
        return [(f"peak {self.label}^2", exprs)]

    def exchange(self, f, problem, m, z, value_nlp, gap_tol):
        p = self._peak(problem, m)
        gap = (p.value**2 - z[0]) / max(1.0, p.value**2)
        add, frac = self._placed(problem, m, p.theta2) if gap > gap_tol else ([], [])
        return Exchange(self.from_nlp(z[0], 1.0), p.value, gap, add, frac)

    def exceeded(self, problem, m):
        return self._placed(problem, m, self._peak(problem, m).theta2)

    @staticmethod
    def _placed(problem, m, theta):
        """Where a sample goes for crank angle theta: the angle itself, or (the loads switching) its fraction of
        its stroke, which the working and the return samples share."""
        if problem.loads is None or not problem.loads.jumps:
            return [theta], []
        lo, length = m.working_arc()
        d = (theta - lo) % TWO_PI
        return [], [d / length if d <= length else (d - length) / (TWO_PI - length)]


for _c in (PeakTorque(), RmsTorque(), ShakingForce(), PeakBearingForce()):
    register(_c, built_in=True)

__all__ = ["PeakTorque", "RmsTorque", "ShakingForce", "PeakBearingForce", "quadrature_rule"]
