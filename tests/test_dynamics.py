"""Inverse dynamics (``m.dynamics``, ``m.flywheel``, ``m.dynamic_extremes``): each checked by an independent route.

qropt differentiates the loop with jets and solves one Newton-Euler system per crank angle. The references here
never use a jet nor ``qropt.dynamics.inverse.generalised``: each body's centre of mass G and angle come from the
exact joint positions (``m.positions``) and the mass model in the body frame (``m.body_masses``), and every rate is
a Richardson-extrapolated central difference in the crank angle (theta2 = omega2 t: d/dt = omega2 d/dtheta2,
d^2/dt^2 = omega2^2 d^2/dtheta2^2 + alpha2 d/dtheta2). Routes:

- the power balance T omega2 = d(KE)/dt + d(PE)/dt + cutting (and friction) power, every type;
- Newton-Euler body by body from the joint forces qropt reports (the connections of the builder linkage), every type;
- the static limit (massless links): T = sign(omega2) F |dx/dtheta2| on the working stroke, 0 on the return;
- the shaking force and moment as minus the rate of change of the total momentum and angular momentum;
- symmetry: a mirrored slider-crank, and the scaling laws T ~ s^3 (lengths) and T ~ omega2^2; mm against m;
- a hand-derived closed form of the centred slider-crank's torque;
- the flywheel and the cycle extremes against a dense trapezoid rule;
- bad input: typed errors naming the problem.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import qropt
from qropt import BodyMass, Counterweight, Loads, Masses
from tests.randmech import random_mechanisms

KINDS = (
    "slider-crank",
    "crank-shaper",
    "whitworth",
    "crank-rocker-slider",
    "drag-link-slider",
    "four-bar",
    "coupler-slider",
    "slot-ram-shaper",
)
SLIDER_KINDS = tuple(k for k in KINDS if k != "four-bar")
TWO_PI = 2 * math.pi
H = 2e-3  # crank-angle step (rad) of the differences, Richardson with h and h/2: it balances the O(h^4) truncation
# and the ~eps / h^2 rounding of the second derivative (measured worst power error 5e-9 here; 4e-9 at h = 1e-3 and
# 8e-8 at h = 4e-3), so every tolerance on a difference below is 1e-6, >= 20x the worst measured
THETA = np.linspace(0.0, TWO_PI, 37)[:-1] + 0.0123  # 36 crank angles, none on a special position
G0 = 9.81


def _designs(kind, n=3, seed=5):
    """n random valid mechanisms of a kind; the crank-shaper's list holds both the yoke and the rod variants."""
    out = random_mechanisms(kind, 12 if kind == "crank-shaper" else n, seed)
    if kind == "crank-shaper":
        yoke = [d for d in out if "r6" not in d[0]]
        rod = [d for d in out if "r6" in d[0]]
        out = yoke[: max(1, n - 1)] + rod[: min(1, n - 1)]
        assert len(out) == n and {"r6" in p for p, _ in out} == ({True, False} if n > 1 else {False})
    return [m for _, m in out[:n]]


def _case(kind, i, m):
    """Masses and loads for the i-th mechanism of a kind: bars, a ram, a counterweight, an off-axis body, a massive
    block (the first slotted mechanism), an offset yoke centre, gravity, a cutting force (a follower torque for the
    four-bar), friction on the third; omega2 and alpha2 of both signs."""
    bodies = m.bodies()
    names = [b.name for b in bodies]
    slotted = "block" in names
    over = {}
    bars = [b for b in bodies if b.kind in ("bar", "plate", "slot-lever") and b.name != "crank"]
    if bars:  # a body whose centre is off its axis, with its own inertia
        over[bars[-1].name] = BodyMass(1.1 + 0.3 * i, (0.04 + 0.02 * i, 0.03 - 0.025 * i), 0.006 + 0.002 * i)
    if "yoke" in names and i % 2 == 1:
        over["yoke"] = BodyMass(2.0, (0.04, 0.07), 0.01)
    masses = Masses.bars(
        1.5 + i,
        2.5 + i,
        block=0.7 if slotted and i == 0 else 0.0,
        bodies=over,
        counterweight=Counterweight(0.8, 0.6 * m.params["r2"], math.pi - 0.4 * i),
    )
    if kind == "four-bar":
        loads = Loads(follower_torque=25.0 + 10 * i, gravity=G0)
    else:
        loads = Loads(cutting_force=150.0 * (i + 1), gravity=G0, friction=0.12 if i == 2 else 0.0)
    omega2 = (6.0, -4.0, 9.0)[i % 3]
    alpha2 = (0.0, 3.0, -5.0)[i % 3]
    return masses, loads, omega2, alpha2


def _wrap(a):
    return (a + math.pi) % TWO_PI - math.pi


def _poses(m, props, theta):
    """body -> (G (n, 2), angle (n,)) from the exact joint positions: the body frame's origin at its first joint,
    x towards its second (a block: along O4->A, i.e. from its second joint to its first; a ram or yoke: no turn,
    the yoke's origin on y = 0 under x_C), G = origin + R(angle) com."""
    pts = m.positions(theta).points
    out = {}
    for b in m.bodies():
        j = b.joints
        if b.kind == "ram":
            o, phi = pts[j[0]], np.zeros(theta.shape)
        elif b.kind == "yoke":
            o, phi = np.column_stack([pts[j[0]][:, 0], np.zeros(theta.shape)]), np.zeros(theta.shape)
        else:
            d = pts[j[0]] - pts[j[1]] if b.kind == "block" else pts[j[1]] - pts[j[0]]
            o, phi = pts[j[0]], np.arctan2(d[:, 1], d[:, 0])
        cx, cy = props[b.name].com
        c, s = np.cos(phi), np.sin(phi)
        out[b.name] = (o + np.column_stack([c * cx - s * cy, s * cx + c * cy]), phi)
    return out


def _diff(values, h):
    """First and second derivatives from samples at offsets (-h, -h/2, 0, h/2, h), Richardson-extrapolated."""
    fm, fm2, f0, fp2, fp = values
    d1 = (4 * (fp2 - fm2) / h - (fp - fm) / (2 * h)) / 3
    d2 = (4 * (fp2 - 2 * f0 + fm2) / (h / 2) ** 2 - (fp - 2 * f0 + fm) / h**2) / 3
    return d1, d2


OFFSETS = (-H, -H / 2, 0.0, H / 2, H)


def _kinematics(m, props, theta, omega2, alpha2):
    """body -> dict(G, v, a, phi, w, alpha, mass, inertia): positions exact, rates by finite differences."""
    samples = [_poses(m, props, theta + d) for d in OFFSETS]
    out = {}
    for name, bm in props.items():
        G = [s[name][0] for s in samples]
        phi0 = samples[2][name][1]
        phi = [phi0 + _wrap(s[name][1] - phi0) for s in samples]
        g1, g2 = _diff(G, H)
        p1, p2 = _diff(phi, H)
        out[name] = {
            "G": G[2],
            "v": omega2 * g1,
            "a": omega2**2 * g2 + alpha2 * g1,
            "phi": phi0,
            "w": omega2 * p1,
            "alpha": omega2**2 * p2 + alpha2 * p1,
            "mass": bm.mass,
            "inertia": bm.inertia,
        }
    return out


def _cross(r, f):
    return r[..., 0] * f[..., 1] - r[..., 1] * f[..., 0]


def _output_body(m):
    return next((b for b in m.bodies() if b.kind in ("ram", "yoke")), None)


def _working(m, omega2, rate):
    """Whether the output moves on its working stroke, from the sign of its rate (independent of qropt's split)."""
    way = m.working_direction(omega2)
    return np.sign(rate) == (1.0 if way == "+x" else -1.0)


def _cutting_force(m, loads, omega2, kin):
    """(n, 2) force on the output body: magnitude F resisting its motion on the working stroke, zero on the return."""
    out = _output_body(m)
    v = kin[out.name]["v"][:, 0]
    F = loads.force_at(m.positions(THETA).points[m.output_joint()][:, 0])
    fx = np.where(_working(m, omega2, v), -F * np.sign(v), 0.0)
    return np.column_stack([fx, np.zeros_like(fx)])


def _connections(m, props):
    """The connections the force analysis uses and the key of each force: a massless crank-pin block is dropped
    and its force passes crank -> lever; a massive block's pin is 'A/block'; the ram's guide is 'slide'."""
    conns = list(type(m).linkage(m.params).connections())
    block = next((b for b in m.bodies() if b.kind == "block"), None)
    massive = block is not None and props[block.name].mass > 0
    if block is not None and not massive:
        pin = next(c for c in conns if c.receiver == block.name and c.kind == "pin")
        conns = [c._replace(giver=pin.giver) if c.giver == block.name else c for c in conns if c is not pin]
    out = []
    for c in conns:
        if c.kind == "guide":
            key = "slide"
        elif c.kind == "pin" and massive and c.receiver == block.name:
            key = f"{c.joint}/block"
        else:
            key = c.joint
        out.append((c, key))
    return out, massive


# ---- 1. power balance ----------------------------------------------------------------------------------------------
@pytest.mark.parametrize("kind", KINDS)
def test_power_balance_every_type(kind):
    """Route: energy. T omega2 = sum(m a_G . v_G + I alpha w) + sum(m g v_Gy) + F |v| on the working stroke (+ mu |N|
    |v| with friction; tau |w4| for the four-bar's follower torque), rates from finite differences of the exact
    positions. Tolerance 1e-6 of the peak |T omega2|, the differences being good to ~1e-9 (measured worst 4.9e-9,
    a Whitworth; the others <= 1.4e-9)."""
    worst = 0.0
    for i, m in enumerate(_designs(kind)):
        masses, loads, omega2, alpha2 = _case(kind, i, m)
        props = m.body_masses(masses)
        d = m.dynamics(THETA, omega2, alpha2, masses=masses, loads=loads)
        kin = _kinematics(m, props, THETA, omega2, alpha2)
        power = np.zeros(THETA.shape)
        for k in kin.values():
            power += k["mass"] * np.sum(k["a"] * k["v"], axis=1) + k["inertia"] * k["alpha"] * k["w"]
            power += k["mass"] * loads.gravity * k["v"][:, 1]
        out = _output_body(m)
        if out is not None:
            v = kin[out.name]["v"][:, 0]
            power -= _cutting_force(m, loads, omega2, kin)[:, 0] * v
            power += loads.friction * np.abs(d.joint_forces["slide"][:, 1]) * np.abs(v)
        else:
            w4 = kin["follower"]["w"]
            power += np.where(_working(m, omega2, w4), loads.follower_torque * np.abs(w4), 0.0)
        err = np.max(np.abs(d.power - power)) / np.max(np.abs(power))
        worst = max(worst, err)
        assert err < 1e-6, f"{m!r}: T omega2 differs from the rate of energy by {err:.2e} of the peak power"
    assert worst < 1e-6


# ---- 2. Newton-Euler body by body --------------------------------------------------------------------------------
def _resultant(m, d, kin, conns, group, point, loads, omega2):
    """Force (n, 2) and moment about ``point`` (n,) of everything acting on the bodies of ``group`` from outside
    it: joint forces (+ on the receiver, - on the giver), the motor torque on the crank, the yoke guide's moment,
    gravity at each G, the cutting force through the output body's point. Forces between two bodies of the group
    cancel (both act at the same joint)."""
    F = np.zeros((THETA.size, 2))
    M = np.zeros(THETA.size)
    for c, key in conns:
        f = d.joint_forces[key]
        at = kin[c.receiver]["G"] if (c.kind == "guide" and c.receiver == "yoke") else None
        if at is None:
            at = m.positions(THETA).points[c.joint]
        for body, sign in ((c.receiver, 1.0), (c.giver, -1.0)):
            if body in group:
                F += sign * f
                M += _cross(at - point, sign * f)
    if "crank" in group:
        M += d.torque
    if "yoke" in group:
        M += d.guide_moment
    for name in group:
        k = kin[name]
        g = np.column_stack([np.zeros(THETA.size), np.full(THETA.size, -k["mass"] * loads.gravity)])
        F += g
        M += _cross(k["G"] - point, g)
    out = _output_body(m)
    if out is not None and out.name in group:
        fc = _cutting_force(m, loads, omega2, kin)
        F += fc
        M += _cross(kin[out.name]["G"] - point, fc)
    elif out is None and "follower" in group:
        w4 = kin["follower"]["w"]
        M -= np.where(_working(m, omega2, w4), loads.follower_torque * np.sign(w4), 0.0)
    return F, M


@pytest.mark.parametrize("kind", KINDS)
def test_newton_euler_body_by_body(kind):
    """Route: Newton-Euler from the reported joint forces. For every moving body: sum of the forces it receives
    (from the builder's connections) + gravity + cutting force = m a_G, and the moments about G (+ the motor torque
    on the crank, the yoke guide's moment) = I alpha, with a_G and alpha by finite differences of the exact
    positions. A massive crank-pin block and its lever also carry a couple qropt does not report: their moment
    balance is checked together, about O4, where it cancels. Every reported force key is used. Tolerance 1e-6 of
    the largest force (moments: of the largest force times the mechanism's size); measured worst 8e-10 (forces)
    and 4e-11 (moments)."""
    for i, m in enumerate(_designs(kind)):
        masses, loads, omega2, alpha2 = _case(kind, i, m)
        props = m.body_masses(masses)
        d = m.dynamics(THETA, omega2, alpha2, masses=masses, loads=loads)
        kin = _kinematics(m, props, THETA, omega2, alpha2)
        conns, massive = _connections(m, props)
        assert sorted(d.joint_forces) == sorted(key for _, key in conns), f"{m!r}: force keys"
        pts = m.positions(THETA).points
        size = max(np.max(np.hypot(*p.T)) for p in pts.values())
        fscale = max(np.max(np.hypot(*f.T)) for f in d.joint_forces.values())
        groups = [{b} for b in kin if not (massive and b in ("block", "lever")) and (massive or b != "block")]
        if massive:
            groups.append({"block", "lever"})
        for group in groups:
            point = pts["O4"] if len(group) > 1 else kin[next(iter(group))]["G"]
            F, M = _resultant(m, d, kin, conns, group, point, loads, omega2)
            ma = sum(kin[b]["mass"] * kin[b]["a"] for b in group)
            h = sum(
                _cross(kin[b]["G"] - point, kin[b]["mass"] * kin[b]["a"]) + kin[b]["inertia"] * kin[b]["alpha"]
                for b in group
            )
            ef = np.max(np.hypot(*(F - ma).T)) / fscale
            em = np.max(np.abs(M - h)) / (fscale * size)
            assert ef < 1e-6, f"{m!r}: force balance of {sorted(group)} off by {ef:.2e} of the largest force"
            assert em < 1e-6, f"{m!r}: moment balance of {sorted(group)} off by {em:.2e} of force x size"


# ---- 3. the static limit -------------------------------------------------------------------------------------------
@pytest.mark.parametrize("kind", KINDS)
def test_static_limit_massless_links(kind):
    """Route: virtual work with no inertia. Massless links (the default ``Masses()``), a constant cutting force F
    (the four-bar: a follower torque): T = sign(omega2) F |dx/dtheta2| on the working stroke and exactly 0 on the
    return, with dx/dtheta2 = m.motion(...).v / omega2 and the working stroke from working_direction and the sign
    of v; both senses of rotation. Tolerance 1e-9 of F max|dx/dtheta2| (measured 6e-16: rounding only)."""
    for m in _designs(kind, 2, seed=9):
        for omega2 in (3.0, -2.0):
            F = 400.0
            loads = Loads(follower_torque=F) if kind == "four-bar" else Loads(cutting_force=F)
            d = m.dynamics(THETA, omega2, masses=Masses(), loads=loads)
            v = m.motion(THETA, omega2).v
            work = _working(m, omega2, v)
            assert work.any() and (~work).any()
            expected = np.where(work, math.copysign(1.0, omega2) * F * np.abs(v / omega2), 0.0)
            scale = F * np.max(np.abs(v / omega2))
            err = np.max(np.abs(d.torque - expected)) / scale
            assert err < 1e-9, f"{m!r} omega2={omega2}: static torque off by {err:.2e} of F max|x'|"
            assert np.all(d.torque[~work] == 0.0), f"{m!r}: torque on the return stroke with massless links"
            assert np.all(d.shaking_force == 0.0) and np.all(d.shaking_moment == 0.0)


@pytest.mark.parametrize("kind", SLIDER_KINDS)
def test_static_limit_cutting_force_table(kind):
    """Route: virtual work with a cutting-force table F(x) (linear in the ram's position x, the output joint's x):
    T = sign(omega2) F(x) |dx/dtheta2| on the working stroke, x and v from m.motion (the output's own position).
    Tolerance 1e-9 of max F |x'|."""
    for m in _designs(kind, 3, seed=9):
        mo = m.motion(THETA, 2.5)
        lo, hi = float(mo.x.min()), float(mo.x.max())
        table = ((lo - 0.1, 100.0), (0.5 * (lo + hi), 900.0), (hi + 0.1, 300.0))
        loads = Loads(cutting_force=table)
        d = m.dynamics(THETA, 2.5, masses=Masses(), loads=loads)
        work = _working(m, 2.5, mo.v)
        F = np.interp(mo.x, *np.array(table).T)
        expected = np.where(work, F * np.abs(mo.v / 2.5), 0.0)
        err = np.max(np.abs(d.torque - expected)) / np.max(np.abs(expected))
        assert err < 1e-9, (
            f"{m!r}: the cutting-force table is read at the wrong ram position (torque off by {err:.2e} of its "
            f"peak); qropt/dynamics/inverse.py _solve reads x at m.OUTPUT_JOINT={m.OUTPUT_JOINT!r}, the class "
            f"attribute, instead of m.output_joint()={m.output_joint()!r}"
        )


# ---- 4. shaking force and moment -----------------------------------------------------------------------------------
@pytest.mark.parametrize("kind", KINDS)
def test_shaking_is_minus_the_rate_of_momentum(kind):
    """Route: momentum. The shaking force is -d^2/dt^2 of the total first moment sum(m_i G_i) (one difference of the
    whole mechanism's centre of mass, no per-body acceleration); the shaking moment about O2 is -dH/dt with
    H = sum(m G x v_G + I w) = omega2 h(theta2), h from differences of the positions, dH/dt = omega2^2 h' +
    alpha2 h by a second difference of h. Tolerance 1e-6 of the peak (measured worst 1.4e-8 and 1.5e-8)."""
    for i, m in enumerate(_designs(kind)):
        masses, loads, omega2, alpha2 = _case(kind, i, m)
        props = m.body_masses(masses)
        d = m.dynamics(THETA, omega2, alpha2, masses=masses, loads=loads)

        def first_moment(t, m=m, props=props):
            poses = _poses(m, props, t)
            return sum(props[b].mass * poses[b][0] for b in props)

        s1, s2 = _diff([first_moment(THETA + o) for o in OFFSETS], H)
        force = -(omega2**2 * s2 + alpha2 * s1)
        ef = np.max(np.hypot(*(d.shaking_force - force).T)) / np.max(np.hypot(*force.T))
        assert ef < 1e-6, f"{m!r}: shaking force off by {ef:.2e} of its peak"

        def h(t, m=m, props=props):  # angular momentum about O2 (the origin) per unit omega2
            kin = _kinematics(m, props, t, 1.0, 0.0)
            return sum(k["mass"] * _cross(k["G"], k["v"]) + k["inertia"] * k["w"] for k in kin.values())

        h1, _ = _diff([h(THETA + o) for o in OFFSETS], H)
        moment = -(omega2**2 * h1 + alpha2 * h(THETA))
        em = np.max(np.abs(d.shaking_moment - moment)) / np.max(np.abs(moment))
        assert em < 1e-6, f"{m!r}: shaking moment off by {em:.2e} of its peak"


# ---- 5. symmetry and scaling ---------------------------------------------------------------------------------------
def test_mirrored_slider_crank():
    """Route: symmetry. The slider-crank with offset -e is the one with +e mirrored in y (y -> -y; checked on the
    positions first): at theta2 -> -theta2, omega2 -> -omega2, alpha2 -> -alpha2, with every mass mirrored (a centre
    (x, y) in a body frame -> (x, -y), the counterweight's angle negated) and the same cutting force (the ram moves
    the same way at the same times), T -> -T, every force (fx, fy) -> (fx, -fy), the shaking force likewise and the
    shaking moment -> -itself. No gravity (it is not mirrored). Tolerance 1e-10 of each peak (rounding only)."""
    a = qropt.SliderCrank(r2=0.2, r3=0.7, e=0.08)
    b = qropt.SliderCrank(r2=0.2, r3=0.7, e=-0.08)
    pa, pb = a.positions(THETA).points, b.positions(-THETA).points
    for j in pa:
        assert np.allclose(pa[j] * [1, -1], pb[j], atol=1e-13)

    def masses(sign):
        over = {"rod": BodyMass(1.7, (0.25, sign * 0.04), 0.02)}
        return Masses.bars(2.0, 3.0, bodies=over, counterweight=Counterweight(0.9, 0.1, sign * 2.5))

    loads = Loads(cutting_force=350.0)
    da = a.dynamics(THETA, 7.0, 4.0, masses=masses(1), loads=loads)
    db = b.dynamics(-THETA, -7.0, -4.0, masses=masses(-1), loads=loads)
    assert np.max(np.abs(db.torque + da.torque)) < 1e-10 * np.max(np.abs(da.torque))
    for j, f in da.joint_forces.items():
        assert np.max(np.abs(db.joint_forces[j] - f * [1, -1])) < 1e-10 * np.max(np.abs(f)), j
    assert np.max(np.abs(db.shaking_force - da.shaking_force * [1, -1])) < 1e-10 * np.max(np.abs(da.shaking_force))
    assert np.max(np.abs(db.shaking_moment + da.shaking_moment)) < 1e-10 * np.max(np.abs(da.shaking_moment))


def _scaled(m, s):
    kinds = m.kinds()
    p = {k: v * s if kinds[k] in ("length", "offset") else v for k, v in m.params.items()}
    return type(m)(**p)


@pytest.mark.parametrize("kind", KINDS)
def test_torque_scales_as_length_cubed_and_omega_squared(kind):
    """Route: dimensional analysis. No loads, density fixed (kg/m), ram (and block, counterweight) mass x s: every
    mass scales as s, inertia as s^3, acceleration as s omega2^2, so at a fixed shape (lengths and offsets x s,
    angles and branches kept) T x s^3 k^2 and the joint forces x s^2 k^2 at omega2 x k, alpha2 x k^2.
    Tolerance 1e-9 of the peak (rounding only)."""
    s, k = 2.5, 1.7
    for m in _designs(kind, 2, seed=13):
        big = _scaled(m, s)
        slotted = any(b.kind == "block" for b in m.bodies())

        def masses(f, m=m, slotted=slotted):
            cw = Counterweight(0.5 * f, 0.5 * m.params["r2"] * f, 2.0)
            return Masses.bars(3.0, 2.0 * f, block=0.4 * f if slotted else 0.0, counterweight=cw)

        d1 = m.dynamics(THETA, 4.0, 6.0, masses=masses(1.0))
        d2 = big.dynamics(THETA, 4.0 * k, 6.0 * k**2, masses=masses(s))
        ratio = s**3 * k**2
        assert np.max(np.abs(d2.torque - ratio * d1.torque)) < 1e-9 * ratio * np.max(np.abs(d1.torque)), repr(m)
        for j, f in d1.joint_forces.items():
            err = np.max(np.abs(d2.joint_forces[j] - s**2 * k**2 * f))
            assert err <= 1e-9 * s**2 * k**2 * np.max(np.abs(f)), (repr(m), j)
        if d1.guide_moment is not None:
            err = np.max(np.abs(d2.guide_moment - ratio * d1.guide_moment))
            assert err <= 1e-9 * ratio * np.max(np.abs(d1.guide_moment)), repr(m)


def test_millimetres_give_the_same_dynamics_as_metres():
    """Route: units. A slider-crank stated in mm (a cutting-force table in mm) gives the SI dynamics of the same
    mechanism stated in m (table in m): torque, forces and shaking equal to 1e-12 relative."""
    mm = qropt.SliderCrank(r2=150.0, r3=520.0, e=40.0, units="mm")
    m = qropt.SliderCrank(r2=0.15, r3=0.52, e=0.04)
    masses = Masses.bars(4.0, 6.0, counterweight=Counterweight(1.0, 0.08))
    table = ((200.0, 100.0), (500.0, 800.0), (700.0, 200.0))
    lm = Loads(cutting_force=tuple((x / 1000, f) for x, f in table), gravity=G0, friction=0.1)
    d_mm = mm.dynamics(THETA, 5.0, masses=masses, loads=Loads(cutting_force=table, gravity=G0, friction=0.1))
    d_m = m.dynamics(THETA, 5.0, masses=masses, loads=lm)
    assert np.allclose(d_mm.torque, d_m.torque, rtol=1e-12, atol=1e-12 * np.max(np.abs(d_m.torque)))
    for j in d_m.joint_forces:
        assert np.allclose(d_mm.joint_forces[j], d_m.joint_forces[j], rtol=1e-12, atol=1e-9), j
    assert np.allclose(d_mm.shaking_moment, d_m.shaking_moment, rtol=1e-12, atol=1e-9)


# ---- 6. a closed form ----------------------------------------------------------------------------------------------
def test_centred_slider_crank_closed_form():
    """Route: a hand derivation. Centred slider-crank (e = 0), massless crank r, uniform rod (mass m3, length L,
    I = m3 L^2 / 12), ram m4, constant omega2, no load. With s = sin th, c = cos th, D = sqrt(L^2 - r^2 s^2):
    x_C = r c + D, G = ((r c + x_C) / 2, r s / 2), the rod's angle phi = -asin(r s / L); kinetic energy
    M(th) omega2^2 / 2 with M = m4 x_C'^2 + m3 |G'|^2 + I phi'^2, so T = M'(th) omega2^2 / 2 =
    omega2^2 (m4 x_C' x_C'' + m3 G'.G'' + I phi' phi''), where (d/dth of q/D with q = s c: cos2th / D + r^2 q^2 / D^3)
    x_C' = -r s - r^2 q / D,  x_C'' = -r c - r^2 (cos2th / D + r^2 q^2 / D^3),
    G_x' = -r s - r^2 q / (2D), G_x'' = -r c - r^2 (cos2th / D + r^2 q^2 / D^3) / 2, G_y' = r c / 2, G_y'' = -r s / 2,
    phi' = -r c / D,  phi'' = r s / D - r^3 s c^2 / D^3.
    The derivation is first checked against differences of M; then qropt agrees to 1e-9 of the peak (measured
    5e-16) at 200 angles and two speeds."""
    r, L, m3, m4 = 0.12, 0.45, 2.2, 5.0
    mech = qropt.SliderCrank(r2=r, r3=L, e=0.0)
    th = np.linspace(0.0, TWO_PI, 201)[:-1] + 0.001
    s, c = np.sin(th), np.cos(th)
    D = np.sqrt(L**2 - r**2 * s**2)
    q, c2 = s * c, np.cos(2 * th)
    xc1 = -r * s - r**2 * q / D
    xc2 = -r * c - r**2 * (c2 / D + r**2 * q**2 / D**3)
    gx1 = -r * s - r**2 * q / (2 * D)
    gx2 = -r * c - r**2 * (c2 / D + r**2 * q**2 / D**3) / 2
    gy1, gy2 = r * c / 2, -r * s / 2
    p1 = -r * c / D
    p2 = r * s / D - r**3 * s * c**2 / D**3
    inertia = m3 * L**2 / 12
    dM_half = m4 * xc1 * xc2 + m3 * (gx1 * gx2 + gy1 * gy2) + inertia * p1 * p2

    def M(t):  # the generalised inertia from positions written out again, for the derivation's own check
        s_, c_ = np.sin(t), np.cos(t)
        D_ = np.sqrt(L**2 - r**2 * s_**2)
        xc_ = r * c_ + D_
        gx_, gy_ = (r * c_ + xc_) / 2, r * s_ / 2
        phi_ = -np.arcsin(r * s_ / L)
        return xc_, gx_, gy_, phi_

    samples = [M(th + o) for o in OFFSETS]
    d1 = [_diff([smp[i] for smp in samples], H)[0] for i in range(4)]
    Mfd = m4 * d1[0] ** 2 + m3 * (d1[1] ** 2 + d1[2] ** 2) + inertia * d1[3] ** 2
    Mcf = m4 * xc1**2 + m3 * (gx1**2 + gy1**2) + inertia * p1**2
    assert np.max(np.abs(Mfd - Mcf)) < 1e-9 * np.max(Mcf)  # the hand derivation's first derivatives
    Mp = [M(th + o)[0] for o in OFFSETS]  # and its second: x_C'' by differences
    assert np.max(np.abs(_diff(Mp, H)[1] - xc2)) < 1e-8 * np.max(np.abs(xc2))
    masses = Masses.bars(m3 / L, m4, bodies={"crank": BodyMass(0.0)})
    assert mech.positions(th).points["C"][:, 0] == pytest.approx(r * c + D, abs=1e-14)
    for omega2 in (10.0, -3.0):
        T = mech.dynamics(th, omega2, masses=masses).torque
        expected = omega2**2 * dM_half
        err = np.max(np.abs(T - expected)) / np.max(np.abs(expected))
        assert err < 1e-9, f"closed form: torque off by {err:.2e} of its peak at omega2={omega2}"


# ---- 7. the flywheel and the cycle extremes -------------------------------------------------------------------------
FLY_KINDS = ("slider-crank", "crank-shaper", "whitworth", "drag-link-slider", "coupler-slider", "slot-ram-shaper")


def _trapezoid_cycle(m, omega2, masses, loads, n=20_000):
    t = np.linspace(0.0, TWO_PI, n + 1)
    T = m.dynamics(t, omega2, masses=masses, loads=loads).torque
    step = TWO_PI / n
    mean = float(np.sum(T[:-1]) * step / TWO_PI)  # periodic trapezoid
    energy = np.concatenate([[0.0], np.cumsum((T[1:] + T[:-1] - 2 * mean) * step / 2)])
    return t, T, mean, energy


@pytest.mark.parametrize("kind", FLY_KINDS)
def test_flywheel_against_dense_trapezoid(kind):
    """Route: quadrature. Constant speed, a constant cutting force F, links with mass and gravity: the inertia
    and gravity terms integrate to zero over a turn, so energy_per_turn = F * stroke (both senses of rotation);
    energy_fluctuation = max - min of the running integral of T - T_mean by the trapezoid rule on 20,000 angles
    (relative 1e-5; the rule's O(h^2) error at the dead centres' kinks ~1e-7, measured worst 8e-8);
    inertia = dE / (cs omega2^2); working + return energy = energy per turn; with massless links the return
    stroke takes no energy and the working stroke F * stroke. dynamic_extremes: mean and RMS torque against the
    trapezoid (1e-6; measured 7e-9 and 2e-10), the peak |T| at least the dense grid's largest and within 1e-6 of it
    (measured 1.4e-7 above it), and the torque at the reported angle equal to the peak."""
    m = _designs(kind, 1, seed=21)[0]
    masses = Masses.bars(2.0, 4.0, counterweight=Counterweight(0.5, 0.5 * m.params["r2"]))
    F = 800.0
    loads = Loads(cutting_force=F, gravity=G0)
    stroke = m.stroke()
    for omega2, cs in ((8.0, 0.05), (-5.0, 0.2)):
        fw = m.flywheel(omega2, cs, masses=masses, loads=loads)
        t, T, mean, energy = _trapezoid_cycle(m, omega2, masses, loads)
        assert fw.energy_per_turn == pytest.approx(F * stroke, rel=1e-9)
        assert fw.mean_torque == pytest.approx(mean, rel=1e-6)
        dE = float(energy.max() - energy.min())
        assert fw.energy_fluctuation == pytest.approx(dE, rel=1e-5), f"{m!r}: energy fluctuation"
        assert fw.inertia == pytest.approx(dE / (cs * omega2**2), rel=1e-5)
        assert fw.working_energy + fw.return_energy == pytest.approx(fw.energy_per_turn, rel=1e-9)
        ex = m.dynamic_extremes(omega2, masses=masses, loads=loads)
        assert ex.mean_torque == pytest.approx(mean, rel=1e-6)
        assert ex.rms_torque == pytest.approx(math.sqrt(np.mean(T[:-1] ** 2)), rel=1e-6)
        i = int(np.argmax(np.abs(T)))
        assert np.abs(T[i]) * (1 - 1e-12) <= ex.peak_torque.value <= np.abs(T[i]) * (1 + 1e-6)
        at = m.dynamics([ex.peak_torque.theta2], omega2, masses=masses, loads=loads).torque[0]
        assert abs(at) == pytest.approx(ex.peak_torque.value, rel=1e-12)
    fw = m.flywheel(3.0, 0.1, loads=Loads(cutting_force=F))
    assert fw.working_energy == pytest.approx(F * stroke, rel=1e-9)
    assert abs(fw.return_energy) <= 1e-9 * F * stroke


@pytest.mark.parametrize("kind", FLY_KINDS)
def test_a_joint_force_that_jumps_at_a_dead_centre_peaks_there_on_the_working_side(kind):
    """Route: a dense grid. The cutting force switches on and off at the dead centres, so the joint forces jump
    there; the peak force at each joint is the supremum over the turn: the largest of a 200,001-angle grid and of
    the limits at both dead centres from inside the working stroke (the ram's inertia and the force together),
    found to 1e-9 and never below it. A large force on light links makes a dead centre the peak of some joint
    (not on the Whitworth, whose lever amplifies the force mid-stroke)."""
    from qropt.dynamics.cycle import CycleDynamics

    m = _designs(kind, 1, seed=21)[0]
    masses, loads = Masses.bars(0.5, 1.0), Loads(cutting_force=5000.0)
    t = np.linspace(0.0, TWO_PI, 200_001)
    d = m.dynamics(t, 7.0, masses=masses, loads=loads)
    dc = m.dead_centres()
    ends = CycleDynamics(m, 7.0, masses=masses, loads=loads).at([dc.theta_max, dc.theta_min], True)
    ex = m.dynamic_extremes(7.0, masses=masses, loads=loads)
    at_ends = 0
    for j, f in d.joint_forces.items():
        grid, limit = np.hypot(*f.T).max(), np.hypot(*ends.joint_forces[j].T).max()
        best = max(grid, limit)
        at_ends += limit >= grid
        assert best * (1 - 1e-12) <= ex.peak_forces[j].value <= best * (1 + 1e-9), f"{m!r}: the peak force at {j}"
    if kind != "whitworth":  # its lever amplifies the force mid-stroke: there every peak is inside the stroke
        assert at_ends >= 1, f"{m!r}: no joint force peaks at a dead centre: the test checks nothing of the jump"


@pytest.mark.parametrize("kind", KINDS)
def test_the_force_analysis_eliminates_by_the_structure(kind):
    """Route: LAPACK. The Newton-Euler system of every type is eliminated in one order fixed by its structure
    (constant pivots, then single unknowns, then 2x2 blocks: none that vanishes off a singular position); its
    solution equals numpy's dense solve with partial pivoting at every angle, to 1e-10 of the largest unknown."""
    from qropt.dynamics.inverse import Elimination, _kinetics, pivots, system_of

    for i, m in enumerate(_designs(kind)):
        masses, loads, omega2, alpha2 = _case(kind, i, m)
        s = system_of(m, masses)
        P, kin, _ = _kinetics(m, s, THETA, omega2, alpha2, 1.0)
        entries, rhs = s.assemble(P, kin, G0, np.sqrt)
        steps = pivots(entries, s.n)
        assert steps is not None and all(len(r) == len(c) <= 2 for r, c in steps), f"{m!r}: {steps}"
        e = Elimination(entries, s.n, THETA.size)
        got = np.array(e.solve(rhs))
        want = e._lapack(rhs, np.ones(THETA.size, bool)).T
        assert np.max(np.abs(got - want)) <= 1e-10 * np.max(np.abs(want)), f"{m!r}"


# ---- 8. bad input --------------------------------------------------------------------------------------------------
def test_bad_input_is_a_typed_error_naming_the_problem():
    """Route: the error contract. Each bad input raises qropt.InvalidParameter (a QroptError) whose message names
    the offending quantity."""
    m = qropt.SliderCrank(r2=0.1, r3=0.4, e=0.02)
    th = np.linspace(0.0, 6.0, 5)
    cases = [
        (lambda: Masses.bars(-1.0), "density"),
        (lambda: Masses.bars(1.0, -2.0), "ram"),
        (lambda: Masses.bars(1.0, block=-0.1), "block"),
        (lambda: BodyMass(-1.0), "mass"),
        (lambda: Counterweight(1.0, -0.1), "radius"),
        (lambda: Loads(cutting_force=-5.0), "cutting_force"),
        (lambda: Loads(gravity=float("nan")), "gravity"),
        (lambda: m.dynamics(th, 2.0, masses=Masses.bars(1.0, bodies={"lever": BodyMass(1.0)})), "lever"),
        (lambda: m.dynamics(th, 2.0, masses={"density": 1.0}), "Masses"),
        (lambda: m.dynamics(th, 2.0, loads={"cutting_force": 1.0}), "Loads"),
        (lambda: m.dynamics(th, 0.0, loads=Loads(cutting_force=100.0)), "omega2"),
        (lambda: m.dynamics(th, 0.0, loads=Loads(cutting_force=((0.0, 0.0), (1.0, 5.0)))), "omega2"),
        (lambda: m.flywheel(5.0, 0.0), "cs"),
        (lambda: m.flywheel(5.0, 2.0), "cs"),
        (lambda: m.flywheel(5.0, -0.1), "cs"),
        (lambda: m.flywheel(5.0, True), "cs"),
        (lambda: m.flywheel(0.0, 0.1), "omega2"),
        (lambda: m.body_masses(Masses.bars(1.0, bodies={"ram ": BodyMass(1.0)})), "ram "),
    ]
    for call, word in cases:
        with pytest.raises(qropt.InvalidParameter, match=None) as e:
            call()
        assert isinstance(e.value, qropt.QroptError)
        assert word.lower() in str(e.value).lower(), f"message {str(e.value)!r} does not name {word!r}"


def test_cycle_routes_refuse_a_load_at_zero_speed():
    """Route: the error contract, as m.dynamics: a cutting force resists the motion, so it needs omega2 != 0; the
    cycle quantities must refuse it too rather than drop the load."""
    m = qropt.SliderCrank(r2=0.1, r3=0.4, e=0.02)
    try:
        ex = m.dynamic_extremes(0.0, loads=Loads(cutting_force=100.0))
    except qropt.InvalidParameter as e:
        assert "omega2" in str(e)
    else:
        pytest.fail(
            "m.dynamic_extremes(0.0, loads=Loads(cutting_force=100.0)) returned (peak torque "
            f"{ex.peak_torque.value:g} N m: the cutting force silently dropped) where m.dynamics raises "
            "InvalidParameter; qropt/dynamics/cycle.py CycleDynamics.__init__ lacks inverse_dynamics' omega2 == 0 check"
        )


# ---- friction on the slide -----------------------------------------------------------------------------------------
@pytest.mark.parametrize("kind", SLIDER_KINDS)
def test_the_slides_friction_is_coulombs_law_at_every_angle(kind):
    """Route: the friction law itself. With mu = 0.3 the force the guide puts on the ram along the slide is
    -mu |N| sign(v) at every crank angle (v the ram's velocity from differences of its exact positions), and the
    bodies are in equilibrium with it (``test_newton_euler_body_by_body`` checks that with friction)."""
    mu = 0.3
    for i, m in enumerate(_designs(kind, 2, seed=9)):
        masses, loads, omega2, alpha2 = _case(kind, i, m)
        loads = Loads(cutting_force=loads.cutting_force, gravity=G0, friction=mu)
        d = m.dynamics(THETA, omega2, alpha2, masses=masses, loads=loads)
        kin = _kinematics(m, m.body_masses(masses), THETA, omega2, alpha2)
        v = kin[_output_body(m).name]["v"][:, 0]
        friction, normal = d.joint_forces["slide"].T
        assert np.abs(normal).max() > 1.0  # the law is not met trivially
        assert friction == pytest.approx(-mu * np.abs(normal) * np.sign(v), rel=1e-12, abs=1e-9)


def test_a_slide_that_friction_locks_is_an_error_naming_the_angle():
    """Route: statics of the massless slider-crank. Its rod holds the ram: a force F along the slide needs the
    guide's N = F tan(phi), phi the rod's angle to the slide, so friction mu locks the slide where mu tan(phi) >= 1.
    A mu 1 % above 1 / max tan(phi) (from the exact positions on a 200,001-angle grid) raises DegenerateMechanism
    naming friction and an angle where tan(phi) is within 2 % of its largest; 1 % below does not."""
    m = qropt.SliderCrank(r2=0.1, r3=0.16, e=0.05)
    t = np.linspace(0.0, TWO_PI, 200_001)
    p = m.positions(t).points
    rod = p["C"] - p["A"]
    tan = np.abs(rod[:, 1] / rod[:, 0])
    limit = 1.0 / tan.max()
    loads = Loads(cutting_force=500.0, friction=1.01 * limit)
    with pytest.raises(qropt.DegenerateMechanism, match="friction") as e:
        m.dynamics(t[::100], 10.0, loads=loads)
    deg = float(str(e.value).split("crank angle ")[1].split(" deg")[0])
    assert e.value.theta2 == pytest.approx(np.radians(deg), abs=1e-5)  # SlideLocked: the angle, for a sample
    k = np.argmin(np.abs(t - e.value.theta2))
    assert tan[k] >= 0.98 * tan.max()
    d = m.dynamics(t[::100], 10.0, loads=Loads(cutting_force=500.0, friction=0.99 * limit))
    assert np.isfinite(d.torque).all()


# a crank-rocker slider at TR 1.542, 0.0646 m whose toggle (gamma_min 0.1 deg) sits at its dead centre: a
# Nelder-Mead descent on the peak torque once ended here, where the grid's maxima hid a spike
_SPIKY = {
    "r1": 0.02570553540249558,
    "r2": 0.009867777577398127,
    "r3": 0.0238444345693509,
    "r4": 0.031420787954489736,
    "r5": 0.051245044595973954,
    "r6": 0.03621979501504334,
    "h": 0.058631794689428605,
}


def test_a_torque_spike_narrower_than_the_grid_step_is_the_peak():
    """Near a toggle the torque spikes over less than the 720-angle grid's step: at this design the grid's
    samples read at most 19.54 N m, the torque peaks at 78.74 N m 0.1 deg past the dead centre; the exact peak is
    the largest of 2,000,001 angles (and not below it), found by the sub-grid at the toggle's crank angle."""
    from benchmarks.tasks import LOADS, MASSES
    from qropt.dynamics.cycle import GRID, CycleDynamics
    from qropt.studies._design import type_problem

    p = type_problem("crank-rocker-slider", 1.542, 0.0646, objective="min_peak_torque", masses=MASSES, loads=LOADS)
    m = p.build(_SPIKY, {k: b[0] for k, b in p.branches.items()})
    assert math.degrees(m.gamma_min().value) < 0.2
    cd = CycleDynamics(m, 10.0, masses=MASSES, loads=LOADS)
    peak = cd.peak(lambda d: np.abs(d.torque))
    dense = np.abs(cd.at(np.linspace(0.0, 2 * np.pi, 2_000_001)).torque).max()
    grid = np.abs(cd.at(np.linspace(0.0, 2 * np.pi, GRID, endpoint=False)).torque).max()
    assert grid < 0.3 * dense
    assert peak.value >= dense * (1 - 1e-12) and peak.value == pytest.approx(dense, rel=1e-7)  # a sharp top
    assert m.dynamic_extremes(10.0, masses=MASSES, loads=LOADS).peak_torque.value == peak.value
