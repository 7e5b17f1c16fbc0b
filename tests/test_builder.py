"""The linkage builder (qropt.mechanisms.builder) re-declares every shipped loop from Assur groups and reproduces the
hand-written loops the types had before they were declared with it (kept below as plain functions, the independent
reference): points, angles, x, transmission (cosines), margins and bodies to 1e-12 on numpy arrays, x and its first
two derivatives on Taylor jets, the same numbers through a compiled CasADi Function, and the same time ratio, stroke
and gamma_min through a Mechanism subclass whose loop is the hand-written one."""

from __future__ import annotations

import math

import casadi
import numpy as np
import pytest

import qropt
from qropt.kinematics.closures import (
    RIGHT_ANGLE,
    joint_lines,
    on_ray,
    pin_in_slot,
    rod_lines,
    rod_to_line,
    slot_line_lines,
    slot_to_line,
    transmission_cos,
)
from qropt.kinematics.ops import CASADI, JET, NUMPY, Jet
from qropt.mechanisms import Body, Loop
from qropt.mechanisms.builder import Linkage, LinkageError
from qropt.mechanisms.four_bar import four_bar as four_bar_closure  # the four-bar the hand-written loops used
from tests import randmech
from tests.test_sixbars import _coupler_designs, _slot_ram_designs

TOL = 1e-12
THETA = np.linspace(0.0, 2 * math.pi, 181)  # crank angles of the comparisons (rad), both ends included
N_DESIGNS = 12  # random valid designs per loop


# ---- the reference: the hand-written loops, bodies, frames and outputs the types had before the builder ------------
def ref_slider_crank(xp, theta2, p):
    a = (p["r2"] * xp.cos(theta2), p["r2"] * xp.sin(theta2))
    c, m = rod_to_line(xp, a, p["r3"], p["e"], p["sigma_slider"])
    return Loop(
        points={"O2": (0.0, 0.0), "A": a, "C": c},
        angles={"theta2": theta2, "theta3": xp.atan2(c[1] - a[1], c[0] - a[0])},
        x=c[0],
        transmission={"C": rod_lines(a, c)},
        margins=[("rod AC reaching the slide line", m)],
    )


def ref_crank_shaper(xp, theta2, p):
    o4 = (0.0, -p["r1"])
    a = (p["r2"] * xp.cos(theta2), p["r2"] * xp.sin(theta2))
    theta4 = pin_in_slot(xp, o4, a)
    c = on_ray(xp, o4, theta4, p["r4"])
    points = {"O2": (0.0, 0.0), "A": a, "O4": o4, "C": c}
    angles = {"theta2": theta2, "theta4": theta4}
    if "r6" not in p:
        return Loop(points, angles, c[0], {"A": RIGHT_ANGLE, "C": RIGHT_ANGLE}, [])
    d, m = rod_to_line(xp, c, p["r6"], -p["r1"] + p["h"], p["sigma_slider"])
    points["D"] = d
    angles["theta6"] = xp.atan2(d[1] - c[1], d[0] - c[0])
    trans = {"A": RIGHT_ANGLE, "D": rod_lines(c, d)}
    return Loop(points, angles, d[0], trans, [("rod CD reaching the slide line", m)])


def ref_whitworth(xp, theta2, p):
    o4 = (0.0, -p["r1"])
    a = (p["r2"] * xp.cos(theta2), p["r2"] * xp.sin(theta2))
    theta4 = pin_in_slot(xp, o4, a)
    c = on_ray(xp, o4, theta4, p["r5"])
    d, m = rod_to_line(xp, c, p["r6"], -p["r1"] + p["h"], p["sigma_slider"])
    return Loop(
        points={"O2": (0.0, 0.0), "A": a, "O4": o4, "C": c, "D": d},
        angles={"theta2": theta2, "theta4": theta4, "theta6": xp.atan2(d[1] - c[1], d[0] - c[0])},
        x=d[0],
        transmission={"A": RIGHT_ANGLE, "D": rod_lines(c, d)},
        margins=[("rod CD reaching the slide line", m)],
    )


def ref_four_bar(xp, theta2, p):
    a, o4, b, theta3, theta4, m = four_bar_closure(xp, theta2, p)
    return Loop(
        points={"O2": (0.0, 0.0), "A": a, "B": b, "O4": o4},
        angles={"theta2": theta2, "theta3": theta3, "theta4": theta4},
        x=theta4,
        transmission={"B": joint_lines(a, o4, b)},
        margins=[("four-bar closure at B", m)],
    )


def _ref_rod_after_four_bar(xp, theta2, p, pin_name, pin_of):
    """The four-bar, then a rod from the pin ``pin_of(a, o4, theta3, theta4)`` (named pin_name) to the ram D."""
    a, o4, b, theta3, theta4, m4 = four_bar_closure(xp, theta2, p)
    pin = pin_of(a, o4, theta3, theta4)
    d, m6 = rod_to_line(xp, pin, p["r6"], p["h"], p["sigma_slider"])
    return Loop(
        points={"O2": (0.0, 0.0), "A": a, "B": b, "O4": o4, pin_name: pin, "D": d},
        angles={
            "theta2": theta2,
            "theta3": theta3,
            "theta4": theta4,
            "theta6": xp.atan2(d[1] - pin[1], d[0] - pin[0]),
        },
        x=d[0],
        transmission={"B": joint_lines(a, o4, b), "D": rod_lines(pin, d)},
        margins=[("four-bar closure at B", m4), (f"rod {pin_name}D reaching the slide line", m6)],
    )


def ref_four_bar_slider(xp, theta2, p):
    return _ref_rod_after_four_bar(xp, theta2, p, "C", lambda a, o4, t3, t4: on_ray(xp, o4, t4, p["r5"]))


def ref_coupler_slider(xp, theta2, p):
    def coupler_point(a, o4, t3, t4):
        return (a[0] + p["r5"] * xp.cos(t3 + p["beta"]), a[1] + p["r5"] * xp.sin(t3 + p["beta"]))

    return _ref_rod_after_four_bar(xp, theta2, p, "P", coupler_point)


def ref_slot_ram_shaper(xp, theta2, p):
    o4 = (0.0, -p["r1"])
    a = (p["r2"] * xp.cos(theta2), p["r2"] * xp.sin(theta2))
    theta4 = pin_in_slot(xp, o4, a)
    d, _ = slot_to_line(xp, o4, a, -p["r1"] + p["h"])  # on the ray (t > 0) wherever the rules hold
    return Loop(
        points={"O2": (0.0, 0.0), "A": a, "O4": o4, "D": d},
        angles={"theta2": theta2, "theta4": theta4},
        x=d[0],
        transmission={"A": RIGHT_ANGLE, "D": slot_line_lines(o4, a)},
        margins=[],
    )


_CRANK, _BLOCK = Body("crank", ("O2", "A"), "bar"), Body("block", ("A", "O4"), "block")
_COUPLER, _FOLLOWER = Body("coupler", ("A", "B"), "bar"), Body("follower", ("O4", "B"), "bar")
# case -> (loop, bodies, ground, output joint), as the hand-written types declared them
REF = {
    "slider-crank": (
        ref_slider_crank,
        (_CRANK, Body("rod", ("A", "C"), "bar"), Body("ram", ("C",), "ram")),
        ("O2",),
        "C",
    ),
    "crank-shaper-yoke": (
        ref_crank_shaper,
        (_CRANK, _BLOCK, Body("lever", ("O4", "A", "C"), "slot-lever"), Body("yoke", ("C",), "yoke")),
        ("O2", "O4"),
        "C",
    ),
    "crank-shaper-rod": (
        ref_crank_shaper,
        (
            _CRANK,
            _BLOCK,
            Body("lever", ("O4", "A", "C"), "slot-lever"),
            Body("rod", ("C", "D"), "bar"),
            Body("ram", ("D",), "ram"),
        ),
        ("O2", "O4"),
        "D",
    ),
    "whitworth": (
        ref_whitworth,
        (
            _CRANK,
            _BLOCK,
            Body("lever", ("O4", "A", "C"), "slot-lever"),
            Body("rod", ("C", "D"), "bar"),
            Body("ram", ("D",), "ram"),
        ),
        ("O2", "O4"),
        "D",
    ),
    "four-bar": (ref_four_bar, (_CRANK, _COUPLER, _FOLLOWER), ("O2", "O4"), None),
    "four-bar-slider": (
        ref_four_bar_slider,
        (
            _CRANK,
            _COUPLER,
            Body("follower", ("O4", "B", "C"), "bar"),
            Body("rod", ("C", "D"), "bar"),
            Body("ram", ("D",), "ram"),
        ),
        ("O2", "O4"),
        "D",
    ),
    "coupler-slider": (
        ref_coupler_slider,
        (
            _CRANK,
            Body("coupler", ("A", "B", "P"), "plate"),
            _FOLLOWER,
            Body("rod", ("P", "D"), "bar"),
            Body("ram", ("D",), "ram"),
        ),
        ("O2", "O4"),
        "D",
    ),
    "slot-ram-shaper": (
        ref_slot_ram_shaper,
        (_CRANK, _BLOCK, Body("lever", ("O4", "A", "D"), "slot-lever"), Body("ram", ("D",), "ram")),
        ("O2", "O4"),
        "D",
    ),
}
REF["crank-rocker-slider"] = REF["drag-link-slider"] = REF["four-bar-slider"]


# ---- the eight shipped loops, declared with the builder -----------------------------------------------------------
def slider_crank() -> Linkage:
    L = Linkage()
    L.ground("O2", (0, 0))
    L.crank("A", about="O2", length="r2")
    L.rrp("C", ("A", "r3"), line_y="e", sign="sigma_slider")
    return L.output("C")


def _shaper_lever(lever: str) -> Linkage:
    L = Linkage()
    L.ground("O2", (0, 0))
    L.crank("A", about="O2", length="r2")
    L.ground("O4", (0, "-r1"))
    L.rpr("A", pivot="O4", angle="theta4")  # the crank-pin block in the lever's slot
    L.on_ray("C", "O4", "A", lever)
    return L


def crank_shaper_yoke() -> Linkage:
    L = _shaper_lever("r4")
    L.rpp("C")
    return L.output("C")


def crank_shaper_rod() -> Linkage:
    L = _shaper_lever("r4")
    L.rrp("D", ("C", "r6"), line_y="-r1 + h", sign="sigma_slider")
    return L.output("D")


def whitworth() -> Linkage:
    L = _shaper_lever("r5")
    L.rrp("D", ("C", "r6"), line_y="-r1 + h", sign="sigma_slider")
    return L.output("D")


def _four_bar() -> Linkage:
    L = Linkage()
    L.ground("O2", (0, 0))
    L.crank("A", about="O2", length="r2")
    L.rrr("B", ("A", "r3"), ("O4", "r4"), sign="sigma", around=math.pi)
    L.ground("O4", ("r1", 0))  # after B: the hand-written four-bar lists O2, A, B, O4
    return L


def four_bar() -> Linkage:
    return _four_bar().output("theta4")


def four_bar_slider() -> Linkage:
    L = _four_bar()
    L.on_ray("C", "O4", "B", "r5")
    L.rrp("D", ("C", "r6"), line_y="h", sign="sigma_slider")
    return L.output("D")


def coupler_slider() -> Linkage:
    L = _four_bar()
    L.coupler_point("P", "A", "B", "r5", angle="beta")
    L.rrp("D", ("P", "r6"), line_y="h", sign="sigma_slider")
    return L.output("D")


def slot_ram_shaper() -> Linkage:
    L = Linkage()
    L.ground("O2", (0, 0))
    L.crank("A", about="O2", length="r2")
    L.ground("O4", (0, "-r1"))
    L.rpr("A", pivot="O4", angle="theta4")
    L.slot_line("D", ("O4", "A"), line_y="-r1 + h")
    return L.output("D")


SHAPER_YOKE, SHAPER_ROD = crank_shaper_yoke(), crank_shaper_rod()


def _draws(kind, n, seed):
    """n valid designs of a kind through the type's own constructor (randmech's draws; six-bars: test_sixbars)."""
    if kind == "coupler-slider":
        return [m for _, m in _coupler_designs(n, seed)]
    if kind == "slot-ram-shaper":
        return [m for _, m in _slot_ram_designs(n, seed)]
    rng, cls, out = np.random.default_rng(seed), qropt.mechanism_type(kind), []
    while len(out) < n:
        try:
            out.append(cls(**randmech._draw(kind, rng)))
        except qropt.QroptError:
            continue
    return out


# (case, type, linkage, design filter): the crank-shaper twice, the four-bar sliders' shared loop twice
CASES = [
    ("slider-crank", qropt.SliderCrank, slider_crank(), None),
    ("crank-shaper-yoke", qropt.CrankShaper, SHAPER_YOKE, lambda m: "r6" not in m.params),
    ("crank-shaper-rod", qropt.CrankShaper, SHAPER_ROD, lambda m: "r6" in m.params),
    ("whitworth", qropt.Whitworth, whitworth(), None),
    ("four-bar", qropt.FourBar, four_bar(), None),
    ("crank-rocker-slider", qropt.CrankRockerSlider, four_bar_slider(), None),
    ("drag-link-slider", qropt.DragLinkSlider, four_bar_slider(), None),
    ("coupler-slider", qropt.CouplerSlider, coupler_slider(), None),
    ("slot-ram-shaper", qropt.SlotRamShaper, slot_ram_shaper(), None),
]
IDS = [c[0] for c in CASES]


def _designs(cls, keep, n=N_DESIGNS, seed=7):
    out, s = [], seed
    while len(out) < n:
        out += [m for m in _draws(cls.KIND, n, s) if keep is None or keep(m)]
        s += 1000
    return out[:n]


def _close(a, b, what):
    a, b = np.broadcast_arrays(np.asarray(a, float), np.asarray(b, float))
    assert a.shape == b.shape, what
    np.testing.assert_allclose(a, b, rtol=0.0, atol=TOL, err_msg=what)


def _compare(ref, got, t, where=""):
    """Two Loops agree: names and order, points, angles, x, transmission lines and cosines, margins (numpy)."""
    assert list(got.points) == list(ref.points), where
    assert list(got.angles) == list(ref.angles), where
    assert list(got.transmission) == list(ref.transmission), where
    assert [k for k, _ in got.margins] == [k for k, _ in ref.margins], where
    shape = np.shape(t)
    for k in ref.points:
        for i in (0, 1):
            _close(np.broadcast_to(got.points[k][i], shape), np.broadcast_to(ref.points[k][i], shape), f"{where} {k}")
    for k in ref.angles:
        _close(np.broadcast_to(got.angles[k], shape), np.broadcast_to(ref.angles[k], shape), f"{where} {k}")
    _close(np.broadcast_to(got.x, shape), np.broadcast_to(ref.x, shape), f"{where} x")
    for k, lines in ref.transmission.items():
        assert (got.transmission[k] is RIGHT_ANGLE) == (lines is RIGHT_ANGLE), f"{where} {k}"
        c_ref, c_got = transmission_cos(NUMPY, lines), transmission_cos(NUMPY, got.transmission[k])
        _close(np.broadcast_to(c_got, shape), np.broadcast_to(c_ref, shape), f"{where} cos at {k}")
    for (k, m_ref), (_, m_got) in zip(ref.margins, got.margins, strict=True):
        _close(np.broadcast_to(m_got, shape), np.broadcast_to(m_ref, shape), f"{where} margin {k}")


@pytest.mark.parametrize(("case", "cls", "L", "keep"), CASES, ids=IDS)
def test_numpy_loop_equals_the_hand_written_one(case, cls, L, keep):
    for m in _designs(cls, keep):
        p = dict(m.params)
        with np.errstate(invalid="ignore", divide="ignore"):
            _compare(REF[case][0](NUMPY, THETA, p), L.loop(NUMPY, THETA, p), THETA, f"{case} {m!r}")
            # a scalar crank angle too (the NLP and the API pass numbers)
            _compare(REF[case][0](NUMPY, 1.234, p), L.loop(NUMPY, 1.234, p), 1.234, f"{case} {m!r} scalar")


@pytest.mark.parametrize(("case", "cls", "L", "keep"), CASES, ids=IDS)
def test_vectorised_over_parameters_as_the_kernel_calls_it(case, cls, L, keep):
    """Kernel.grid_many evaluates theta (n, 1) against parameter rows (1, K): the builder broadcasts alike."""
    ms = _designs(cls, keep, n=6, seed=11)
    names = list(ms[0].params)
    ms = [m for m in ms if list(m.params) == names]
    P = np.array([[m.params[k] for k in names] for m in ms])
    p = {k: P[:, i][None, :] for i, k in enumerate(names)}
    theta = THETA[:, None]
    with np.errstate(invalid="ignore", divide="ignore"):
        ref, got = REF[case][0](NUMPY, theta, p), L.loop(NUMPY, theta, p)
    shape = (theta.size, P.shape[0])
    _close(np.broadcast_to(got.x, shape), np.broadcast_to(ref.x, shape), case)
    for (k, a), (_, b) in zip(ref.margins, got.margins, strict=True):
        _close(np.broadcast_to(b, shape), np.broadcast_to(a, shape), f"{case} {k}")


@pytest.mark.parametrize(("case", "cls", "L", "keep"), CASES, ids=IDS)
def test_jet_loop_equals_the_hand_written_one(case, cls, L, keep):
    for m in _designs(cls, keep, seed=21):
        p = dict(m.params)
        with np.errstate(invalid="ignore", divide="ignore"):
            ref = REF[case][0](JET, Jet.seed(THETA, 2.5, -0.7), p)
            got = L.loop(JET, Jet.seed(THETA, 2.5, -0.7), p)
        assert isinstance(got.x, Jet)
        for part in ("v", "d1", "d2"):
            _close(getattr(got.x, part), getattr(ref.x, part), f"{case} {m!r} x.{part}")
        for k in ref.angles:  # every link's angle, rate and acceleration (Mechanism.motion reads them)
            a, b = ref.angles[k], got.angles[k]
            for part in ("v", "d1", "d2"):
                _close(getattr(b, part), getattr(a, part), f"{case} {m!r} {k}.{part}")


def _flat(lp):
    """Every number of a loop in a fixed order: points, angles, x, transmission cosines, margins."""
    out = [c for pt in lp.points.values() for c in pt] + list(lp.angles.values()) + [lp.x]
    out += [transmission_cos(CASADI if _symbolic(lp) else NUMPY, v) for v in lp.transmission.values()]
    return out + [m for _, m in lp.margins]


def _symbolic(lp):
    return isinstance(lp.x, casadi.SX)


@pytest.mark.parametrize(("case", "cls", "L", "keep"), CASES, ids=IDS)
def test_casadi_loop_builds_and_evaluates_to_the_same_numbers(case, cls, L, keep):
    ms = _designs(cls, keep, n=4, seed=31)
    names = tuple(ms[0].params)
    t, P = casadi.SX.sym("t"), casadi.SX.sym("p", len(names))
    lp = L.loop(CASADI, t, {k: P[i] for i, k in enumerate(names)})
    assert _symbolic(lp)
    f = casadi.Function("builder", [t, P], [casadi.vertcat(*[casadi.SX(v) + 0 * t for v in _flat(lp)])])
    fm = f.map(THETA.size)
    for m in ms:
        if tuple(m.params) != names:
            continue
        p = dict(m.params)
        vec = np.array([p[k] for k in names])
        got = np.array(fm(THETA[None, :], np.repeat(vec[:, None], THETA.size, axis=1)))
        with np.errstate(invalid="ignore", divide="ignore"):
            ref = REF[case][0](NUMPY, THETA, p)
        want = np.array([np.broadcast_to(np.asarray(v, float), THETA.shape) for v in _flat(ref)])
        _close(got, want, f"{case} {m!r} casadi")


# ---- a Mechanism whose loop is the hand-written one, against the shipped type (whose loop is the builder's) --------
def _hand_written_type(cls, loop, case):
    return type(f"HandWritten_{case.replace('-', '_')}", (cls,), {"loop": staticmethod(loop)})


HAND_WRITTEN = [
    ("slider-crank", qropt.SliderCrank, ref_slider_crank),
    ("crank-shaper", qropt.CrankShaper, ref_crank_shaper),
    ("whitworth", qropt.Whitworth, ref_whitworth),
    ("four-bar", qropt.FourBar, ref_four_bar),
    ("crank-rocker-slider", qropt.CrankRockerSlider, ref_four_bar_slider),
    ("drag-link-slider", qropt.DragLinkSlider, ref_four_bar_slider),
    ("coupler-slider", qropt.CouplerSlider, ref_coupler_slider),
    ("slot-ram-shaper", qropt.SlotRamShaper, ref_slot_ram_shaper),
]


def _valid_qr(kind, n, seed):
    if kind in ("coupler-slider", "slot-ram-shaper"):
        return _draws(kind, n, seed)
    return [m for _, m in randmech.random_mechanisms(kind, n, seed=seed)]


@pytest.mark.parametrize(("case", "cls", "loop"), HAND_WRITTEN, ids=[b[0] for b in HAND_WRITTEN])
def test_a_type_with_the_hand_written_loop_has_the_same_cycle_quantities(case, cls, loop):
    built = _hand_written_type(cls, loop, case)
    assert built.KIND == cls.KIND and built.__dict__.get("KIND") is None  # not registered: no KIND of its own
    assert cls.loop is not loop  # the shipped type runs the builder's loop
    n = 6 if case == "crank-shaper" else 3  # the crank-shaper: both variants among them
    designs = _valid_qr(cls.KIND, n, seed=5)
    if case == "crank-shaper":
        assert {"r6" in m.params for m in designs} == {True, False}
    for m in designs:
        b = built(**m.params)
        for q in ("time_ratio", "stroke"):
            assert abs(getattr(b, q)() - getattr(m, q)()) <= TOL, (case, m, q)
        g, h = b.gamma_min(), m.gamma_min()
        assert abs(g.value - h.value) <= TOL and g.joint == h.joint, (case, m)


# ---- bodies, frame and output as the types declare them -----------------------------------------------------------
BODIES = [
    ("slider-crank", slider_crank(), qropt.SliderCrank(r2=1.0, r3=3.0)),
    ("crank-shaper-yoke", SHAPER_YOKE, qropt.CrankShaper(r1=1.0, r2=0.5, r4=2.0)),
    ("crank-shaper-rod", SHAPER_ROD, qropt.CrankShaper(r1=1.0, r2=0.5, r4=2.0, r6=1.5, h=1.8)),
    ("whitworth", whitworth(), qropt.Whitworth(r1=0.5, r2=1.0, r5=1.0, r6=2.0)),
    ("four-bar", four_bar(), qropt.FourBar(r1=3.0, r2=1.0, r3=3.5, r4=3.0)),
    ("crank-rocker-slider", four_bar_slider(), qropt.CrankRockerSlider(r1=3.0, r2=1.0, r3=3.5, r4=3.0, r5=4.0, r6=5.0)),
    ("drag-link-slider", four_bar_slider(), qropt.DragLinkSlider(r1=1.0, r2=2.0, r3=3.0, r4=3.0, r5=4.0, r6=6.0)),
    ("coupler-slider", coupler_slider(), _draws("coupler-slider", 1, 3)[0]),
    ("slot-ram-shaper", slot_ram_shaper(), qropt.SlotRamShaper(r1=1.0, r2=0.5, h=1.0)),
]


@pytest.mark.parametrize(("case", "L", "m"), BODIES, ids=[b[0] for b in BODIES])
def test_bodies_ground_and_output_joint_match_the_type(case, L, m):
    _, bodies, ground, output_joint = REF[case]  # as the hand-written types declared them
    assert L.bodies() == bodies == m.bodies()
    assert L.ground_joints() == ground == m.GROUND
    assert L.output_joint() == output_joint == m.output_joint()
    assert set(L.parameters()) <= set(m.params)


def test_parameters_in_first_use_order():
    assert coupler_slider().parameters() == ("r2", "r3", "r4", "sigma", "r1", "r5", "beta", "r6", "h", "sigma_slider")
    assert SHAPER_ROD.parameters() == ("r2", "r1", "r4", "r6", "h", "sigma_slider")


# ---- a linkage of one's own and the declaration errors ------------------------------------------------------------
def test_a_new_linkage_in_a_few_lines_runs_on_every_namespace():
    """A crank-rocker whose coupler point drives a second rocker (an RRR not on the crank): it needs no loop."""
    L = Linkage()
    L.ground("O2", (0, 0))
    L.ground("O4", ("r1", 0))
    L.ground("O6", ("r1", "2*r1 - e"))
    L.crank("A", about="O2", length="r2")
    L.rrr("B", ("A", "r3"), ("O4", "r4"), sign="sigma", around=math.pi)
    L.coupler_point("P", "A", "B", "r5", angle="beta")
    L.rrr("E", ("P", "r6"), ("O6", "r7"), sign=1, bodies=("link6", "rocker"), angles=("theta6", "theta7"))
    L.output("theta7")
    p = {"r1": 3.0, "r2": 1.0, "r3": 3.5, "r4": 3.0, "r5": 1.0, "beta": 0.3, "e": 0.5, "r6": 4.0, "r7": 3.0}
    p["sigma"] = -1.0
    lp = L.loop(NUMPY, THETA, p)
    assert [k for k, _ in lp.margins] == ["four-bar closure at B", "closure at E"]
    e, o6, pp = lp.points["E"], lp.points["O6"], lp.points["P"]
    np.testing.assert_allclose(np.hypot(e[0] - pp[0], e[1] - pp[1]), 4.0, atol=1e-12)
    np.testing.assert_allclose(np.hypot(e[0] - o6[0], e[1] - o6[1]), 3.0, atol=1e-12)
    cross = (pp[0] - o6[0]) * (e[1] - o6[1]) - (pp[1] - o6[1]) * (e[0] - o6[0])
    assert np.all(cross > 0)  # the branch sign of the contract
    assert o6[1] == 2 * 3.0 - 0.5
    j = L.loop(JET, Jet.seed(THETA), p)
    h = 1e-6
    fd = (L.loop(NUMPY, THETA + h, p).x - L.loop(NUMPY, THETA - h, p).x) / (2 * h)
    np.testing.assert_allclose(j.x.d1, fd, atol=1e-6)
    assert [b.name for b in L.bodies()] == ["crank", "coupler", "follower", "link6", "rocker"]
    assert L.bodies()[1].kind == "plate" and L.output_joint() is None


@pytest.mark.parametrize(
    ("declare", "message"),
    [
        (lambda L: L.ground("O2", (0, 0)), "placed twice"),
        (lambda L: L.crank("Z", about="O2", length="r2"), "one crank"),
        (lambda L: L.ground("Q", ("r1 +", 0)), "cannot read"),
        (lambda L: L.ground("Q", ("r1 r2", 0)), "cannot read"),
        (lambda L: L.rpr("A", pivot="O4", angle="theta9"), "two transmission rules"),
        (lambda L: L.rpr("C", pivot="O4", angle="theta4"), "angle 'theta4' is defined twice"),
        (lambda L: L.rrp("E", ("C", "r7"), line_y="h", angle=None), "used twice"),
        (lambda L: L.on_ray("X", "O2", "Q", "r9").output("X"), "never placed"),
        (lambda L: L.on_ray("X", "O2", "O4", "r9").output("X"), "no link carries"),
        (lambda L: L.output("nowhere"), "neither a placed joint"),
    ],
)
def test_declaration_errors_are_named(declare, message):
    with pytest.raises(LinkageError, match=message):
        L = crank_shaper_rod()
        declare(L)
        L.bodies()
        L.loop(NUMPY, THETA, {})


def test_the_docstrings_example_is_a_type_of_its_own():
    """A type from scratch (no shipped parent, no KIND): the module docstring's four-bar slider."""
    from qropt.mechanisms import REQUIRED, Mechanism, grashof_rules

    L = four_bar_slider()

    class BuiltDragLink(Mechanism):
        PARAMS = {**{k: REQUIRED for k in L.parameters() if k[0] == "r"}, "h": 0.0, "sigma": -1.0, "sigma_slider": 1.0}
        LENGTHS = ("r1", "r2", "r3", "r4", "r5", "r6")
        loop = staticmethod(L.loop)
        BODIES, GROUND, OUTPUT_JOINT = L.bodies(), L.ground_joints(), L.output_joint()

        @classmethod
        def rules(cls, xp, p, grashof=None):
            return grashof_rules(xp, p, grashof or "drag-link")

    for m in _valid_qr("drag-link-slider", 2, seed=8):
        b = BuiltDragLink(**m.params)
        assert abs(b.time_ratio() - m.time_ratio()) <= TOL and abs(b.stroke() - m.stroke()) <= TOL
        assert abs(b.gamma_min().value - m.gamma_min().value) <= TOL
        assert b.bodies() == m.bodies()
