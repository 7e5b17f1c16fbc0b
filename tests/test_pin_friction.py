"""Coulomb friction at the pins (``Loads.pin_friction``) and the mechanical efficiency, each against an independent
route:

- the power balance T omega2 = d(KE)/dt + d(PE)/dt + the loads' power + the friction's (the slide's and the pins'),
  every rate a Richardson-extrapolated central difference of the exact positions (no jet), each pin's loss
  recomputed as mu r |F| |omega_rel| from the joint forces qropt reports and the bodies' angles' differences;
- mu = 0 against the frictionless analysis;
- a lock against the friction-circle check of a massless slider-crank: the rod's force line, tangent to the
  friction circles at A and C on the sides the relative rotations set, can stand normal to the slide
  (mu |r_A s_A + r_C s_C| >= |x_C - x_A|), where the linkage jams;
- the efficiency of the working stroke and of the turn against a dense trapezoid of the loads' and the friction's
  power (a driving load read the other way);
- bad input, the round trip, and the parts that refuse pin friction.
"""

from __future__ import annotations

import dataclasses
import json
import math
import tomllib

import numpy as np
import pytest
import tomli_w

import qropt
from qropt import Force, Loads, Masses
from qropt.dynamics.cycle import CycleDynamics
from qropt.dynamics.inverse import body_masses, inverse_dynamics, linkage_of
from qropt.dynamics.model import PinFriction
from qropt.errors import InvalidParameter, PinLocked, UnsupportedLoad

TWO_PI = 2 * math.pi
H = 2e-3  # crank-angle step of the differences (Richardson with h and h/2), as tests/test_dynamics.py
G0 = 9.81


def _slider_crank():
    return qropt.SliderCrank(r2=0.12, r3=0.45, e=0.03)


def _crank_rocker_slider():
    return qropt.CrankRockerSlider(
        r1=0.5, r2=0.12, r3=0.45, r4=0.35, r5=0.4, r6=0.6, h=0.1, sigma=1.0, sigma_slider=1.0
    )


def _crank_shaper():
    return qropt.CrankShaper(r1=0.3, r2=0.1, r4=0.7)  # a massless block at A: its pin's force is the slot's


CASES = {
    "slider-crank": (_slider_crank, PinFriction(0.15, 0.02, {"C": (0.3, 0.015)})),
    "crank-shaper": (_crank_shaper, PinFriction(0.1, 0.02)),
    "crank-rocker-slider": (_crank_rocker_slider, PinFriction(0.12, 0.025, {"O4": 0.04})),
}


def _mech(kind):
    return CASES[kind][0]()


def _angle(body, p):
    """The body's angle (rad) from exact joint positions (n, 2), as its frame defines it (0 for a ram)."""
    if body.kind in ("ram", "yoke"):
        return np.zeros(len(next(iter(p.values()))))
    a, b = p[body.joints[0]], p[body.joints[1]]
    d = a - b if body.kind == "block" else b - a
    return np.unwrap(np.arctan2(d[:, 1], d[:, 0]))


def _centre(body, bm, p):
    phi = _angle(body, p)
    o = p[body.joints[0]]
    if body.kind == "yoke":
        o = np.stack([o[:, 0], 0 * o[:, 1]], axis=1)
    c, s = np.cos(phi), np.sin(phi)
    return np.stack([o[:, 0] + c * bm.com[0] - s * bm.com[1], o[:, 1] + s * bm.com[0] + c * bm.com[1]], axis=1)


def _rates(f, t):
    """(value, d/dtheta, d2/dtheta2) of f(theta) (n, ...) at t: Richardson on central differences."""

    def d(h):
        fm, f0, fp = f(t - h), f(t), f(t + h)
        return (fp - fm) / (2 * h), (fp - 2 * f0 + fm) / (h * h)

    (d1h, d2h), (d1q, d2q) = d(H), d(H / 2)
    return f(t), (4 * d1q - d1h) / 3, (4 * d2q - d2h) / 3


def _balance(m, t, omega2, masses, loads, d):
    """The crank power the balance needs and its scale, and each pin's loss recomputed: (power, scale, losses)."""
    bodies = linkage_of(m).bodies()
    props = body_masses(m, masses)
    pos = lambda th: m.positions(th).points  # noqa: E731
    terms = []
    spin = {}
    for b in bodies:
        if b.name not in props:
            continue
        bm = props[b.name]
        _, v, a = _rates(lambda th, b=b, bm=bm: _centre(b, bm, pos(th)), t)
        _, w, al = _rates(lambda th, b=b: _angle(b, pos(th)), t)
        spin[b.name] = w * omega2
        v, a = v * omega2, a * omega2**2
        terms.append(bm.mass * np.sum(v * a, axis=1) + bm.inertia * w * omega2 * al * omega2**2)  # d(KE)/dt
        terms.append(bm.mass * G0 * v[:, 1])  # d(PE)/dt
    _, xv, _ = _rates(lambda th: m.positions(th).x, t)
    vx = xv * omega2  # m/s (the mechanisms here are in metres)
    on = CycleDynamics(m, omega2, 0.0, masses, loads)
    working = np.array([_on_working(on, th) for th in t])
    terms.append(np.where(working, loads.cutting_force * np.abs(vx), 0.0))  # what the cut absorbs
    terms.append(np.abs(d.joint_forces["slide"][:, 0] * vx))  # the slide's friction
    losses = {}
    pf = loads.pin_friction
    for c in linkage_of(m).connections():
        if c.kind != "pin":
            continue
        mu, r = pf.at(c.joint)
        rel = spin.get(c.receiver, 0.0) - spin.get(c.giver, 0.0)
        key = f"{c.joint}/block" if c.receiver == "block" and f"{c.joint}/block" in d.joint_forces else c.joint
        losses[c.joint] = mu * r * np.hypot(*d.joint_forces[key].T) * np.abs(rel)
        terms.append(losses[c.joint])
    power = np.sum(terms, axis=0)
    scale = np.sum(np.abs(terms), axis=0)
    return power, scale, losses


def _on_working(cd, th):
    lo, hi = cd.pieces[0]
    first = lo <= lo + (th - lo) % TWO_PI < hi
    return first == cd.working_pieces[0]


THETA = np.linspace(0.0, TWO_PI, 25)[:-1] + 0.0123


@pytest.mark.parametrize("kind", [*CASES, "crank-shaper/massive-block"])
def test_power_balance_and_pin_losses(kind):
    """T omega2 = d(KE + PE)/dt + the cut's power + the slide's and the pins' friction power, to 1e-7 of the
    balance's terms; each pin's loss equals mu r |F| |omega_rel| from the reported forces and differenced angles;
    each friction moment is mu r |F| against the relative rotation."""
    block = kind.endswith("/massive-block")  # the block a body: its pin's force is the pin's own, A/block
    kind = kind.partition("/")[0]
    m, pf = _mech(kind), CASES[kind][1]
    masses = Masses.bars(4.0, 12.0, block=1.5 if block else 0.0)
    loads = Loads(cutting_force=800.0, friction=0.12, gravity=G0, pin_friction=pf)
    omega2 = 7.0
    d = inverse_dynamics(m, THETA, omega2, masses=masses, loads=loads)
    power, scale, losses = _balance(m, THETA, omega2, masses, loads, d)
    np.testing.assert_array_less(np.abs(d.torque * omega2 - power), 1e-7 * scale)
    assert set(d.pin_power_loss) == set(losses)
    for j, want in losses.items():
        np.testing.assert_allclose(d.pin_power_loss[j], want, rtol=1e-6, atol=1e-9 * scale.max())
        mu, r = pf.at(j)
        key = f"{j}/block" if f"{j}/block" in d.joint_forces else j
        np.testing.assert_allclose(np.abs(d.pin_moments[j]), mu * r * np.hypot(*d.joint_forces[key].T), rtol=1e-12)
    assert sum(float(v.sum()) for v in losses.values()) > 1e-3 * float(np.abs(d.power).sum())  # friction matters


@pytest.mark.parametrize("kind", list(CASES))
def test_zero_mu_is_frictionless(kind):
    m = _mech(kind)
    masses = Masses.bars(4.0, 12.0)
    plain = Loads(cutting_force=800.0, friction=0.12, gravity=G0)
    zero = dataclasses.replace(plain, pin_friction=PinFriction(0.0, 0.02))
    a = inverse_dynamics(m, THETA, 7.0, masses=masses, loads=plain)
    b = inverse_dynamics(m, THETA, 7.0, masses=masses, loads=zero)
    scale = np.abs(a.torque).max()
    np.testing.assert_allclose(b.torque, a.torque, rtol=0, atol=1e-12 * scale)
    for j, f in a.joint_forces.items():
        np.testing.assert_allclose(b.joint_forces[j], f, rtol=0, atol=1e-12 * np.abs(f).max())
    pins = {c.joint for c in linkage_of(m).connections() if c.kind == "pin"}
    assert set(b.pin_power_loss) == set(b.pin_moments) == pins
    assert all(not v.any() for v in b.pin_power_loss.values())
    assert a.pin_power_loss is None and not a.pin_friction_power.any()


def test_lock_against_the_friction_circles():
    """A massless slider-crank (the rod a two-force member): it jams where its force line, tangent to the friction
    circles at A and C on the sides the relative rotations set, can stand normal to the slide:
    mu |r_A sign(w3 - w2) + r_C sign(w3)| >= |x_C - x_A|. qropt raises PinLocked exactly there (and only there:
    with the rotations opposed the circles' offsets cancel)."""
    m = qropt.SliderCrank(r2=0.2, r3=0.3, e=0.02)
    mu, r = 0.25, 0.5
    loads = Loads(cutting_force=1000.0, pin_friction=PinFriction(mu, r))
    seen = {True: 0, False: 0}
    for th in np.linspace(0.0, TWO_PI, 121)[:-1] + 0.0037:
        p = m.positions(np.array([th - 1e-6, th, th + 1e-6])).points
        a, c = p["A"], p["C"]
        beta = np.unwrap(np.arctan2(c[:, 1] - a[:, 1], c[:, 0] - a[:, 0]))
        w3 = (beta[2] - beta[0]) / 2e-6  # omega2 = 1
        offset = mu * r * abs(np.sign(w3 - 1.0) + np.sign(w3))
        reach = abs(c[1, 0] - a[1, 0])
        if abs(offset - reach) < 1e-6 or abs(w3) < 1e-6:
            continue
        want = offset >= reach
        try:
            inverse_dynamics(m, [th], 1.0, loads=loads)
            got = False
        except PinLocked as e:
            got = True
            assert e.joint in ("A", "C") and abs(e.theta2 - th % TWO_PI) < 1e-12
            assert "locks" in str(e) and "at pin" in str(e)
        assert got == want, th
        seen[want] += 1
    assert seen[True] >= 10 and seen[False] >= 10


def _trapezoid(m, loads, masses, omega2, lo, hi, n=20001):
    """(what the loads absorb, what friction dissipates, the crank's work) over the stroke [lo, hi] (J), by the
    trapezoid rule on n angles; the stroke closed at its dead centres with its own loads (the cut on or off, the
    slide's friction against the stroke's way) at both ends."""
    t = np.linspace(lo, hi, n)
    cd = CycleDynamics(m, omega2, 0.0, masses, loads)
    on = _on_working(cd, 0.5 * (lo + hi))
    d = cd.at(t % TWO_PI, on)
    v = m.motion(t % TWO_PI, omega2).v  # m/s (metres)
    working = np.full(t.shape, on)
    absorbed = np.where(working, loads.cutting_force * np.abs(v), 0.0)
    for f in loads.forces:  # 'against' the ram's velocity, always: absorbs magnitude * |v|
        absorbed = absorbed + f.magnitude * np.abs(v)
    lost = d.pin_friction_power + np.abs(d.joint_forces["slide"][:, 0] * v)
    dt = (t[1] - t[0]) / abs(omega2)
    trap = lambda f: float(np.trapezoid(f, dx=dt))  # noqa: E731
    return trap(absorbed), trap(lost), trap(d.power), trap(d.pin_friction_power)


TRAP = 2e-5  # the trapezoid's error where a pin stops turning (its moment turns over: a jump) is h |jump| / 2


@pytest.mark.parametrize("kind", list(CASES))
def test_efficiency_against_a_dense_trapezoid(kind):
    """The crank's work, the friction's and the efficiency of the working stroke and the turn against the trapezoid
    rule on 20001 angles of each stroke of the loads' power (the cut times |v|) and the friction's; the loads' work,
    which qropt takes from the power balance, to 1e-6 (its integrand is smooth)."""
    m, pf = _mech(kind), CASES[kind][1]
    masses = Masses.bars(4.0, 12.0)
    loads = Loads(cutting_force=800.0, friction=0.12, gravity=G0, pin_friction=pf)
    omega2 = 7.0
    cd = CycleDynamics(m, omega2, 0.0, masses, loads)
    e = cd.efficiency()
    pieces = cd.pieces if cd.working_pieces[0] else cd.pieces[::-1]
    out, lost, w_in, _ = _trapezoid(m, loads, masses, omega2, *pieces[0])
    assert e.working.driven_by == "crank"
    assert e.working.efficiency == pytest.approx(out / (out + lost), rel=TRAP)
    assert e.working.input == pytest.approx(w_in, rel=TRAP)
    assert e.working.output == pytest.approx(out, rel=1e-6)
    assert e.working.friction == pytest.approx(lost, rel=TRAP)
    turn = [_trapezoid(m, loads, masses, omega2, *p) for p in cd.pieces]
    out, lost, w_in, pins = (sum(v) for v in zip(*turn, strict=True))
    assert e.turn.efficiency == pytest.approx(out / w_in, rel=TRAP)  # at constant speed the turn stores nothing
    assert e.turn.output == pytest.approx(out, rel=1e-6)
    assert sum(e.turn.pins.values()) == pytest.approx(pins, rel=TRAP)
    assert 0.5 < e.turn.efficiency < 1.0


def test_a_driving_load_reads_the_other_way():
    """A force that pushes the ram along its velocity all the turn (it drives the machine): over the turn the loads
    deliver energy, and the efficiency is what reaches the crank over what they deliver."""
    m = _slider_crank()
    masses = Masses.bars(4.0, 12.0)
    push = Force("C", -600.0, "against", "always")
    loads = Loads(forces=(push,), gravity=G0, pin_friction=PinFriction(0.15, 0.02))
    cd = CycleDynamics(m, 7.0, 0.0, masses, loads)
    e = cd.efficiency()
    out, lost, w_in, _ = (sum(v) for v in zip(*[_trapezoid(m, loads, masses, 7.0, *p) for p in cd.pieces], strict=True))
    assert out < 0 and e.turn.driven_by == "loads"
    assert e.turn.output == pytest.approx(out, rel=1e-6)
    assert e.turn.efficiency == pytest.approx(w_in / out, rel=TRAP)
    assert 0.5 < e.turn.efficiency < 1.0


def test_bad_input_and_round_trip():
    for bad in (
        dict(mu=-0.1, radius=0.01),
        dict(mu=math.nan, radius=0.01),
        dict(mu=0.1, radius=0.0),
        dict(mu=0.1, radius=-1.0),
        dict(mu=0.1),
        dict(mu=0.1, radius=0.01, joints={"A": (0.1, 0.0)}),
        dict(mu=0.1, radius=0.01, joints={"A": (0.1, 0.01, 3)}),
        dict(mu=0.1, radius=0.01, joints=["A"]),
    ):
        with pytest.raises(InvalidParameter):
            PinFriction(**bad)
    with pytest.raises(InvalidParameter, match="pin_friction"):
        Loads(pin_friction=0.1)
    m = _slider_crank()
    with pytest.raises(InvalidParameter, match="Z"):
        inverse_dynamics(m, [0.3], 1.0, loads=Loads(pin_friction=PinFriction(0.1, 0.01, {"Z": 0.02})))
    shaper = qropt.CrankShaper(r1=0.3, r2=0.1, r4=0.7)  # its C: the lever's slot and the yoke's guide
    with pytest.raises(InvalidParameter, match="not a pin"):
        inverse_dynamics(shaper, [0.3], 1.0, loads=Loads(pin_friction=PinFriction(0.1, 0.01, {"C": 0.02})))
    loads = Loads(cutting_force=500.0, pin_friction=PinFriction(0.1, 0.01, {"A": 0.02, "C": (0.2, 0.03)}))
    d = loads.to_dict()
    assert Loads.from_dict(json.loads(json.dumps(d))) == loads
    assert Loads.from_dict(tomllib.loads(tomli_w.dumps(d))) == loads
    assert "pin_friction" not in Loads(cutting_force=500.0).to_dict()
    only = PinFriction(0.1, joints={"A": 0.02})
    assert only.at("O2") == (0.0, 0.0) and only.at("A") == (0.1, 0.02)


def test_the_parts_that_cannot_apply_it_refuse():
    from qropt.dynamics import compiled
    from qropt.dynamics.inverse import crank_acceleration, generalised, system_of

    m = _slider_crank()
    loads = Loads(cutting_force=500.0, pin_friction=PinFriction(0.1, 0.01))
    with pytest.raises(UnsupportedLoad, match="pin friction"):
        loads.require_plain("the synthesis NLP (min_peak_torque)")
    with pytest.raises(UnsupportedLoad, match="pin friction"):
        generalised(m, [0.1], loads=loads)
    s = system_of(m, Masses.bars(4.0, 12.0))
    with pytest.raises(UnsupportedLoad, match="pin friction"):
        crank_acceleration(m, s, 0.1, 5.0, loads, 10.0, 0.1)
    with pytest.raises(UnsupportedLoad, match="pin friction"):
        compiled.parts(m, s, np.array([0.1]), 5.0, 0.0, 0.0, 1.0, loads=loads)
    with pytest.raises(UnsupportedLoad, match="pin friction"):
        qropt.simulate(m, lambda w: 10.0, masses=Masses.bars(4.0, 12.0), loads=loads, flywheel=0.1, omega0=5.0)
