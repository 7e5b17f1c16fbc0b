"""General loads (qropt.Force, qropt.Torque, qropt.Window, a gravity vector, point masses): the crank torque of the
Newton-Euler inverse dynamics against the power balance, the shorthands unchanged, the TR = 1 working stroke, bad
input, the round trip, and the parts that cannot take them yet."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import qropt
from qropt import Force, Loads, Masses, Torque, Window
from qropt.dynamics.inverse import body_masses, generalised, inverse_dynamics, linkage_of
from qropt.errors import InvalidParameter, UnsupportedLoad
from qropt.kinematics.ops import JET, Jet
from tests.randmech import KINDS, SIXBARS, random_mechanisms

ALL = (*KINDS, *SIXBARS)


def _rates(m, t, omega2, alpha2):
    """joint -> (p, v, a), each (2, n), in metres (the random mechanisms' unit), from the mechanism's jets."""
    lp = m.evaluate(JET, Jet.seed(t, omega2, alpha2))
    out = {}
    for j, (x, y) in lp.points.items():
        cx = x.c if isinstance(x, Jet) else np.array([[float(x)], [0.0], [0.0]])
        cy = y.c if isinstance(y, Jet) else np.array([[float(y)], [0.0], [0.0]])
        cx, cy = np.broadcast_to(cx, (3, t.size)), np.broadcast_to(cy, (3, t.size))
        out[j] = tuple(np.array([cx[i], cy[i]]) for i in range(3))
    return out


def _frame(body, r):
    """(origin p, v, a; angle's cos, sin, omega, alpha) of a body from its joints, as the contract defines frames."""
    if body.kind in ("ram", "yoke"):
        p, v, a = r[body.joints[0]]
        if body.kind == "yoke":
            p, v, a = (np.array([p[0], 0 * p[1]]), np.array([v[0], 0 * v[1]]), np.array([a[0], 0 * a[1]]))
        z = np.zeros(p.shape[1])
        return p, v, a, 1.0 + z, z, z, z
    if body.kind == "block":
        o, far = r[body.joints[0]], r[body.joints[1]]
        d = [o[i] - far[i] for i in range(3)]
    else:
        o, far = r[body.joints[0]], r[body.joints[1]]
        d = [far[i] - o[i] for i in range(3)]
    (dx, dy), (vx, vy), (ax, ay) = d
    r2 = dx * dx + dy * dy
    w = (dx * vy - dy * vx) / r2
    al = (dx * ay - dy * ax) / r2 - 2 * w * (dx * vx + dy * vy) / r2
    n = np.sqrt(r2)
    return o[0], o[1], o[2], dx / n, dy / n, w, al


def _point(fr, local):
    """Position and velocity of a body point (x, y) of frame fr."""
    o, v, _, c, s, w, _ = fr
    rx, ry = c * local[0] - s * local[1], s * local[0] + c * local[1]
    return np.array([o[0] + rx, o[1] + ry]), np.array([v[0] - w * ry, v[1] + w * rx])


def _carrier(m, bodies, joint):
    if joint == m.output_joint():
        return next(b for b in bodies if b.kind in ("ram", "yoke"))
    return next(b for b in bodies if b.kind != "block" and joint in b.joints)


def _power_torque(m, t, omega2, alpha2, masses, loads):
    """The crank torque from the power balance T omega2 = dKE/dt - sum m g.v_G - sum F.v - sum tau omega, and the
    sum of the balance's absolute terms over |omega2| (its scale)."""
    r = _rates(m, t, omega2, alpha2)
    bodies = linkage_of(m).bodies()
    plain = masses.replace(points={})
    props = body_masses(m, plain)
    frames = {b.name: _frame(b, r) for b in bodies}
    g = np.array(loads.gravity_vector)[:, None]
    terms = []
    for b in bodies:
        bm = props[b.name]
        fr = frames[b.name]
        o, v, a, c, s, w, al = fr
        rx, ry = c * bm.com[0] - s * bm.com[1], s * bm.com[0] + c * bm.com[1]
        vG = np.array([v[0] - w * ry, v[1] + w * rx])
        aG = np.array([a[0] - al * ry - w * w * rx, a[1] + al * rx - w * w * ry])
        terms += [bm.mass * (vG * aG).sum(0), bm.inertia * w * al, -bm.mass * (g * vG).sum(0)]
    for joint, mass in masses.points.items():
        b = _carrier(m, bodies, joint)
        fr = frames[b.name]
        if b.kind in ("ram", "yoke"):
            vP, aP = fr[1], fr[2]
        else:
            _, vP, aP = r[joint]
        terms += [mass * (vP * aP).sum(0), -mass * (g * vP).sum(0)]
    way = m.working_direction(omega2) or loads.working
    xo = r[m.output_joint()] if m.output_joint() else None
    working = (m.motion(t, omega2).v > 0) == (way == "+x") if way else None
    for f in (*loads.forces, *loads.torques):
        x = xo[0][0] if xo is not None else None
        arg = x if f.against == "x" else np.mod(t, 2 * math.pi)
        mag = qropt.dynamics.model.level(f.magnitude, arg)
        win = f.window
        on = np.ones(t.size, bool)
        if win.stroke != "both":
            on &= working if win.stroke == "working" else ~working
        if win.x is not None:
            on &= (x >= win.x[0]) & (x <= win.x[1])
        if win.theta2 is not None:
            on &= np.mod(t - win.theta2[0], 2 * math.pi) <= win.theta2[1] - win.theta2[0]
        mag = mag * on
        if isinstance(f, Torque):
            terms.append(-mag * frames[f.on][5])
            continue
        if isinstance(f.at, str):
            b = _carrier(m, bodies, f.at)
            fr = frames[b.name]
            p = r[f.at][0]
            o, v, _, _, _, w, _ = fr
            vP = np.array([v[0] - w * (p[1] - o[1]), v[1] + w * (p[0] - o[0])])
        else:
            _, vP = _point(frames[f.at[0]], f.at[1:])
        if f.direction == "against":
            speed = np.hypot(*vP)
            F = -mag * vP / np.where(speed > 0, speed, 1.0)  # zero at rest (a ground pivot)
        elif f.direction == "slide":
            F = np.array([mag, 0 * mag])
        else:
            d = np.array(f.direction) / math.hypot(*f.direction)
            F = mag * d[:, None]
        terms.append(-(F * vP).sum(0))
    total = sum(terms)
    scale = sum(np.abs(x) for x in terms)
    return total / omega2, scale / abs(omega2)


def _random_loads(m, rng, kind):
    """Masses and loads of every kind on mechanism m: point masses, a gravity vector, forces at joints and body
    points in each direction kind, torques, windows of each kind, tables against x and theta2."""
    link = linkage_of(m)
    bodies = link.bodies()
    massive_block = any(b.kind == "block" for b in bodies) and rng.random() < 0.5
    joints = sorted({j for b in bodies for j in b.joints})
    turning = [b.name for b in bodies if b.kind not in ("ram", "block") or (b.kind == "block" and massive_block)]
    loadable = [b.name for b in bodies if b.kind != "block" or massive_block]
    masses = Masses(
        density=rng.uniform(1, 20),
        ram=rng.uniform(0, 30),
        block=rng.uniform(0.5, 2) if massive_block else 0.0,
        points={str(rng.choice(joints)): rng.uniform(0.5, 5), joints[-1]: rng.uniform(0.5, 5)},
    )
    xo = m.output_joint()
    if xo is not None:
        x = m.motion(np.linspace(0, 2 * math.pi, 64, endpoint=False), 1.0).x
        lo, hi = float(x.min()), float(x.max())
        xs = np.sort(rng.uniform(lo, hi, 3))
        table = tuple((float(a), float(rng.uniform(-500, 800))) for a in xs)
        xwin = Window(x=(float(xs[0]), float(xs[2])), stroke=str(rng.choice(["working", "return", "both"])))
        against = "x"
    else:
        table = ((0.5, 300.0), (2.0, -100.0), (4.0, 250.0))
        xwin = Window(theta2=(1.0, 4.5))
        against = "theta2"
    a = float(rng.uniform(0, 2 * math.pi))
    forces = [
        Force(str(rng.choice(joints)), table, "against", "working", against=against),
        Force((str(rng.choice(loadable)), rng.uniform(-0.3, 0.3), rng.uniform(-0.2, 0.2)), 700.0, "against", "return"),
        Force((str(rng.choice(loadable)), rng.uniform(-0.3, 0.3), 0.1), -350.0, (rng.normal(), rng.normal()), "always"),
        Force(str(rng.choice(joints)), 250.0, "slide", xwin),
        Force(xo or "B", 900.0, (0.3, -1.0), Window(theta2=(a, a + 2.0))),
    ]
    if xo is not None:
        forces.append(Force(xo, 1200.0, "against", "working"))
    torques = [
        Torque(str(rng.choice(turning)), 40.0, "always"),
        Torque(str(rng.choice(turning)), ((0.0, -30.0), (3.0, 60.0), (6.0, 10.0)), "working", against="theta2"),
    ]
    gravity = (float(rng.uniform(-3, 3)), float(rng.uniform(-10, 10)))
    return masses, Loads(forces=forces, torques=torques, gravity=gravity)


@pytest.mark.parametrize("kind", ALL)
def test_the_torque_is_the_power_balance(kind):
    """Route: the power balance T omega2 = dKE/dt - sum m g.v_G - sum F.v_P - sum tau omega_body, every velocity
    and acceleration from the mechanism's own rates and the contract's body frames. The Newton-Euler torque under
    forces at joints and body points (against, slide, fixed vectors; tables against x and theta2), torques,
    gravity vectors, point masses and windows of every kind agrees to 1e-9 of the balance's terms."""
    rng = np.random.default_rng(ALL.index(kind))
    for i, (_, m) in enumerate(random_mechanisms(kind, 3, seed=11)):
        masses, loads = _random_loads(m, rng, kind)
        omega2 = (1.0 if i % 2 == 0 else -1.0) * rng.uniform(2, 12)
        alpha2 = rng.uniform(-20, 20) if i > 0 else 0.0
        t = rng.uniform(0, 2 * math.pi, 60)
        d = inverse_dynamics(m, t, omega2, alpha2, masses=masses, loads=loads)
        want, scale = _power_torque(m, t, omega2, alpha2, masses, loads)
        err = np.abs(d.torque - want) / np.maximum(scale, 1e-300)
        assert err.max() <= 1e-9, f"{m!r}: {err.max():.3g}"


@pytest.mark.parametrize("kind", ["slider-crank", "whitworth", "coupler-slider", "four-bar"])
def test_the_generalised_load_carries_them(kind):
    """Route: T = M alpha2 + M' omega2^2 / 2 + Q (what simulate integrates) against the Newton-Euler torque, at
    both senses of rotation, with general loads."""
    rng = np.random.default_rng(7)
    for _, m in random_mechanisms(kind, 2, seed=3):
        masses, loads = _random_loads(m, rng, kind)
        t = rng.uniform(0, 2 * math.pi, 40)
        for omega2, alpha2 in ((6.0, 3.0), (-4.0, -7.0)):
            g = generalised(m, t, masses=masses, loads=loads, sense=omega2)
            d = inverse_dynamics(m, t, omega2, alpha2, masses=masses, loads=loads)
            want = g.M * alpha2 + 0.5 * g.dM * omega2**2 + g.Q
            assert np.max(np.abs(d.torque - want)) <= 1e-9 * max(1.0, np.max(np.abs(want))), f"{m!r}"


def test_a_driving_load_gives_a_negative_torque():
    """Route: massless links, T omega2 = F.v_ram. A gas force along +x drives the ram where it moves +x: the
    torque is negative there, -F dx/dtheta2."""
    m = qropt.SliderCrank(r2=0.1, r3=0.4, e=0.02)
    t = np.linspace(0, 2 * math.pi, 73)
    d = m.dynamics(t, 5.0, loads=Loads(forces=[Force("C", 2000.0, "slide", "always")]))
    v = m.motion(t, 5.0).v
    assert np.allclose(d.torque, -2000.0 * v / 5.0, rtol=0, atol=1e-9 * 2000 * 0.1)
    assert (d.torque[v > 1e-9] < 0).all() and (d.torque[v < -1e-9] > 0).all()


def test_the_centred_slider_crank_needs_its_working_direction():
    """At TR = 1 the working stroke is the one the loads name: without it a load on a stroke is an error (never
    dropped); with it the cutting force resists the named stroke: T = F |dx/dtheta2| there, 0 on the other."""
    m = qropt.SliderCrank(r2=0.3, r3=1.2, e=0)
    t = np.linspace(0.05, 2 * math.pi - 0.05, 91)
    for loads in (
        Loads(cutting_force=68_700),
        Loads(forces=[Force("C", 500.0, "against", Window(x=(0.0, 1.0), stroke="return"))]),
        Loads(torques=[Torque("rod", 5.0, "working")]),
    ):
        for call in (
            lambda loads=loads: m.dynamics(t, 10.0, loads=loads),
            lambda loads=loads: m.flywheel(10.0, 0.05, masses=Masses(density=10), loads=loads),
            lambda loads=loads: generalised(m, t, loads=loads),
        ):
            with pytest.raises(InvalidParameter, match="TR = 1.*working="):
                call()
    mo = m.motion(t, 10.0)
    for way, moving in (("+x", mo.v > 0), ("-x", mo.v < 0)):
        d = m.dynamics(t, 10.0, loads=Loads(cutting_force=68_700, working=way))
        want = np.where(moving, 68_700 * np.abs(mo.v) / 10.0, 0.0)
        assert np.allclose(d.torque, want, rtol=1e-12, atol=1e-9)
    fw = m.flywheel(10.0, 0.05, masses=Masses(density=10), loads=Loads(cutting_force=68_700, working="+x"))
    assert fw.working_energy == pytest.approx(68_700 * m.stroke(), rel=1e-9)
    shaper = qropt.Whitworth(r1=0.2, r2=0.5, r5=0.5, r6=1.0)
    other = "+x" if shaper.working_direction(1.0) == "-x" else "-x"
    with pytest.raises(InvalidParameter, match="slow"):
        shaper.dynamics(t, 1.0, loads=Loads(cutting_force=10.0, working=other))


def test_the_shorthands_are_unchanged():
    """Gravity (0, -g) is the number g; a force against the ram's velocity on the working stroke is the cutting
    force, its cycle's extremes included."""
    m = qropt.Whitworth(r1=0.2, r2=0.5, r5=0.5, r6=1.0)
    assert Loads(gravity=(0.0, -9.81)) == Loads(gravity=9.81)
    masses = Masses(density=8.0, ram=20.0)
    t = np.linspace(0.1, 6.2, 50)
    d0 = m.dynamics(t, 4.0, masses=masses, loads=Loads(cutting_force=3000.0, gravity=9.81))
    d1 = m.dynamics(t, 4.0, masses=masses, loads=Loads(cutting_force=3000.0, gravity=(0, -9.81)))
    assert np.array_equal(d0.torque, d1.torque)
    d2 = m.dynamics(t, 4.0, masses=masses, loads=Loads(forces=[Force("D", 3000.0)], gravity=9.81))
    assert np.allclose(d0.torque, d2.torque, rtol=0, atol=1e-9 * np.abs(d0.torque).max())
    for j in d0.joint_forces:
        assert np.allclose(d0.joint_forces[j], d2.joint_forces[j], rtol=0, atol=1e-8 * 3000)
    from qropt.dynamics.cycle import CycleDynamics

    cut, force = (
        CycleDynamics(m, 4.0, 0.0, masses, Loads(cutting_force=3000.0)).extremes(),
        CycleDynamics(m, 4.0, 0.0, masses, Loads(forces=[Force("D", 3000.0)])).extremes(),
    )
    assert force.mean_torque == pytest.approx(cut.mean_torque, rel=1e-9)
    for j, p in cut.peak_forces.items():
        assert force.peak_forces[j].value == pytest.approx(p.value, rel=1e-7), j
    dc = m.dead_centres()
    ends = np.array([dc.theta_max, dc.theta_min])
    for on in (True, False):  # a stroke closed at its dead centres: the force resists the stroke's way there
        a = CycleDynamics(m, 4.0, 0.0, masses, Loads(cutting_force=3000.0)).at(ends, on)
        b = CycleDynamics(m, 4.0, 0.0, masses, Loads(forces=[Force("D", 3000.0)])).at(ends, on)
        for j in a.joint_forces:
            assert np.allclose(a.joint_forces[j], b.joint_forces[j], rtol=0, atol=1e-8 * 3000), (on, j)


def test_point_masses_join_their_body():
    """A point mass at a joint is part of the body that carries it: at the ram's joint, the ram's mass."""
    m = qropt.Whitworth(r1=0.2, r2=0.5, r5=0.5, r6=1.0)
    base = body_masses(m, Masses(density=5.0, ram=3.0))
    more = body_masses(m, Masses(density=5.0, ram=3.0, points={"D": 2.0, "C": 1.5}))
    assert more["ram"].mass == pytest.approx(5.0)
    lever = base["lever"]
    assert more["lever"].mass == pytest.approx(lever.mass + 1.5)
    assert more["lever"].com[0] == pytest.approx((lever.mass * lever.com[0] + 1.5 * 0.5) / (lever.mass + 1.5))
    with pytest.raises(InvalidParameter, match="no joint 'Q'"):
        body_masses(m, Masses(points={"Q": 1.0}))


BAD = [
    (lambda: Force("C", math.inf), "finite"),
    (lambda: Force("C", float("nan")), "finite"),
    (lambda: Force("C", 1.0, (0.0, 0.0)), "zero length"),
    (lambda: Force("C", 1.0, "up"), "direction"),
    (lambda: Force("C", ((1.0, 2.0), (0.5, 3.0))), "increase"),
    (lambda: Force("C", ((1.0, 2.0), (1.0, 3.0))), "increase"),
    (lambda: Force("C", ()), "1 to"),
    (lambda: Force(("rod", 0.1), 1.0), "body's point"),
    (lambda: Force("", 1.0), "non-empty"),
    (lambda: Force("C", 1.0, against="time"), "against"),
    (lambda: Force("C", 1.0, window="sometimes"), "window"),
    (lambda: Window(x=(1.0, 1.0)), "x0 < x1"),
    (lambda: Window(x=(2.0, 1.0)), "x0 < x1"),
    (lambda: Window(x=(0.0, math.inf)), "finite"),
    (lambda: Window(stroke="cutting"), "stroke"),
    (lambda: Window(theta2=(1.0, 0.5)), "theta2"),
    (lambda: Window(theta2=(0.0, 7.0)), "theta2"),
    (lambda: Window(theta2=(0.0, 1.0), stroke="working"), "alone"),
    (lambda: Torque("", 1.0), "body"),
    (lambda: Torque("rod", "big"), "number"),
    (lambda: Loads(gravity=(0.0, math.nan)), "finite"),
    (lambda: Loads(gravity=(1.0,)), "pair"),
    (lambda: Loads(working="up"), "working"),
    (lambda: Loads(forces=Force("C", 1.0)), "list"),
    (lambda: Loads(forces=[3]), "list"),
    (lambda: Loads.from_dict({"forces": [{"at": "C"}]}), "magnitude"),
    (lambda: Loads.from_dict({"forces": [{"at": "C", "magnitude": 1, "colour": "red"}]}), "colour"),
    (lambda: Loads.from_dict({"load": 1}), "loads take"),
    (lambda: Masses(points={"C": -1.0}), "zero or positive"),
    (lambda: Masses(points={"C": math.inf}), "finite"),
    (lambda: Masses(points=[("C", 1.0)]), "dict"),
]


@pytest.mark.parametrize("make, words", BAD)
def test_bad_input_is_a_typed_error(make, words):
    with pytest.raises(InvalidParameter, match=words):
        make()


BAD_ON_A_MECHANISM = [
    (Loads(forces=[Force("Z", 1.0)]), "the force at Z.*no joint 'Z'"),
    (Loads(forces=[Force(("arm", 0.0, 0.0), 1.0)]), "no body 'arm'"),
    (Loads(torques=[Torque("arm", 1.0)]), "the torque on arm.*no body"),
    (Loads(torques=[Torque("ram", 1.0)]), "the ram does not turn"),
    (Loads(forces=[Force(("block", 0.0, 0.0), 1.0)]), "block is massless"),
]


@pytest.mark.parametrize("loads, words", BAD_ON_A_MECHANISM)
def test_a_load_the_mechanism_has_no_place_for_is_a_typed_error(loads, words):
    m = qropt.Whitworth(r1=0.2, r2=0.5, r5=0.5, r6=1.0)
    with pytest.raises(InvalidParameter, match=words):
        m.dynamics(np.array([0.3]), 2.0, loads=loads)


def test_a_four_bar_has_no_ram_position():
    m = qropt.FourBar(r1=1.0, r2=0.3, r3=1.0, r4=0.8)
    with pytest.raises(InvalidParameter, match="no ram"):
        m.dynamics(np.array([0.3]), 2.0, loads=Loads(torques=[Torque("follower", ((0.0, 1.0), (1.0, 2.0)))]))


def test_a_force_at_the_ram_is_at_each_types_output_joint():
    """Force("ram", ...) acts at the output's joint whatever the type names it (C or D): in every type ``design``
    compares, the crank torque and the joint forces equal those of the same force at that joint; ``design`` over
    types whose rams are C and D takes it, each row the row of the cutting-force shorthand; a four-bar, without a
    ram, refuses it by name."""
    from qropt.studies._design import TYPES, type_problem

    t, masses = np.linspace(0.0, 2 * np.pi, 37), Masses.bars(3.0, 10.0)
    joints = set()
    for kind in TYPES:
        cls = type_problem(kind, 1.5, 0.3).mechanism
        m = cls(**cls.EXAMPLE)
        joint = m.output_joint()
        joints.add(joint)
        at = {
            j: m.dynamics(t, 10.0, masses=masses, loads=Loads(forces=[Force(j, 500.0, (0.3, -1.0), "always")]))
            for j in ("ram", joint)
        }
        np.testing.assert_array_equal(at["ram"].torque, at[joint].torque)
        for k, v in at[joint].joint_forces.items():
            np.testing.assert_array_equal(at["ram"].joint_forces[k], v)
    assert joints == {"C", "D"}
    kw = dict(objective="min_peak_torque", types=["crank-shaper", "slot-ram-shaper"], masses=masses, omega2=10.0)
    ram = qropt.design(1.5, 0.3, loads=Loads(forces=[Force("ram", 1000.0)]), **kw)
    short = qropt.design(1.5, 0.3, loads=Loads(1000.0), **kw)
    assert [(r.type, r.result.status) for r in ram.rows] == [(r.type, r.result.status) for r in short.rows]
    for a, b in zip(ram.rows, short.rows, strict=True):
        assert a.result.status == "optimal" and a.result.objective == pytest.approx(b.result.objective, rel=1e-9)
    m = qropt.FourBar(r1=1.0, r2=0.3, r3=1.0, r4=0.8)
    with pytest.raises(InvalidParameter, match="the force at ram: FourBar has no ram; its joints"):
        m.dynamics(np.array([0.3]), 2.0, loads=Loads(forces=[Force("ram", 1.0)]))


def test_the_round_trip():
    loads = Loads(
        cutting_force=((0.0, 10.0), (0.5, 30.0)),
        friction=0.1,
        gravity=(2.0, -9.0),
        forces=[
            Force("C", ((0.0, 1.0), (2.0, 3.0)), "against", Window(x=(0.1, 0.4), stroke="return")),
            Force(("lever", 0.2, -0.1), -40.0, (1.0, 2.0), Window(theta2=(-1.0, 2.0)), against="theta2"),
            Force("D", 5.0, "slide", "always"),
        ],
        torques=[Torque("rod", 3.0, "working"), Torque("lever", ((0.0, 1.0), (1.0, 2.0)), against="theta2")],
        working="+x",
    )
    d = json.loads(json.dumps(loads.to_dict()))
    assert Loads.from_dict(d) == loads
    masses = Masses(density=2.0, ram=1.0, points={"C": 2.0, "A": 0.5})
    assert Masses.from_dict(json.loads(json.dumps(masses.to_dict()))) == masses
    assert "points" not in Masses(density=1.0).to_dict() and "forces" not in Loads().to_dict()
    p = qropt.Problem(
        "whitworth",
        free={"r1": (0.1, 0.3)},
        fixed={"r2": 0.5, "r5": 0.5, "r6": 1.0},
        targets={"time_ratio": 2.0},
        loads=loads,
    )
    back = qropt.Problem.from_toml(p.to_toml())
    assert back.loads == loads


def test_what_cannot_take_them_says_so():
    """The compiled kernel raises, naming the load."""
    m = qropt.Whitworth(r1=0.2, r2=0.5, r5=0.5, r6=1.0)
    from qropt.dynamics import compiled
    from qropt.dynamics.inverse import system_of

    with pytest.raises(UnsupportedLoad, match="compiled.*gravity"):
        compiled.parts(m, system_of(m, Masses(density=1.0)), np.array([0.1]), 1.0, 0.0, (1.0, -9.81), 1.0)


def test_the_servos_profile_takes_them():
    """The servo's torque M alpha2 + M' omega2^2 / 2 + Q with Q from every load: the cutting force stated as a
    force against the ram on the working stroke gives the shorthand's profile; a torque on the rod and a tilted
    gravity count (test_servo.py checks such a profile by the inverse dynamics); pin friction is refused by name."""
    m = qropt.SliderCrank(r2=0.1, r3=0.4, e=0.05)
    kw = dict(omega_max=20, v_cut=0.5, alpha_max=400, masses=Masses.bars(2.0, 5.0), torque_max=12.0)
    short = qropt.speed_profile(m, loads=Loads(100.0), **kw)
    general = qropt.speed_profile(m, loads=Loads(forces=[Force("C", 100.0, "against", "working")]), **kw)
    assert short.status == general.status == "optimal"
    assert general.cycle_time == pytest.approx(short.cycle_time, rel=1e-7)
    loads = Loads(forces=[Force("C", 100.0, "against", "working")], torques=[Torque("rod", 0.5)], gravity=(3.0, -9.0))
    sp = qropt.speed_profile(m, loads=loads, **kw)
    assert sp.status == "optimal" and sp.cycle_time > short.cycle_time + 5e-4  # the loads count
    with pytest.raises(UnsupportedLoad, match="servo.*pin friction"):
        qropt.speed_profile(m, loads=Loads(pin_friction=qropt.PinFriction(0.1, 0.01)), **kw)


def test_simulate_and_the_flywheel_take_them():
    """The flywheel's energy per turn is the loads' work: with massless links and a force along a fixed vector
    only (a conservative load) it is zero. A force against the ram's velocity on the working stroke is the cutting
    force: the forward simulation under it follows the same motion."""
    m = qropt.Whitworth(r1=0.2, r2=0.5, r5=0.5, r6=1.0)
    fixed = Loads(forces=[Force(("lever", 0.3, 0.0), 100.0, (1.0, 1.0), "always")])
    fw = m.flywheel(5.0, 0.05, loads=fixed)
    assert abs(fw.energy_per_turn) <= 1e-9 * 100.0
    masses = Masses(density=10.0, ram=5.0)
    runs = []
    for loads in (Loads(cutting_force=500.0), Loads(forces=[Force("D", 500.0)])):
        T = qropt.dynamics.steady_mean_torque(m, 5.0, masses, loads)
        runs.append(qropt.simulate(m, qropt.Motor.constant(T), masses=masses, loads=loads, omega0=5.0, turns=2))
    assert np.allclose(runs[0].omega2, runs[1].omega2, rtol=1e-7)


@pytest.mark.parametrize("stroke, share", [("working", 1.0), ("return", -1.0), ("both", 0.0)])
def test_the_energy_of_a_window_is_its_work(stroke, share):
    """Route: the work of a constant force along the slide over a window of the ram's positions, F (x1 - x0) on a
    stroke, resisted on the working stroke (the motor delivers it) and driving on the return (it gives it back):
    the flywheel's energy per turn, with the quadrature split at the window's ends, to 1e-9."""
    m = qropt.Whitworth(r1=0.2, r2=0.5, r5=0.5, r6=1.0)
    way = 1.0 if m.working_direction(3.0) == "+x" else -1.0
    F, x0, x1 = 1500.0, 0.7, 1.2
    loads = Loads(forces=[Force("D", -way * F, "slide", Window(x=(x0, x1), stroke=stroke))])
    fw = m.flywheel(3.0, 0.05, loads=loads)
    assert fw.energy_per_turn == pytest.approx(share * F * (x1 - x0), abs=1e-9 * F)
