"""General loads through the compiled dynamics kernel (qropt.dynamics.compiled): the same unknowns as the jets and
numpy (``inverse._numpy_parts``, forced by a kernel that declines) for random mechanisms of every type under
every load kind (forces at joints and body points against a velocity, along the slide and along a vector, tables
against x and theta2, windows, torques, a gravity vector, point masses), with the slide's friction and a cutting
force's table on top, at both senses of rotation and on strokes closed at their dead centres; the kernel's cache
per layout of the loads; and the same numbers before and after the kernel turns to machine code."""

from __future__ import annotations

import math

import numpy as np
import pytest

from qropt import Force, Loads, Masses, Torque
from qropt.dynamics import compiled
from qropt.dynamics.cycle import CycleDynamics
from qropt.dynamics.inverse import inverse_dynamics, system_of
from tests.randmech import random_mechanisms
from tests.test_loads import ALL, _random_loads


def _routes(monkeypatch, call, *args, **kw):
    """call(*args, **kw) through the kernel (checked that it took every solve) and through the jets and numpy."""
    taken = []
    real = compiled.parts

    def spy(*a, **k):
        out = real(*a, **k)
        taken.append(out is not None)
        return out

    monkeypatch.setattr(compiled, "parts", spy)
    fast = call(*args, **kw)
    assert taken and all(taken), "the compiled kernel declined a solve"
    monkeypatch.setattr(compiled, "parts", lambda *a, **k: None)
    slow = call(*args, **kw)
    monkeypatch.setattr(compiled, "parts", real)
    return fast, slow


def _close(a, b, what, tol=1e-12):
    scale = max(float(np.max(np.abs(b))), 1e-300)
    err = float(np.max(np.abs(np.asarray(a) - np.asarray(b)))) / scale
    assert err <= tol, f"{what}: {err:.3g}"


def _same(fast, slow, what):
    _close(fast.torque, slow.torque, f"{what} torque")
    assert fast.joint_forces.keys() == slow.joint_forces.keys()
    for j in slow.joint_forces:
        _close(fast.joint_forces[j], slow.joint_forces[j], f"{what} {j}")
    _close(fast.shaking_force, slow.shaking_force, f"{what} shaking force")
    _close(fast.shaking_moment, slow.shaking_moment, f"{what} shaking moment")
    if slow.guide_moment is not None:
        _close(fast.guide_moment, slow.guide_moment, f"{what} guide moment")


@pytest.mark.parametrize("kind", ALL)
def test_the_kernel_gives_the_numpy_routes_unknowns(kind, monkeypatch):
    rng = np.random.default_rng(100 + ALL.index(kind))
    for i, (_, m) in enumerate(random_mechanisms(kind, 2, seed=23)):
        masses, loads = _random_loads(m, rng, kind)
        if m.output_joint() is not None and i == 1:  # the slide's friction and a cutting force's table on top
            x = m.motion(np.linspace(0, 2 * math.pi, 16, endpoint=False), 1.0).x
            table = ((float(x.min()), 200.0), (float(x.max()), 900.0))
            loads = Loads(table, 0.08, loads.gravity, forces=loads.forces, torques=loads.torques)
        omega2 = (1.0 if i % 2 == 0 else -1.0) * rng.uniform(2, 12)
        alpha2 = rng.uniform(-20, 20)
        t = rng.uniform(0, 2 * math.pi, 40)
        fast, slow = _routes(monkeypatch, inverse_dynamics, m, t, omega2, alpha2, masses=masses, loads=loads)
        _same(fast, slow, repr(m))
        if m.output_joint() is not None:  # strokes closed at their dead centres: the limits of 'against' there
            cd = CycleDynamics(m, omega2, 0.0, masses, loads)
            (lo, hi), on = cd.pieces[0], cd.working_pieces[0]
            ends = np.linspace(lo, hi, 9) % (2 * math.pi)
            for working in (on, not on):
                fast, slow = _routes(monkeypatch, cd.at, ends, working)
                _same(fast, slow, f"{m!r} closed stroke")


def test_a_gravity_vector_alone_and_single_angles(monkeypatch):
    """A gravity vector without forces takes the kernel too; one crank angle at a time is as a batch."""
    for kind in ("whitworth", "four-bar"):
        _, m = random_mechanisms(kind, 1, seed=5)[0]
        masses = Masses(density=7.0, ram=3.0)
        t = np.linspace(0.0, 2 * math.pi, 13)
        for loads in (Loads(gravity=(2.0, -9.0)), Loads(gravity=(0.0, 9.81), torques=[Torque("crank", 3.0)])):
            fast, slow = _routes(monkeypatch, inverse_dynamics, m, t, 4.0, 1.0, masses=masses, loads=loads)
            _same(fast, slow, repr(m))
            one = [inverse_dynamics(m, [th], 4.0, 1.0, masses=masses, loads=loads).torque[0] for th in t]
            _close(one, fast.torque, f"{m!r} one angle at a time")


def test_a_kernel_per_layout_of_the_loads():
    """Loads that differ only in magnitudes, tables, windows, directions and body-point coordinates share a
    kernel; another body or joint takes its own."""
    _, m = random_mechanisms("whitworth", 1, seed=3)[0]
    s = system_of(m, Masses(density=5.0))
    from qropt.dynamics import applied
    from qropt.dynamics.inverse import linkage_of

    def kernel_of(*forces):
        return compiled.kernel(m, s, False, applied.resolve(m, s, linkage_of(m), Loads(forces=forces)))

    a = kernel_of(Force(("lever", 0.1, 0.0), 10.0, "against"), Force("D", 5.0, "slide"))
    b = kernel_of(Force(("lever", -0.3, 0.2), ((0.5, 1.0), (0.9, 3.0)), (1.0, 2.0), "always"), Force("D", -1.0))
    c = kernel_of(Force(("rod", 0.1, 0.0), 10.0, "against"), Force("D", 5.0, "slide"))
    assert a is b and a is not c
    assert a is not compiled.kernel(m, s, True, applied.resolve(m, s, linkage_of(m), Loads(forces=[Force("D", 1.0)])))


def test_the_numbers_do_not_depend_on_how_often_it_ran(monkeypatch):
    """The kernel's first calls (CasADi's virtual machine) and its calls once compiled (one row's code mapped, and
    the whole map as one loop from Batched.WIDE rows) give the same numbers to the last bit."""
    from qropt.kinematics import native

    monkeypatch.setattr(compiled, "_KERNELS", {})
    _, m = random_mechanisms("crank-shaper", 1, seed=9)[0]
    rng = np.random.default_rng(4)
    masses, loads = _random_loads(m, rng, "crank-shaper")
    for n in (5, 80):
        t = np.linspace(0.1, 6.0, n)
        first = inverse_dynamics(m, t, 6.0, 2.0, masses=masses, loads=loads)
        for _ in range(20):
            last = inverse_dynamics(m, t, 6.0, 2.0, masses=masses, loads=loads)
        assert np.array_equal(first.torque, last.torque)
        for j in first.joint_forces:
            assert np.array_equal(first.joint_forces[j], last.joint_forces[j])
    if native.enabled():  # the last calls ran as machine code
        (f,) = [f for key, f in compiled._KERNELS.items() if key[-1] is not None]
        assert all(f._by_k[n][5] for n in (5, 80))
