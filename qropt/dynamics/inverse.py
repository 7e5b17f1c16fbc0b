"""Exact inverse dynamics of a linkage declared with the builder: the input torque, every joint force, the shaking
force and moment, at given crank angles, omega2 and alpha2.

The jets of the loop (the same code as the kinematics) give each body's centre-of-mass acceleration and angular
acceleration exactly; Newton-Euler's equations of every moving body (three for a rigid body, two for the point
ram) are then one linear system per crank angle, solved at all angles at once. Unknowns: the crank torque T, a
force vector at every pin, a force along the contact normal at every slot (a block or pin in a slot, the yoke),
the guide's normal force under the ram (and the moment a yoke-ram's guide carries), and the couple between a
massive crank-pin block and its slot. A massless block (the default) passes its force straight from the crank to
the lever along the slot's normal. Friction on the slide (mu |N| against the ram's velocity) makes the system
depend on N; as the system is linear in a load on the ram, N has a closed form (``friction_load``), the same in
the exact analysis and in the NLP. General loads (forces at points, torques on bodies, a gravity vector:
``applied``) are known external forces and moments on the right-hand side: the compiled kernel solves them as it
solves the shorthands (``compiled``), the jets and numpy where it cannot (pin friction, a singular angle). SI units
throughout.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from qropt import units as units_
from qropt.dynamics import applied, compiled
from qropt.dynamics.elimination import Elimination, Parts, pivots
from qropt.dynamics.model import BodyMass, Loads, Masses, Window, slender_bar, union
from qropt.dynamics.rigid import body_motion, is_zero, shaking
from qropt.errors import DegenerateMechanism, InvalidParameter, PinLocked, SlideLocked, UnsupportedLoad
from qropt.kinematics.ops import JET, Jet
from qropt.validate import LIMIT, number

LENGTH_GRID = 720  # crank angles where a lever's reach is sampled before its exact maximum is refined


@dataclass(frozen=True)
class Dynamics:
    """Inverse dynamics over crank angles ``theta2`` (rad) at omega2 (rad/s), alpha2 (rad/s^2), SI units.

    torque: (n,) N m, the motor's torque on the crank (``torque * omega2`` the power it delivers);
    joint_forces: joint -> (n, 2) N, what the driven body receives across the joint ('O2' the crank's ground
    bearing; 'slide' the guide's force on the ram: its normal force and, with friction, the friction along x);
    shaking_force: (n, 2) N, ``-sum(m a_G)``; shaking_moment: (n,) N m about O2, ``-sum(r_G x m a_G + I alpha)``;
    guide_moment: (n,) N m the yoke-ram's guide carries (None without a yoke). With pin friction
    (``Loads.pin_friction``): pin_moments: joint -> (n,) N m, the friction moment the driven body receives across the
    pin (the driving body the opposite one), ``-mu r |F| sign(omega_rel)`` with omega_rel the driven body's angular
    velocity less the driving body's; pin_power_loss: joint -> (n,) W >= 0, ``|M omega_rel|`` (None without)."""

    theta2: np.ndarray
    omega2: float
    alpha2: float
    torque: np.ndarray
    joint_forces: dict
    shaking_force: np.ndarray
    shaking_moment: np.ndarray
    guide_moment: np.ndarray | None = None
    pin_moments: dict | None = None
    pin_power_loss: dict | None = None

    @property
    def pin_friction_power(self) -> np.ndarray:
        """(n,) W >= 0, the power the pins' friction dissipates (0 without pin friction)."""
        if not self.pin_power_loss:
            return np.zeros(self.theta2.shape)
        return np.sum(list(self.pin_power_loss.values()), axis=0)

    @property
    def power(self) -> np.ndarray:
        """W, the power the motor delivers (``torque * omega2``)."""
        return self.torque * self.omega2

    def force_magnitudes(self) -> dict:
        """joint -> (n,) N, the magnitude of each joint force."""
        return {k: np.hypot(v[:, 0], v[:, 1]) for k, v in self.joint_forces.items()}


def _parts(j, shape) -> np.ndarray:
    """(3, n): value, first and second time derivative of a jet or a constant."""
    if isinstance(j, Jet):
        return np.broadcast_to(j.c, (3, *shape)).astype(float)
    out = np.zeros((3, *shape))
    out[0] = float(j)
    return out


def _jet3(j, k: float = 1.0) -> tuple:
    """(value, first, second derivative) of a jet (arrays) or of a constant (a number, 0, 0), times k."""
    if isinstance(j, Jet):
        c = j.c
        return (c[0], c[1], c[2]) if k == 1.0 else (c[0] * k, c[1] * k, c[2] * k)
    return (float(j) * k, 0.0, 0.0)


def _triples(lp, k) -> dict:
    """joint -> ((x, x', x''), (y, y', y'')) in metres (k: metres per the mechanism's unit) from the loop's jets."""
    return {j: (_jet3(x, k), _jet3(y, k)) for j, (x, y) in lp.points.items()}


def linkage_of(m):
    """The builder linkage of a mechanism (InvalidParameter for a hand-written loop)."""
    link = type(m).linkage(m.params)
    if link is None:
        raise InvalidParameter(
            f"{type(m).__name__}: dynamics needs the joints and bodies of a linkage declared with the builder "
            "(qropt.mechanisms.builder.Linkage); this type's loop is hand-written"
        )
    return link


def body_masses(m, masses: Masses) -> dict[str, BodyMass]:
    """Every moving body's mass model in SI (body frames as in ``Dynamics``): the defaults of ``masses`` (uniform
    slender bars, a point ram, a point block, the counterweight on the crank) with its overrides."""
    if not isinstance(masses, Masses):
        raise InvalidParameter(f"masses is a qropt.Masses, got {type(masses).__name__}")
    if masses.balancing:
        raise InvalidParameter(
            "the counterweight is free (Counterweight.balancing): a solve chooses its mass and angle; analyse with "
            "a fixed one (a Result's counterweight, or Counterweight(mass, radius, angle))"
        )
    k = units_.to_metres(m.units)
    bodies = linkage_of(m).bodies()
    unknown = sorted(set(masses.bodies) - {b.name for b in bodies})
    if unknown:
        raise InvalidParameter(f"{type(m).__name__} has no bodies {unknown}; its bodies: {[b.name for b in bodies]}")
    t = np.linspace(0.0, 2 * math.pi, LENGTH_GRID, endpoint=False)
    reach = None
    out = {}
    for b in bodies:
        if b.name in masses.bodies:
            bm = masses.bodies[b.name]
        elif b.kind in ("ram", "yoke"):
            bm = BodyMass(masses.ram)
        elif b.kind == "block":
            bm = BodyMass(masses.block)
        else:
            if reach is None:
                reach = _reaches(m, t)
            bars = [k * reach(b.joints[0], j) for j in b.joints[1:]]
            if b.kind != "plate":
                bars = [max(bars)]
            bm = _bars(b, bars, m, masses.density)
        if b.name == "crank" and masses.counterweight is not None and masses.counterweight.mass > 0:
            bm = _combined(bm, BodyMass(*masses.counterweight.part()))
        out[b.name] = bm
    link = linkage_of(m)
    for joint, mass in masses.points.items():
        name = applied.carrier(m, link, joint)
        body = next(b for b in bodies if b.name == name)
        where = (0.0, 0.0) if body.kind in ("ram", "yoke") else _fixed_point(m, body, joint, k)
        out[name] = _combined(out[name], BodyMass(mass, where))
    return out


def _fixed_point(m, body, joint: str, k: float) -> tuple:
    """(x, y) (m) of a joint in the frame of a turning body that carries it; InvalidParameter where the joint
    slides on the body (its place in the frame changes over the turn)."""
    from qropt.dynamics.rigid import frame

    t = np.array([0.0, 2.1, 4.2])
    pts = {j: ((p[:, 0] * k, 0.0, 0.0), (p[:, 1] * k, 0.0, 0.0)) for j, p in m.positions(t).points.items()}
    (ox, oy), (c, sn, _, _) = frame(body, pts)
    dx, dy = pts[joint][0][0] - ox[0], pts[joint][1][0] - oy[0]
    x, y = c * dx + sn * dy, -sn * dx + c * dy
    if np.ptp(x) > 1e-9 * (1.0 + np.abs(x).max()) or np.ptp(y) > 1e-9 * (1.0 + np.abs(y).max()):
        raise InvalidParameter(f"the point mass at {joint}: {joint} slides on the {body.name}, it is not fixed on it")
    return float(x[0]), float(y[0])


def _reaches(m, t):
    """reach(a, b): the largest distance (mechanism units) between joints a and b over a turn: exact for joints
    fixed on one body (constant), refined by Newton on the jets' derivative where b slides along a lever."""
    pos = m.positions(t).points

    def reach(a, b):
        d = np.hypot(*(pos[b] - pos[a]).T)
        if np.ptp(d) <= 1e-12 * max(1.0, d.max()):
            return float(d.max())
        th = float(t[int(np.argmax(d))])
        for _ in range(8):  # Newton on d(|r|^2)/dtheta = 0 from the grid's best
            lp = m.evaluate(JET, Jet.seed(np.array([th])))
            (ax, ay), (bx, by) = lp.points[a], lp.points[b]
            dx, dy = _parts(bx, (1,)) - _parts(ax, (1,)), _parts(by, (1,)) - _parts(ay, (1,))
            g1 = dx[0] * dx[1] + dy[0] * dy[1]
            g2 = dx[1] ** 2 + dx[0] * dx[2] + dy[1] ** 2 + dy[0] * dy[2]
            if not g2[0] < 0:
                break
            step = float(g1[0] / g2[0])
            th -= step
            if abs(step) < 1e-14:
                break
        lp = m.evaluate(JET, Jet.seed(np.array([th])))
        (ax, ay), (bx, by) = lp.points[a], lp.points[b]
        exact = float(np.hypot(_parts(bx, (1,))[0] - _parts(ax, (1,))[0], _parts(by, (1,))[0] - _parts(ay, (1,))[0])[0])
        return max(exact, float(d.max()))

    return reach


def _bars(body, lengths, m, density) -> BodyMass:
    """Uniform slender bars from the body's first joint along each other joint's direction (the body frame's
    x-axis for the first; a plate's other bars at their angle in the frame)."""
    if body.kind != "plate":
        return BodyMass(*slender_bar(density, lengths[0]))
    pos = m.positions(np.array([0.0])).points
    o = pos[body.joints[0]][0]
    x_dir = pos[body.joints[1]][0] - o
    phi = math.atan2(x_dir[1], x_dir[0])
    out = None
    for j, L in zip(body.joints[1:], lengths, strict=True):
        d = pos[j][0] - o
        a = math.atan2(d[1], d[0]) - phi
        part = slender_bar(density, L, math.cos(a), math.sin(a))
        out = part if out is None else union(out, part)
    return BodyMass(*out)


def _combined(a: BodyMass, b: BodyMass) -> BodyMass:
    """Two rigid parts in one frame as one body (parallel axes)."""
    return BodyMass(*union((a.mass, a.com, a.inertia), (b.mass, b.com, b.inertia)))


def system_of(m, masses: Masses) -> _System:
    """The Newton-Euler system of mechanism ``m`` under ``masses``, kept on the (immutable) mechanism for the
    last mass model asked: the bars' lengths need each lever's exact reach, which costs more than a solve."""
    cached = m.__dict__.get("_force_system")
    if cached is not None and cached[0] == masses:
        return cached[1]
    s = _System(m, masses)
    m.__dict__["_force_system"] = (masses, s)
    return s


class _System:
    """The Newton-Euler system of one mechanism: bodies, unknowns and the rows they enter."""

    def __init__(self, m, masses: Masses):
        self.props = body_masses(m, masses)
        self._structure(linkage_of(m), type(m).__name__, lambda name: self.props[name].mass > 0)

    @classmethod
    def of_linkage(cls, link, name: str, massive) -> _System:
        """The structure alone (no numbers): ``massive(body)`` says whether a body has a mass (the block's
        decides whether it is a body of the system)."""
        s = cls.__new__(cls)
        s.props = None
        s._structure(link, name, massive)
        return s

    def pivots(self, entries: dict):
        """The elimination's pivots for these entries (``pivots``), kept per structure: which entries are numbers."""
        key = tuple((rc, v if isinstance(v, (int, float)) else None) for rc, v in entries.items())
        cache = self.__dict__.setdefault("_pivots", {})
        if key not in cache:
            cache[key] = pivots(entries, self.n)
        return cache[key]

    def _structure(self, link, name, massive):
        bodies = list(link.bodies())
        conns = list(link.connections())
        block = next((b for b in bodies if b.kind == "block"), None)
        self.block_massive = block is not None and massive(block.name)
        self.all_bodies = {b.name: b for b in bodies}
        self.pins = [c for c in conns if c.kind == "pin"]  # every revolute joint (pin friction acts there)
        self.block_pin = None
        if block is not None and not self.block_massive:  # crank -> lever straight along the slot's normal
            bodies = [b for b in bodies if b is not block]
            pin = self.block_pin = next(c for c in conns if c.receiver == block.name and c.kind == "pin")
            conns = [
                c._replace(giver=pin.giver) if c.giver == block.name else c
                for c in conns
                if not (c.receiver == block.name and c.kind == "pin")
            ]
        self.bodies = bodies
        self.kinds = {b.name: b.kind for b in bodies}  # the system's bodies' kinds (``kind``)
        self.conns = conns
        self.ground = set(link.ground_joints())
        rows, n = {}, 0
        for b in bodies:
            rows[b.name] = n
            n += 2 if b.kind == "ram" else 3
        self.rows, self.n_rows = rows, n
        cols, n = [], 1  # column 0: the crank torque
        for c in conns:
            width = 2 if c.kind == "pin" else 1
            cols.append((c, n, width))
            n += width
        self.cols = cols
        self.yoke = next((b.name for b in bodies if b.kind == "yoke"), None)
        self.output = next((b for b in bodies if b.kind in ("ram", "yoke")), None)  # the body a cutting force acts on
        if self.yoke is not None:
            self.guide_moment_col = n
            n += 1
        if self.block_massive:
            self.couple_col = n
            n += 1
        if n != self.n_rows:
            raise InvalidParameter(
                f"{name}: {self.n_rows} equations of motion against {n} unknown forces; the force "
                "analysis needs a linkage whose every body is held by pins, slots and the ram's guide"
            )
        self.n = n

    def load_row(self) -> int | None:
        """The row a known load enters: the output body's x force (a cutting force), else the follower's moment
        (a follower's load torque); None for neither."""
        if self.output is not None:
            return self.rows[self.output.name]
        return self.rows["follower"] + 2 if "follower" in self.rows else None

    def kind(self, body: str) -> str:
        return self.kinds[body]

    def assemble(self, P, kin, g, sqrt):
        """The Newton-Euler system as entries: ({(row, column): value}, {row: value}), the values numpy arrays
        over crank angles or CasADi expressions alike. P: joint -> (x, y) (m); kin: body -> (G (x, y),
        a_G (x, y), alpha, mass, inertia); g: gravity (m/s^2); sqrt: the namespace's square root. Column 0 is the
        crank torque; the known loads (cutting force, a follower torque, friction) go on the right-hand side
        afterwards."""
        A, rhs = {}, {}

        def add(r, c, v):
            A[(r, c)] = A[(r, c)] + v if (r, c) in A else v

        for b in self.bodies:
            _, a, alpha, mass, inertia = kin[b.name]
            r = self.rows[b.name]
            rhs[r] = mass * a[0]
            rhs[r + 1] = mass * a[1] + mass * g
            if b.kind != "ram":
                rhs[r + 2] = inertia * alpha
        add(self.rows["crank"] + 2, 0, 1.0)  # the motor's torque on the crank

        def put(body, col, fx, fy, at):
            """A unit unknown in column col gives the force (fx, fy) on ``body`` at point ``at``."""
            if body == "ground":
                return
            r, G = self.rows[body], kin[body][0]
            zx, zy = is_zero(fx), is_zero(fy)  # a unit force along an axis enters two rows, not three
            if not zx:
                add(r, col, fx)
            if not zy:
                add(r + 1, col, fy)
            if self.kind(body) != "ram":
                if zx:
                    add(r + 2, col, (at[0] - G[0]) * fy)
                elif zy:
                    add(r + 2, col, -(at[1] - G[1]) * fx)
                else:
                    add(r + 2, col, (at[0] - G[0]) * fy - (at[1] - G[1]) * fx)

        for c, col, _ in self.cols:
            at = P[c.joint]
            if c.kind == "pin":
                for i, (fx, fy) in enumerate(((1.0, 0.0), (0.0, 1.0))):
                    put(c.receiver, col + i, fx, fy, at)
                    put(c.giver, col + i, -fx, -fy, at)
            elif c.kind == "slot":
                nx, ny = self.normal(c, P, sqrt)
                put(c.receiver, col, nx, ny, at)
                put(c.giver, col, -nx, -ny, at)
            else:  # the guide under the ram: a force normal to the slide line, at the ram's joint
                put(c.receiver, col, 0.0, 1.0, at if self.kind(c.receiver) != "yoke" else kin[c.receiver][0])
        if self.yoke is not None:
            add(self.rows[self.yoke] + 2, self.guide_moment_col, 1.0)
        if self.block_massive:
            block = next(b.name for b in self.bodies if b.kind == "block")
            lever = next(c.receiver for c in self.conns if c.giver == block and c.kind == "slot")
            add(self.rows[block] + 2, self.couple_col, 1.0)
            add(self.rows[lever] + 2, self.couple_col, -1.0)
        return A, rhs

    @staticmethod
    def normal(c, P, sqrt):
        """The unit normal of a slot's line (rotated +90 degrees from a->b); the yoke's: +x."""
        if c.line is None:
            return 1.0, 0.0
        (ax, ay), (bx, by) = P[c.line[0]], P[c.line[1]]
        dx, dy = bx - ax, by - ay
        L = sqrt(dx * dx + dy * dy)
        return -dy / L, dx / L


def inverse_dynamics(m, theta2, omega2: float = 1.0, alpha2: float = 0.0, *, masses=None, loads=None) -> Dynamics:
    """Inverse dynamics of ``m`` at crank angles theta2 (rad); see ``Dynamics``."""
    masses = Masses() if masses is None else masses
    loads = Loads() if loads is None else loads
    if not isinstance(loads, Loads):
        raise InvalidParameter(f"loads is a qropt.Loads, got {type(loads).__name__}")
    omega2, alpha2 = number("omega2", omega2, limit=LIMIT), number("alpha2", alpha2, limit=LIMIT)
    require_sense(omega2, loads)
    t = m._angles(theta2)
    return _solve(m, system_of(m, masses), t, omega2, alpha2, loads)


def require_sense(omega2: float, loads: Loads) -> None:
    """InvalidParameter where omega2 is zero and a load needs the crank's sense of rotation (it resists the motion
    or acts on a stroke)."""
    against = any(f.direction == "against" for f in loads.forces)
    if omega2 == 0.0 and (loads.friction or loads.switching or against or loads.by_stroke()):
        raise InvalidParameter(
            "omega2 must be nonzero with a cutting force, friction, or a load on a stroke or against a velocity"
        )


def _kinetics(m, s: _System, t, omega2, alpha2, k, rates: bool = False):
    """From the loop's jets: the joints' positions (m) (with ``rates``, their rates first), every body's (G, a_G,
    alpha, mass, inertia) and the velocity friction needs (the output body's); the jets themselves are dropped on
    return, which keeps the solve's memory small."""
    pts = _triples(m.evaluate(JET, Jet.seed(t, omega2, alpha2)), k)
    P = {j: (x[0], y[0]) for j, (x, y) in pts.items()}
    kin, vel = {}, {}
    for b in s.bodies:
        bm = s.props[b.name]
        G, v, a, ph = body_motion(b, bm.com, pts)
        kin[b.name] = (G, a, ph[3], bm.mass, bm.inertia)
        if b.kind in ("ram", "yoke"):
            vel[b.name] = v
    return (pts, P, kin, vel) if rates else (P, kin, vel)


def _loaded(m, s: _System, t, omega2, alpha2, loads, working=None, keep=None) -> tuple:
    """One solve's parts with its loads at crank angles t: (parts, the load on the ram's row (an (n,) array, or
    None: it is in the parts), the guide's column where the slide has friction and the ram's velocity's sign
    there, else (None, None)). ``working`` as ``_solve``."""
    k = units_.to_metres(m.units)
    forced = working is not None
    way = working_way(m, loads, omega2 or 1.0)  # the load resists the working stroke's motion, its ends included
    working = _working(m, t, omega2, way) if working is None else np.full(t.shape, bool(working))
    way = 0.0 if way is None else (1.0 if way == "+x" else -1.0)
    out_body = s.output
    guide_col = next((col for c, col, _ in s.cols if c.kind == "guide"), None)
    sliding = bool(loads.friction) and guide_col is not None
    table = out_body is not None and isinstance(loads.cutting_force, tuple)
    known = None  # a load that does not depend on the motion (a table does: on the ram's position)
    if out_body is not None and not table and loads.cutting_force:
        known = np.where(working, loads.cutting_force * way, 0.0)
    elif out_body is None and loads.follower_torque and m.OUTPUT == "follower":
        known = np.where(working, loads.follower_torque * way, 0.0)
    general = _resolved(m, s, loads) if loads.forces or loads.torques or isinstance(loads.gravity, tuple) else None
    ends = np.where(working, way, -way) if forced and way else None
    extra = None if general is None else (loads, general, working, ends)
    # the compiled kernel, general loads included; pin friction needs the elimination itself (``keep``): the jets
    # and numpy, as every angle where the kernel's rows are not finite
    a = (
        None
        if keep is not None
        else compiled.parts(m, s, t, omega2, alpha2, loads.gravity, k, known, table or sliding, loads, extra)
    )
    if a is None and keep is None:  # rows the kernel found not finite: the jets give them, singular angles as NaN
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            a = _numpy_parts(m, s, t, omega2, alpha2, loads.gravity, k, known, extra, keep)
    elif a is None:
        a = _numpy_parts(m, s, t, omega2, alpha2, loads.gravity, k, known, extra, keep)
    # along x, through the ram's point (no moment about a yoke's centre on its line)
    load = np.where(working, loads.force_at(a.x_out), 0.0) * way if table else None
    if keep is not None and sliding:
        keep["sigma"] = _velocity_sign(a, working, way, forced)
    if not sliding:
        return a, load, None, None
    return a, load, guide_col, _velocity_sign(a, working, way, forced)


def _resolved(m, s: _System, loads: Loads) -> list[tuple]:
    """``applied.resolve`` of the loads on m, kept on the system (of one mechanism and mass model) for the loads
    last asked (the same object: a cycle's solves share it)."""
    cached = s.__dict__.get("_resolved")
    if cached is not None and cached[0] is loads:
        return cached[1]
    out = applied.resolve(m, s, linkage_of(m), loads)
    s.__dict__["_resolved"] = (loads, out)
    return out


def _singular(m) -> DegenerateMechanism:
    return DegenerateMechanism(
        f"{m!r}: the force analysis is singular at some crank angle (a transmission angle of zero: no force can "
        "drive the output there)"
    )


def _solve(m, s: _System, t, omega2, alpha2, loads, working=None) -> Dynamics:
    """``working``: the cutting force's state at every angle (True on, False off; None: by the stroke)."""
    n = t.size
    pf = loads.pin_friction
    keep = {} if pf is not None else None
    pin_out = None
    try:
        a, load, col, sigma = _loaded(m, s, t, omega2, alpha2, loads, working, keep)
        x = a.solve(load)
        friction = np.zeros(n)
        if pf is not None:
            x, friction, pin_out = _with_pins(m, s, t, omega2, a, x, load, col, loads, keep)
        elif col is not None:
            x, friction = _with_friction(m, t, a, x, load, col, loads.friction, sigma)
    except np.linalg.LinAlgError:
        raise _singular(m) from None
    forces = {}
    for c, col, _ in s.cols:
        if c.kind == "pin":
            key = f"{c.joint}/block" if s.block_massive and s.kind(c.receiver) == "block" else c.joint
            forces[key] = _pairs(x[col], x[col + 1], n)
        elif c.kind == "slot":
            nx, ny = a.normals[c.joint]
            forces[c.joint] = _pairs(x[col] * nx, x[col] * ny, n)
        else:
            forces["slide"] = _pairs(friction, x[col], n)
    sfx, sfy, sm = a.shaking
    gm = x[s.guide_moment_col] if s.yoke is not None else None
    sm = np.broadcast_to(sm, t.shape).astype(float)
    moments, losses = pin_out if pin_out is not None else (None, None)
    return Dynamics(t, omega2, alpha2, x[0], forces, _pairs(sfx, sfy, n), sm, gm, moments, losses)


def friction_load(xp, n0, n1, mu, sigma):
    """The friction on the slide as a load on the ram's row (N along x): e = -(mu |N| against the velocity), with
    the guide's normal force N = N0 + N1 e (N0 without friction, N1 its change per newton on that row), so
    |N| = |N0| / (1 - mu sigma N1 sign(N0)), sigma the sign of the ram's velocity. The one solution while
    mu |N1| < 1 (beyond it the slide locks). xp: numpy, or casadi for the NLP's expressions."""
    return mu * sigma * xp.fabs(n0) / (1 - mu * sigma * n1 * xp.sign(n0))


PIN_REST = 1e-12  # a pin's relative rotation below this times |omega2| (rad/s) is at rest: no friction moment
NEWTON_STEPS = 60  # Newton's iterations on the friction moments (quadratic: a handful where it converges)
GAIN_STEPS = 200  # power iterations on the friction loop's gain


def pin_table(m, s: _System, pf) -> list[tuple]:
    """The pins with friction: (joint, mu r (m), driven body, driving body, the body the driven side's moment goes
    to in the system (None: the ground or a point ram, whose guide carries it), the driving side's, the force's
    column in the unknowns, whether that column is a slot's normal force (the massless block's pin)). The joints
    named in ``pf.joints`` are checked: InvalidParameter naming one that is not a pin."""
    pins = [c.joint for c in s.pins]
    for j in pf.joints:
        if j not in pins:
            what = "a slot or the ram's guide, not a pin" if any(c.joint == j for c in s.conns) else "not a joint"
            raise InvalidParameter(
                f"pin friction at {j}: {type(m).__name__}'s {j} is {what}; its pins (revolute joints): {pins}"
            )
    held = {b.name: b.kind for b in s.bodies}

    def row_of(body):
        return None if body not in held or held[body] == "ram" else body

    out = []
    for c in s.pins:
        mu, r = pf.at(c.joint)
        if mu * r == 0:
            continue
        if c is s.block_pin:  # the massless block passes the pin's force and moment on to the lever
            slot = next(q for q, _, _ in s.cols if q.kind == "slot" and q.joint == c.joint and q.giver == c.giver)
            col = next(k for q, k, _ in s.cols if q is slot)
            out.append((c.joint, mu * r, c.receiver, c.giver, row_of(slot.receiver), row_of(c.giver), col, True))
        else:
            col = next(k for q, k, _ in s.cols if q is c)
            out.append((c.joint, mu * r, c.receiver, c.giver, row_of(c.receiver), row_of(c.giver), col, False))
    return out


def pin_spins(s: _System, table, pts) -> list:
    """Each pin's relative angular velocity (rad/s, or per unit crank angle): the driven body's less the driving
    body's (``rigid.frame``; the ground's and a ram's are 0)."""
    from qropt.dynamics.rigid import frame

    def spin(body):
        if body == "ground":
            return 0.0
        return frame(s.all_bodies[body], pts)[1][2]

    return [spin(p[2]) - spin(p[3]) for p in table]


def _with_pins(m, s: _System, t, omega2, a: Parts, x, load, col, loads, keep) -> tuple:
    """The unknowns with Coulomb friction at the pins (and the slide's, if any), solved exactly: every unknown is
    affine in the friction moments z_j (and the slide's friction load), x = x0 + sum z_j u_j (u_j the unknowns
    per unit moment, from the same elimination), and z_j = -mu_j r_j |F_j(x)| sign(omega_rel_j) (the slide's
    e = mu sigma |N(x)|). Newton on G(z) = z + c |F(x0 + U z)| from z = 0 (the frictionless solution) to machine
    precision, all angles at once. Where a pin is at rest relative to its bodies (|omega_rel| <= PIN_REST |omega2|,
    or omega2 = 0) its moment is 0 (kinetic friction only: a pin at rest may hold any moment up to mu r |F|).
    PinLocked (SlideLocked for the slide alone) where the friction loop's gain (``_gain``) reaches 1, or where
    Newton finds no solution. Returns (x, the slide's friction along x, (pin_moments, pin_power_loss))."""
    n = t.size
    table = pin_table(m, s, loads.pin_friction)
    spins = [np.broadcast_to(np.asarray(w, float), (n,)) for w in pin_spins(s, table, keep["pts"])]
    elim = keep["elim"]
    c, F0, names, units = [], [], [], []
    rest = PIN_REST * abs(omega2)
    for (joint, mur, _, _, recv, giver, k, slot), w in zip(table, spins, strict=True):
        c.append(mur * np.where(np.abs(w) > rest, np.sign(w), 0.0))
        rhs = {}
        if recv is not None:
            rhs[s.rows[recv] + 2] = -1.0  # a unit moment on the driven body leaves its row's right-hand side
        if giver is not None:
            rhs[s.rows[giver] + 2] = 1.0
        units.append(elim.solve(rhs) if rhs else [0.0] * s.n)
        F0.append(_force(x, k, slot, a, joint, n))
        names.append(joint)
    sliding = col is not None and loads.friction
    if sliding:
        sigma = keep["sigma"]
        unit = _per_newton(a, x, load)
        n1 = unit[col]
        locked = (loads.friction * np.abs(n1) >= 1.0) & (sigma != 0)
        if locked.any():
            i = int(np.flatnonzero(locked)[0])
            raise _locked(m, loads.friction, n1[i], t[i])
        c.append(-loads.friction * sigma)
        F0.append(_scalar_force(x[col], n))
        names.append("the slide")
        units.append(unit)
    p = len(c)
    if p == 0:  # no pin has friction (mu r = 0 at every pin) and the slide has none
        zeros = {c_.joint: np.zeros(n) for c_ in s.pins}
        return x, np.zeros(n), (zeros, {j: v.copy() for j, v in zeros.items()})
    cols = [(p_[6], p_[7]) for p_ in table] + ([(col, None)] if sliding else [])
    # Uf[j, k]: (2, n), the force at entry j per unit of entry k
    Uf = np.empty((p, p, 2, n))
    for k_ in range(p):
        for j, (kc, slot) in enumerate(cols):
            if slot is None:
                Uf[j, k_] = _scalar_force(units[k_][kc], n)
            else:
                Uf[j, k_] = _force(units[k_], kc, slot, a, names[j], n)
    C = np.array(c)  # (p, n)
    F0 = np.array(F0)  # (p, 2, n)
    gain, share = _gain(C, Uf)
    locked = gain >= 1.0
    if locked.any():
        i = int(np.flatnonzero(locked)[0])
        raise _pin_locked(m, t[i], names[int(np.argmax(share[:, i]))], float(gain[i]), "jam")
    z = np.zeros((p, n))
    eye = np.eye(p)[:, :, None]
    for _ in range(NEWTON_STEPS):
        F = F0 + np.einsum("jkdn,kn->jdn", Uf, z)
        norm = np.hypot(F[:, 0], F[:, 1])
        G = z + C * norm
        hat = F / np.where(norm > 0, norm, 1.0)[:, None, :]
        J = eye + C[:, None, :] * np.einsum("jdn,jkdn->jkn", hat, Uf)
        try:
            step = np.linalg.solve(J.transpose(2, 0, 1), G.T[:, :, None])[:, :, 0].T
        except np.linalg.LinAlgError:  # a singular Newton step: no solution found where it is
            i = int(np.flatnonzero(np.abs(np.linalg.det(J.transpose(2, 0, 1))) <= 1e-300)[:1].sum())
            raise _pin_locked(m, t[i], names[int(np.argmax(share[:, i]))], float(gain[i]), "none") from None
        z = z - step
        scale = np.abs(z).max(axis=0) + np.abs(C * np.hypot(F0[:, 0], F0[:, 1])).max(axis=0) + 1e-300
        done = np.abs(step).max(axis=0) <= 1e-14 * scale
        if done.all():
            break
    F = F0 + np.einsum("jkdn,kn->jdn", Uf, z)
    norm = np.hypot(F[:, 0], F[:, 1])
    resid = np.abs(z + C * norm)
    scale = np.abs(z).max(axis=0) + np.abs(C * norm).max(axis=0) + 1e-300
    bad = ~np.isfinite(resid).all(axis=0) | (resid.max(axis=0) > 1e-11 * scale)
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise _pin_locked(m, t[i], names[int(np.nanargmax(resid[:, i]))], float(gain[i]), "none")
    out = [xi + sum(z[k_] * units[k_][i_] for k_ in range(p)) for i_, xi in enumerate(x)]
    friction = -z[-1] if sliding else np.zeros(n)
    moments = {names[j]: z[j].copy() for j in range(len(table))}
    losses = {names[j]: np.abs(z[j] * spins[j]) for j in range(len(table))}
    for c_ in s.pins:  # the pins without friction: no moment, no loss
        moments.setdefault(c_.joint, np.zeros(n))
        losses.setdefault(c_.joint, np.zeros(n))
    return out, friction, (moments, losses)


def _force(x, k: int, slot: bool, a: Parts, joint: str, n: int) -> np.ndarray:
    """(2, n): a pin's force from the unknowns x (its two columns from k; a massless block's pin: the slot's
    normal force times its normal)."""
    out = np.empty((2, n))
    if slot:
        nx, ny = a.normals[joint]
        out[0], out[1] = x[k] * nx, x[k] * ny
    else:
        out[0], out[1] = x[k], x[k + 1]
    return out


def _scalar_force(v, n: int) -> np.ndarray:
    out = np.zeros((2, n))
    out[0] = v
    return out


def _gain(C, Uf) -> tuple:
    """The friction loop's gain at each angle and the entries' shares in it (the eigenvector's entries times how
    much each moves the forces: a ground pivot's moment on the crank, which the torque takes, has none): the largest
    lambda with
    H(z) = lambda z, z != 0, for the homogeneous map H(z)_j = -c_j |sum_k z_k U_jk| (what the friction moments do
    to themselves with no load at all), by power iteration on the cone z_k = -sign(c_k) w_k, w >= 0 (H maps into
    it). lambda >= 1: friction could hold a self-stressed jam within its limits (|z_j| <= mu_j r_j |F_j|), as the
    slide locks where mu |dN/dF| >= 1 (for one pin, or pins whose moments drive one force, it is exactly
    |sum c| |u|, the friction-circle condition)."""
    p, n = C.shape
    S = -np.sign(C)
    A = np.abs(C)
    V = Uf * S[None, :, None, :]  # the force per unit w_k
    w = np.ones((p, n)) * (A > 0)
    lam = np.zeros(n)
    for _ in range(GAIN_STEPS):
        F = np.einsum("jkdn,kn->jdn", V, w)
        Tw = A * np.hypot(F[:, 0], F[:, 1])
        top = Tw.max(axis=0)
        new = np.where(top > 0, top, 0.0)
        w_next = Tw / np.where(top > 0, top, 1.0)
        converged = np.abs(new - lam) <= 1e-13 * np.maximum(new, 1e-300)
        lam, w = new, w_next
        if converged.all():
            break
    feed = np.sqrt(np.einsum("jkdn,jkdn->kn", V, V))  # how much each entry's moment moves the forces
    return lam, w * feed


def _pin_locked(m, theta: float, joint: str, gain: float, why: str) -> PinLocked:
    what = (
        f"the friction moments could hold the linkage jammed by themselves (the friction loop's gain "
        f"{gain:.4g} >= 1: the joint forces grow with their own friction)"
        if why == "jam"
        else "the joint forces have no solution with the friction moments (Newton on them does not converge)"
    )
    return PinLocked(
        f"{m!r}: pin friction locks the linkage at crank angle {math.degrees(theta) % 360:.6g} deg, at pin {joint}: "
        f"{what}",
        float(theta % (2 * math.pi)),
        joint,
    )


def energy(m, s: _System, t, omega2: float, loads) -> tuple:
    """(E, v) at crank angles t (rad), speed omega2 (rad/s): E (n,) J, the energy the mechanism stores, kinetic
    (sum m v_G^2 / 2 + I omega^2 / 2) and gravity's potential (-sum m g . r_G); v (n,) m/s, the ram's (or yoke's)
    velocity along x (zeros without one)."""
    k = units_.to_metres(m.units)
    pts = _triples(m.evaluate(JET, Jet.seed(t, omega2, 0.0)), k)
    gx, gy = loads.gravity_vector
    E = np.zeros(t.shape)
    v_out = np.zeros(t.shape)
    for b in s.bodies:
        bm = s.props[b.name]
        G, v, _, ph = body_motion(b, bm.com, pts)
        E = E + 0.5 * bm.mass * (v[0] ** 2 + v[1] ** 2) + 0.5 * bm.inertia * ph[2] ** 2
        E = E - bm.mass * (gx * G[0] + gy * G[1])
        if b.kind in ("ram", "yoke"):
            v_out = v_out + v[0]
    return np.broadcast_to(E, t.shape).astype(float), np.broadcast_to(v_out, t.shape).astype(float)


def pin_rest_angles(m, s: _System, pf) -> list[float]:
    """The crank angles (rad, in [0, 2 pi)) where a pin with friction stops turning relative to its bodies: its
    moment turns there (a quadrature splits its pieces at them). A grid's sign changes refined by brentq."""
    from scipy.optimize import brentq

    table = pin_table(m, s, pf)
    if not table:
        return []
    k = units_.to_metres(m.units)

    def spins(th):
        return pin_spins(s, table, _triples(m.evaluate(JET, Jet.seed(np.atleast_1d(th), 1.0, 0.0)), k))

    t = np.linspace(0.0, 2 * math.pi, LENGTH_GRID + 1)
    out = set()
    for i, w in enumerate(spins(t)):
        w = np.broadcast_to(w, t.shape)
        for j in np.flatnonzero(w[:-1] * w[1:] < 0):
            root = brentq(lambda th, i=i: float(np.ravel(spins(th)[i])[0]), t[j], t[j + 1], xtol=1e-14)
            out.add(root % (2 * math.pi))
        out.update(float(t[j]) % (2 * math.pi) for j in np.flatnonzero(w == 0))
    return sorted(out)


def _velocity_sign(a: Parts, working, way: float, forced: bool) -> np.ndarray:
    """The sign of the ram's velocity: its stroke's direction where the stroke is given (a peak's search over a
    stroke closed at its dead centres, where the velocity vanishes), else the velocity's own sign."""
    if forced and way:
        return np.where(working, way, -way)
    return np.sign(np.broadcast_to(a.v_out, working.shape))


def _with_friction(m, t, a: Parts, x, load, col: int, mu: float, sigma) -> tuple:
    """The unknowns with the slide's friction (``friction_load``) and the friction force along x (N); raises
    SlideLocked (a DegenerateMechanism) where the slide locks (mu |dN/dF| >= 1: the guide's force grows with its
    own friction)."""
    unit = _per_newton(a, x, load)
    n1 = unit[col]
    locked = (mu * np.abs(n1) >= 1.0) & (sigma != 0)
    if locked.any():
        i = int(np.flatnonzero(locked)[0])
        raise _locked(m, mu, n1[i], t[i])
    e = friction_load(np, x[col], n1, mu, sigma)
    return [p + q * e for p, q in zip(x, unit, strict=True)], -e


def _per_newton(a: Parts, x, load) -> list:
    """The unknowns' change per newton on the ram's row (the solve is affine in that load): K rows of n."""
    n = np.shape(x[0])[0]
    return [q - p for p, q in zip(x, a.solve((0.0 if load is None else load) + np.ones(n)), strict=True)]


def _locked(m, mu: float, n1: float, theta: float) -> SlideLocked:
    return SlideLocked(
        f"{m!r}: friction mu = {mu:g} locks the slide at crank angle {math.degrees(theta) % 360:.6g} deg "
        f"(the guide's force grows with its own friction: mu |dN/dF| = {mu * abs(n1):.4g} >= 1)",
        float(theta % (2 * math.pi)),
    )


def crank_acceleration(m, s: _System, theta: float, omega2: float, loads, torque: float, flywheel: float) -> float:
    """The crank's angular acceleration (rad/s^2) at crank angle theta (rad) and speed omega2 (rad/s) where the
    motor's torque (N m) drives the mechanism (system s) and a flywheel (kg m^2), with the slide's friction: every
    unknown is affine in alpha2 but for the friction, whose load (``friction_load``) follows the guide's force
    N(alpha2) = N0 + alpha2 dN, piecewise linear in alpha2 with its kink where N vanishes. The balance
    T(alpha2) + I_fw alpha2 = torque is solved on each side of the kink; the answer is the one that lies on its
    own side (DegenerateMechanism where none or two do: friction makes the motion undetermined)."""
    if loads.pin_friction is not None:
        raise UnsupportedLoad(
            "the crank's acceleration under a motor cannot apply pin friction yet (Loads.pin_friction: its moments "
            "depend on the acceleration through the joint forces); inverse_dynamics applies it"
        )
    t = np.array([float(theta)])
    try:
        a0, load, col, sigma = _loaded(m, s, t, omega2, 0.0, loads)
        a1 = _loaded(m, s, t, omega2, 1.0, loads)[0]
        x0, x1 = a0.solve(load), a1.solve(load)
        unit = _per_newton(a0, x0, load)
    except np.linalg.LinAlgError:
        raise _singular(m) from None
    T0, dT, uT = float(x0[0][0]), float(x1[0][0] - x0[0][0]), float(unit[0][0])
    N0, dN, n1, mu, sg = (
        float(x0[col][0]),
        float(x1[col][0] - x0[col][0]),
        float(unit[col][0]),
        loads.friction,
        float(sigma[0]),
    )
    if mu * abs(n1) >= 1.0 and sg:
        raise _locked(m, mu, n1, theta)
    found = []
    for side in (1.0, -1.0):  # on this side of the kink |N| = side N: e = c (N0 + alpha2 dN)
        c = mu * sg * side / (1.0 - mu * sg * n1 * side)
        slope = dT + uT * c * dN + flywheel
        if slope == 0.0:
            continue
        alpha = (torque - T0 - uT * c * N0) / slope
        if side * (N0 + alpha * dN) >= -1e-12 * max(1.0, abs(N0)):
            found.append(alpha)
    if not found or max(found) - min(found) > 1e-9 * max(1.0, *map(abs, found)):
        raise DegenerateMechanism(
            f"{m!r}: at crank angle {math.degrees(theta) % 360:.6g} deg and {omega2:g} rad/s the slide's friction "
            f"leaves the crank's acceleration {'undetermined' if found else 'without a solution'}"
        )
    return found[0]


def _numpy_parts(m, s: _System, t, omega2, alpha2, g, k, known=None, general=None, keep=None) -> Parts:
    """``Parts`` from the jets and the elimination in numpy (``known``: the load that does not depend on the
    motion, (n,) on the load's row, or None; ``general``: (loads, their ``applied.resolve``, the working stroke's
    mask, the output's way along each closed stroke or None: ``applied.evaluate``'s ends) for the forces, torques
    and a gravity vector, or None)."""
    pts, P, kin, vel = _kinetics(m, s, t, omega2, alpha2, k, rates=True)
    if general is not None and isinstance(g, tuple):
        g = 0.0  # the vector's weights go on the rows below
    entries, rows = s.assemble(P, kin, g, np.sqrt)
    if general is not None:
        _apply(m, s, t, omega2, k, pts, kin, rows, *general)
    elim = Elimination(entries, s.n, t.size, s.pivots(entries))
    r = s.load_row()
    if known is not None:
        rows[r] = rows.get(r, 0.0) + known
    base = rows.get(r, 0.0) if r is not None else 0.0

    def solve(extra):
        return elim.solve(rows if extra is None else {**rows, r: base + extra})

    out_body, x_out, v_out = s.output, None, None
    if out_body is not None:
        x_out = P[m.output_joint()][0] / k if m.output_joint() else kin[out_body.name][0][0] / k
        v_out = vel[out_body.name][0]
    normals = {c.joint: s.normal(c, P, np.sqrt) for c, _, _ in s.cols if c.kind == "slot"}
    if keep is not None:  # pin friction: the elimination (for its unit moments) and the joints' rates
        keep.update(elim=elim, pts=pts)
    return Parts(solve, x_out, v_out, normals, shaking(kin))


def _apply(m, s: _System, t, omega2, k, pts, kin, rows, loads, resolved, working, ends) -> None:
    """Put the general loads on the right-hand side (known external forces and moments leave it): each force
    (fx, fy) at point p on body b and torque tau, -(fx, fy, (p - G) x F + tau); a gravity vector's weight m g."""

    def sub(r, v):
        rows[r] = rows.get(r, 0.0) - v

    if isinstance(loads.gravity, tuple):
        gx, gy = loads.gravity
        for b in s.bodies:
            mass = kin[b.name][3]
            sub(s.rows[b.name], mass * gx)
            sub(s.rows[b.name] + 1, mass * gy)
    joint = m.output_joint()
    x = pts[joint][0][0] / k if joint is not None else None
    for ap in applied.evaluate(m, s, resolved, pts, t, working, x, 1.0, abs(omega2), ends):
        for r, v in applied.rows(s, ap, kin[ap.body][0]):
            sub(r, v)


def _pairs(a, b, n) -> np.ndarray:
    """(n, 2) from two columns (arrays or numbers)."""
    out = np.empty((n, 2))
    out[:, 0], out[:, 1] = a, b
    return out


@dataclass(frozen=True)
class Generalised:
    """The crank's equation of motion ``T = M theta2'' + M' theta2'^2 / 2 + Q`` at crank angles theta2 (rad), SI:
    M (kg m^2) = sum(m |dr_G/dtheta2|^2 + I (dphi/dtheta2)^2), M' = dM/dtheta2, and Q (N m) the torque the loads
    and gravity need at the crank, for a crank turning in the sense of ``sense`` (the cutting force resists the
    working stroke, which depends on it; friction, which depends on the speed, is not in Q)."""

    theta2: np.ndarray
    M: np.ndarray
    dM: np.ndarray
    Q: np.ndarray


def generalised(m, theta2, *, masses=None, loads=None, sense: float = 1.0) -> Generalised:
    """See ``Generalised``; from the jets (seeded with omega2 = 1, alpha2 = 0) and the loads' virtual work."""
    masses = Masses() if masses is None else masses
    loads = Loads() if loads is None else loads
    if loads.friction:
        raise InvalidParameter("friction depends on the speed: it has no place in the generalised load Q")
    if loads.pin_friction is not None:
        raise UnsupportedLoad(
            "pin friction depends on the joint forces (the speed and the acceleration): it has no place in the "
            "generalised load Q, so simulate and the servo's problem cannot apply it yet; inverse_dynamics does"
        )
    t = m._angles(theta2)
    s = system_of(m, masses)
    k = units_.to_metres(m.units)
    way = working_way(m, loads, sense)
    lp = m.evaluate(JET, Jet.seed(t, 1.0, 0.0))
    pts = _triples(lp, k)
    M = np.zeros(t.shape)
    dM = np.zeros(t.shape)
    Q = np.zeros(t.shape)
    tilted = isinstance(loads.gravity, tuple)
    for b in s.bodies:
        bm = s.props[b.name]
        _, (vx, vy), (ax, ay), ph = body_motion(b, bm.com, pts)  # per unit theta2 (seeded 1, 0)
        M += bm.mass * (vx * vx + vy * vy) + bm.inertia * ph[2] ** 2
        dM += 2 * (bm.mass * (vx * ax + vy * ay) + bm.inertia * ph[2] * ph[3])
        if tilted:
            Q -= bm.mass * (loads.gravity[0] * vx + loads.gravity[1] * vy)
        else:
            Q += bm.mass * loads.gravity * vy
    if loads.forces or loads.torques:
        joint = m.output_joint()
        x = pts[joint][0][0] / k if joint is not None else None
        on = _working(m, t, sense, way) if way is not None else None
        resolved = applied.resolve(m, s, linkage_of(m), loads)
        for ap in applied.evaluate(m, s, resolved, pts, t, on, x, math.copysign(1.0, sense), 1.0):
            Q -= ap.force[0] * ap.velocity[0] + ap.force[1] * ap.velocity[1] + ap.torque * ap.spin
    if m.output_joint() is not None or m.OUTPUT == "follower":
        x = _parts(lp.x, t.shape)
        working = _working(m, t, sense, way)
        if m.OUTPUT == "slider":
            Q += np.where(working, loads.force_at(x[0]) * np.abs(x[1]) * k, 0.0) * math.copysign(1.0, sense)
        else:
            Q += np.where(working, loads.follower_torque * np.abs(x[1]), 0.0) * math.copysign(1.0, sense)
    return Generalised(t, M, dM, Q)


def loads_at(m, theta2, omega2: float, masses=None, loads=None, *, opened: bool = False) -> tuple:
    """Each force and torque of ``loads`` at crank angles theta2 (rad) and omega2 (rad/s) as the exact analysis
    applies them: (the (load, body) pairs of ``applied.resolve``, their ``applied.Applied``, where the output is on
    its working stroke (a bool array), the output's x (the mechanism's unit) or None). ``opened``: every window
    open (what a load shut there would carry)."""
    t = m._angles(theta2)
    loads = Loads() if loads is None else loads
    s = system_of(m, Masses() if masses is None else masses)
    k = units_.to_metres(m.units)
    pts = _triples(m.evaluate(JET, Jet.seed(t, omega2, 0.0)), k)
    working = _working(m, t, omega2, working_way(m, loads, omega2))
    joint = m.output_joint()
    x = pts[joint][0][0] / k if joint is not None else None
    resolved = applied.resolve(m, s, linkage_of(m), loads)
    pairs = [(dataclasses.replace(ld, window=Window()), b) for ld, b in resolved] if opened else resolved
    return resolved, applied.evaluate(m, s, pairs, pts, t, working, x, 1.0, abs(omega2)), working, x


def working_way(m, loads: Loads, omega2: float) -> str | None:
    """The way the output moves on the working stroke: the slow stroke's ('+x' or '-x'), or where the strokes take
    equal time (TR = 1) the one the loads name (``Loads.working``); None where neither decides and no load needs it.
    InvalidParameter naming the load where one acts on a stroke that cannot be decided, or where the named way is
    not the slow stroke's."""
    way = m.working_direction(omega2 if omega2 else 1.0)
    if loads.working is not None:
        if way is not None and way != loads.working:
            raise InvalidParameter(
                f"{m!r}: its working (slow) stroke moves {way} at omega2 = {omega2:g} rad/s, but the loads name "
                f"{loads.working}"
            )
        return loads.working
    named = loads.by_stroke() if way is None else []
    if named:
        raise InvalidParameter(
            f"{m!r} has TR = 1: its strokes take equal time, so {named[0]} has no working stroke to act on; name "
            "the working stroke's direction, Loads(..., working='+x' or '-x')"
        )
    return way


def _working(m, t, omega2, way=None) -> np.ndarray:
    """Where the output moves on its working stroke at these crank angles (``way``: its direction, default the
    slow stroke's)."""
    a, _ = m.stroke_angles()
    d = m.dead_centres()
    s = t - d.theta_max
    s -= (2 * math.pi) * np.floor(s * (0.5 / math.pi))  # mod 2 pi, a third of np.remainder's time
    down = s < a  # from theta_max to theta_min counter-clockwise: the output decreases for omega2 > 0
    way = m.working_direction(omega2 if omega2 else 1.0) if way is None else way
    if way is None:
        return np.zeros(t.shape, bool)
    decreasing = down if omega2 > 0 else ~down
    return decreasing if way == "-x" else ~decreasing


__all__ = [
    "Dynamics",
    "Generalised",
    "PinLocked",
    "inverse_dynamics",
    "generalised",
    "body_masses",
    "linkage_of",
    "loads_at",
]
