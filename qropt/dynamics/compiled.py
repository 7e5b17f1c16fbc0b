"""The inverse dynamics of one linkage structure as one compiled call per crank angle: the loop's exact rates
(CasADi's derivatives of the same loop code), each body's motion (``rigid.body_motion``), the Newton-Euler system
(``_System.assemble``) and its elimination in the structure's order (``Elimination``), as one CasADi function
compiled to machine code once it is used often (``kinematics.kernel.Batched``), on CasADi's virtual machine until
then and without a compiler: the same numbers to the last bit, so that a result does not depend on how often the
process evaluated the structure before (the jets' numbers differ in the last bits, and a dynamic solve's path can
follow them to a different design). Where a row is not finite (a singular angle) the jets and numpy
(``inverse._numpy_parts``) compute it and report where.

One function serves every design and mass model of a type: the parameters, the bodies' masses, centres and
inertias, omega2, alpha2, gravity, the length unit and a load known beforehand (a constant cutting force, a
follower's torque) are its inputs. A load that depends on the motion (a table of the ram's position, friction's
iteration) is added in numpy: the superposed variant gives the unknowns per unit load too.

General loads (forces, torques, a gravity vector: ``qropt.dynamics.applied``) take a variant per structure and
per layout of the loads (each load's body and where it acts: a joint, a body point, a torque): its inputs add
gravity's x component and the body points' coordinates; its outputs add the unknowns per unit load on each row a
load enters (the system is linear in its right-hand side), each force's point and that point's velocity
(``applied.geometry``, the same formulas on CasADi expressions), the loaded bodies' centres of mass and the
mechanism's size. What a load is at each angle (its window, its table, its direction against a velocity:
``applied.act``) and what it takes off each row (``applied.rows``) is then numpy on those outputs, the rules of the
numpy route itself; the unknowns are the kernel's less each row's load times the unknowns per unit load there. Pin
friction is not the kernel's: ``inverse`` solves it on the jets in numpy (``parts`` refuses it where it is given the
loads)."""

from __future__ import annotations

import weakref

import casadi
import numpy as np

from qropt.dynamics import applied
from qropt.dynamics.elimination import Elimination, Parts
from qropt.dynamics.model import Force
from qropt.dynamics.rigid import body_motion, shaking
from qropt.errors import UnsupportedLoad
from qropt.kinematics.kernel import CSE, Batched
from qropt.kinematics.ops import CASADI

_KERNELS: dict = {}
_PLANS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()  # system -> {(superposed, id(resolved)): _Plan}
SKIP = 32  # crank angles from which a general load's row that is zero at all of them is skipped (not worth a test)


def _key(m, s, superposed: bool, layout) -> tuple:
    return (type(m), tuple(m.params), tuple(b.name for b in s.bodies), s.block_massive, superposed, layout)


def layout(resolved) -> tuple:
    """What of resolved general loads (``applied.resolve``) shapes a kernel: per load its body and where it acts
    (a joint's name, "point" for a body point, whose coordinates are the kernel's inputs, None for a torque). Their
    magnitudes, tables, windows and directions are not the kernel's: ``applied.act`` applies them in numpy."""
    return tuple(
        (body, (load.at if isinstance(load.at, str) else "point") if isinstance(load, Force) else None)
        for load, body in resolved
    )


def kernel(m, s, superposed: bool = False, resolved=None) -> Batched:
    """The compiled dynamics of m's structure (type, parameter names, bodies) under the system s; ``superposed``:
    also the unknowns per unit load (for a load that depends on the motion, or friction's iteration);
    ``resolved``: general loads (``applied.resolve``; any loads of the same ``layout`` share the kernel), or
    None for the shorthands."""
    lay = None if resolved is None else layout(resolved)
    key = _key(m, s, superposed, lay)
    f = _KERNELS.get(key)
    if f is None:
        f = _KERNELS[key] = Batched(_function(m, s, superposed, resolved))
    return f


class _Plan:
    """Where a general variant's outputs lie, for resolved loads on one system (``_general`` reads them)."""

    def __init__(self, m, s, superposed: bool, resolved):
        K = s.n
        self.f = kernel(m, s, superposed, resolved)
        self.resolved = resolved  # kept: the plan is found by its identity
        self.coords = [c for i in _points(resolved) for c in resolved[i][0].at[1:]]
        i = (2 * K if superposed else K) + 5 + 2 * sum(c.kind == "slot" for c, _, _ in s.cols)
        self.units = {q: (i + j * K, i + (j + 1) * K) for j, q in enumerate(_loaded_rows(s, resolved))}
        i += len(self.units) * K
        self.block = i  # from here: the size, each force's point and velocity, the loaded bodies' centres
        self.geo, i = [], 1  # within the block
        for load, _ in resolved:
            self.geo.append(i if isinstance(load, Force) else None)
            i += 4 if isinstance(load, Force) else 0
        self.centres = {}
        for body in _loaded_bodies(resolved):
            self.centres[body] = i
            i += 2
        self.end = self.block + i
        self.ram = m.output_joint() is not None
        self.against = any(isinstance(load, Force) and load.direction == "against" for load, _ in resolved)


def _plan(m, s, superposed: bool, resolved) -> _Plan:
    """The plan of resolved loads on the system s (one mechanism and mass model), found by the loads' identity
    (``inverse._resolved`` keeps their resolution); kept beside s, not on it (a system stays data: it pickles)."""
    plans = _PLANS.get(s)
    if plans is None:
        plans = _PLANS[s] = {}
    p = plans.get((superposed, id(resolved)))
    if p is None or p.resolved is not resolved:
        if len(plans) >= 32:
            plans.clear()
        p = plans[(superposed, id(resolved))] = _Plan(m, s, superposed, resolved)
    return p


def _loaded_rows(s, resolved) -> list[int]:
    """The rows general loads enter: each loaded body's x and y rows and its moment row (none on a point ram)."""
    out = []
    for _, body in resolved:
        r = s.rows[body]
        for q in (r, r + 1) if s.kind(body) == "ram" else (r, r + 1, r + 2):
            if q not in out:
                out.append(q)
    return out


def _loaded_bodies(resolved) -> list[str]:
    return list(dict.fromkeys(body for _, body in resolved))


def _points(resolved) -> list[int]:
    """The indices of the forces at body points (their coordinates are inputs)."""
    return [i for i, (load, _) in enumerate(resolved) if isinstance(load, Force) and not isinstance(load.at, str)]


def _function(m, s, superposed: bool, resolved=None) -> casadi.Function:
    names = list(m.params)
    t, w, al, g, k, load = (casadi.SX.sym(n) for n in ("t", "w", "al", "g", "k", "load"))
    P = casadi.SX.sym("p", len(names))
    lp = type(m).loop(CASADI, t, {n: P[i] for i, n in enumerate(names)})

    def rates(q):
        q = casadi.SX(q) + 0 * t
        d1 = casadi.jacobian(q, t)
        return q * k, d1 * w * k, (casadi.jacobian(d1, t) * w * w + d1 * al) * k

    pts = {j: (rates(x), rates(y)) for j, (x, y) in lp.points.items()}
    B = casadi.SX.sym("b", 4 * len(s.bodies))
    kin, v_out = {}, 0.0
    for i, b in enumerate(s.bodies):
        mass, cx, cy, inertia = (B[4 * i + j] for j in range(4))
        G, v, a, rot = body_motion(b, (cx, cy), pts)
        kin[b.name] = (G, a, rot[3], mass, inertia)
        if b is s.output:
            v_out = v[0]
    at = {j: (x[0], y[0]) for j, (x, y) in pts.items()}
    entries, rows = s.assemble(at, kin, g, casadi.sqrt)
    extra = []  # the general variant's inputs: gravity's x component, the body points' coordinates
    if resolved is not None:
        gx = casadi.SX.sym("gx")
        C = casadi.SX.sym("c", 2 * len(_points(resolved)))
        extra = [gx, C]
        for b in s.bodies:  # a gravity vector (gx, -g): its x weight leaves the x row, as in ``inverse._apply``
            r = s.rows[b.name]
            rows[r] = rows.get(r, 0.0) - kin[b.name][3] * gx
    elim = Elimination(entries, s.n, None)
    r = s.load_row()
    if r is not None:
        rows[r] = rows.get(r, 0.0) + load
    out = list(elim.solve(rows))
    if superposed:
        out += list(elim.solve({r: 1.0})) if r is not None else [0.0] * s.n
    joint = m.output_joint()
    x_out = at[joint][0] / k if joint else (kin[s.output.name][0][0] / k if s.output is not None else 0.0)
    out += [x_out, v_out, *shaking(kin)]
    for c, _, _ in s.cols:
        if c.kind == "slot":
            out += list(s.normal(c, at, casadi.sqrt))
    if resolved is not None:
        for q in _loaded_rows(s, resolved):  # the unknowns per unit load on each loaded row
            out += list(elim.solve({q: 1.0}))
        out.append(casadi.mmax(casadi.vertcat(*(casadi.sqrt(x * x + y * y) for x, y in at.values()))))
        points = _points(resolved)
        coords = [
            (C[2 * points.index(i)], C[2 * points.index(i) + 1]) if i in points else None for i in range(len(resolved))
        ]
        for (what, _), (p, v, _) in zip(resolved, applied.geometry(s, resolved, pts, coords), strict=True):
            if isinstance(what, Force):
                out += [p[0], p[1], v[0], v[1]]
        for body in _loaded_bodies(resolved):
            out += list(kin[body][0])
    f = casadi.Function("dynamics", [t, w, al, g, k, load, P, B, *extra], [casadi.vertcat(*out)])
    z = casadi.SX.sym("z", 6 + P.numel() + B.numel() + sum(e.numel() for e in extra))
    n = 6 + P.numel()
    args = [z[i] for i in range(6)] + [z[6:n], z[n : n + B.numel()]]
    if extra:
        n += B.numel()
        args += [z[n], z[n + 1 :]]
    return casadi.Function(f"dynamics_{type(m).__name__}", [z], [f(*args)], CSE)


def parts(m, s, t, omega2, alpha2, g, k, known=None, superposed=False, loads=None, general=None):
    """``elimination.Parts`` from the structure's Function (``known``: the load that does not depend on the motion,
    (n,) on the load's row, or None), or None where a row is not finite (a singular angle, which the numpy route
    reports). ``general``: the general loads as ``inverse`` states them for the numpy route, (loads, their
    ``applied.resolve``, the working stroke's mask, the output's way along each closed stroke or None), or None;
    ``loads``: checked where given (UnsupportedLoad for pin friction, which ``inverse`` solves on the jets in numpy,
    and for general loads or a gravity vector without ``general``)."""
    if loads is not None and loads.pin_friction is not None:
        raise UnsupportedLoad(
            "the compiled dynamics kernel cannot apply pin friction (Loads.pin_friction): its moments need the "
            "elimination per unit moment; inverse_dynamics solves it on the jets in numpy"
        )
    if general is None and loads is not None and loads.general:
        raise UnsupportedLoad(
            f"the compiled dynamics kernel applies {loads.general[0]} with the loads resolved (general=...), as "
            "inverse_dynamics gives them"
        )
    if general is None and isinstance(g, tuple):
        raise UnsupportedLoad(
            f"the compiled dynamics kernel cannot apply gravity {g} alone (it takes a number g along -y); "
            "inverse_dynamics gives a gravity vector with the loads resolved (general=...)"
        )
    n = t.size
    plan = None if general is None else _plan(m, s, superposed, general[1])
    # CasADi's VM until its calls are HOT, then machine code: the same numbers
    f = kernel(m, s, superposed) if plan is None else plan.f
    head = [0.0, omega2, alpha2, g, k, 0.0, *m.params.values(), *(v for b in s.bodies for v in _body(s.props[b.name]))]
    if plan is not None:
        gx, gy = g if isinstance(g, tuple) else (0.0, -g)
        head[3] = -gy
        head += [gx, *plan.coords]
    z = np.empty((n, f.m))
    z[:] = head
    z[:, 0] = t
    if known is not None:
        z[:, 5] = known
    out = f(z)
    if not np.isfinite(out).all():
        return None
    a = _unpack(out, s, superposed)
    return a if plan is None else _general(s, t, omega2, out, a, superposed, general, plan)


def _body(bm) -> tuple:
    return bm.mass, bm.com[0], bm.com[1], bm.inertia


def _unpack(out, s, superposed):
    K = s.n
    cols = out.T
    x0, u = out[:, :K], (out[:, K : 2 * K] if superposed else None)

    def solve(extra):  # the unknowns as K rows of a (K, n) view, in one operation
        return x0.T if extra is None else (x0 + extra[:, None] * u).T

    i = 2 * K if superposed else K
    x_out, v_out, sfx, sfy, sm = cols[i : i + 5]
    normals, i = {}, i + 5
    for c, _, _ in s.cols:
        if c.kind == "slot":
            normals[c.joint] = (cols[i], cols[i + 1])
            i += 2
    return Parts(solve, x_out, v_out, normals, (sfx, sfy, sm))


def _general(s, t, omega2, out, a: Parts, superposed: bool, general, plan: _Plan) -> Parts:
    """The parts with the general loads: the kernel's unknowns less each loaded row's load (``applied.act``,
    ``applied.rows`` on the kernel's geometry) times the unknowns per unit load on that row."""
    _, resolved, working, ends = general
    K = s.n
    cols = out.T[plan.block : plan.end]
    if t.size >= SKIP:  # many angles: the block's columns as contiguous rows (numpy's strided loops are slower)
        cols = np.ascontiguousarray(cols)
    geo = []
    for i in plan.geo:  # a torque has no force, so no point (and its body's turn is not needed: 0.0 here)
        geo.append(
            ((0.0, 0.0), (0.0, 0.0), 0.0) if i is None else ((cols[i], cols[i + 1]), (cols[i + 2], cols[i + 3]), 0.0)
        )
    still = 0.0  # the speed at rest: only a force against a velocity reads it
    if plan.against and t.size:
        still = applied.rest(float(cols[0][0] if t.size == 1 else cols[0].max()), abs(omega2))
    x = a.x_out if plan.ram else None
    taken = {}
    for ap in applied.act(s, resolved, geo, t, working, x, 1.0, still, ends):
        i = plan.centres[ap.body]
        for r, v in applied.rows(s, ap, (cols[i], cols[i + 1])):
            taken[r] = taken[r] + v if r in taken else v
    x0, fresh = out[:, :K], False
    for r, v in taken.items():  # a load leaves the right-hand side: its value times the unit solution off
        if t.size < SKIP or v.any():  # a load that is zero at every angle leaves the unknowns as they are
            lo, hi = plan.units[r]
            term = v[:, None] * out[:, lo:hi]
            if fresh:
                x0 -= term
            else:
                x0, fresh = x0 - term, True
    u = out[:, K : 2 * K] if superposed else None

    def solve(extra):
        return x0.T if extra is None else (x0 + extra[:, None] * u).T

    return Parts(solve, a.x_out, a.v_out, a.normals, a.shaking)


__all__ = ["kernel", "parts"]
