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
iteration) is added in numpy: the superposed variant gives the unknowns per unit load too. General loads (forces,
torques, a gravity vector: ``qropt.dynamics.applied``) and pin friction are not its inputs: ``inverse`` solves them
on the jets in numpy (``parts`` refuses them with UnsupportedLoad where it is given the loads).
"""

from __future__ import annotations

import casadi
import numpy as np

from qropt.dynamics.elimination import Elimination, Parts
from qropt.dynamics.rigid import body_motion, shaking
from qropt.errors import UnsupportedLoad
from qropt.kinematics.kernel import CSE, Batched
from qropt.kinematics.ops import CASADI

_KERNELS: dict = {}


def _key(m, s, superposed: bool) -> tuple:
    return (type(m), tuple(m.params), tuple(b.name for b in s.bodies), s.block_massive, superposed)


def kernel(m, s, superposed: bool = False) -> Batched:
    """The compiled dynamics of m's structure (type, parameter names, bodies) under the system s; ``superposed``:
    also the unknowns per unit load (for a load that depends on the motion, or friction's iteration)."""
    key = _key(m, s, superposed)
    f = _KERNELS.get(key)
    if f is None:
        f = _KERNELS[key] = Batched(_function(m, s, superposed))
    return f


def _function(m, s, superposed: bool) -> casadi.Function:
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
    f = casadi.Function("dynamics", [t, w, al, g, k, load, P, B], [casadi.vertcat(*out)])
    z = casadi.SX.sym("z", 6 + P.numel() + B.numel())
    n = 6 + P.numel()
    args = [z[i] for i in range(6)] + [z[6:n], z[n:]]
    return casadi.Function(f"dynamics_{type(m).__name__}", [z], [f(*args)], CSE)


def parts(m, s, t, omega2, alpha2, g, k, known=None, superposed=False, loads=None):
    """``elimination.Parts`` from the structure's Function (``known``: the load that does not depend on the motion,
    (n,) on the load's row, or None), or None where a row is not finite (a singular angle, which the numpy route
    reports). ``loads``: checked where given (UnsupportedLoad for pin friction and the general loads, which
    ``inverse`` solves on the jets in numpy)."""
    if loads is not None and loads.pin_friction is not None:
        raise UnsupportedLoad(
            "the compiled dynamics kernel cannot apply pin friction (Loads.pin_friction): its moments need the "
            "elimination per unit moment; inverse_dynamics solves it on the jets in numpy"
        )
    if loads is not None and loads.general:
        raise UnsupportedLoad(
            f"the compiled dynamics kernel cannot apply {loads.general[0]}; inverse_dynamics applies it on the jets "
            "in numpy"
        )
    if isinstance(g, tuple):
        raise UnsupportedLoad(
            f"the compiled dynamics kernel cannot apply gravity {g} yet (it takes a number g along -y); "
            "inverse_dynamics applies a gravity vector on the jets in numpy"
        )
    n = t.size
    f = kernel(m, s, superposed)  # CasADi's VM until its calls are HOT, then machine code: the same numbers
    z = np.empty((n, f.m))
    z[:] = [0.0, omega2, alpha2, g, k, 0.0, *m.params.values(), *(v for b in s.bodies for v in _body(s.props[b.name]))]
    z[:, 0] = t
    if known is not None:
        z[:, 5] = known
    out = f(z)
    if not np.isfinite(out).all():
        return None
    return _unpack(out, s, superposed)


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


__all__ = ["kernel", "parts"]
