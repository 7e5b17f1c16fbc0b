"""Compiled kernels (qropt.kinematics.native): the same numbers as CasADi's virtual machine and the Taylor jets,
a cache on disk, and a working fallback without a compiler."""

import ast
import os
import pickle
from pathlib import Path

import casadi
import numpy as np
import pytest

import qropt
from qropt.kinematics import cycle, driver, native
from qropt.kinematics.kernel import Batched
from qropt.kinematics.ops import JET, Jet
from qropt.mechanisms import TYPES
from tests.child import run_child
from tests.randmech import random_mechanisms

ROOT = Path(__file__).resolve().parents[1]
needs_compiler = pytest.mark.skipif(not native.enabled(), reason="no C compiler (the VM is used)")


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("QROPT_CACHE", str(tmp_path))
    return tmp_path / "kernels"


def _jet_motion(m, t, omega2, alpha2):
    """((x, v, a), (angles, omega, alpha)) of mechanism m by Taylor jets through its loop: an independent route."""
    lp = m.evaluate(JET, Jet.seed(t, omega2, alpha2))

    def parts(j):
        if isinstance(j, Jet) and j.c.shape == (3,) + t.shape:
            return list(j.c.copy())
        if isinstance(j, Jet):
            return [np.broadcast_to(c, t.shape).astype(float) for c in (j.v, j.d1, j.d2)]
        return [np.broadcast_to(float(j), t.shape).astype(float), np.zeros_like(t), np.zeros_like(t)]

    rates = {k: parts(j) for k, j in lp.angles.items()}
    return parts(lp.x), tuple({k: r[i] for k, r in rates.items()} for i in range(3))


@needs_compiler
@pytest.mark.parametrize("cls", TYPES, ids=lambda c: c.KIND)
def test_compiled_kernels_equal_the_vm(cls, cache):
    """Grid values, the batched Newton refinement and the time rates: compiled (no fused multiply-adds) equal
    the virtual machine's to the last bit (the first call's), at a random mechanism of every type."""
    _, m = random_mechanisms(cls.KIND, 1, seed=23)[0]
    k = m._kernel
    p = k.vector(m.params)
    th = cycle.grid(180)
    grid = k.grid_values(p, th)  # builds the Function
    vm_grid = Batched(k._groups["grid"].f)
    z = np.column_stack([th, np.broadcast_to(p, (th.size, p.size))])
    compiled = native.compiled(k._groups["grid"].f.map(th.size))
    assert compiled is not k._groups["grid"].f
    out = np.zeros((th.size, grid.shape[0]))
    buf, ev = compiled.buffer()
    zin = np.ascontiguousarray(z)
    buf.set_arg(0, memoryview(zin))
    buf.set_res(0, memoryview(out))
    ev()
    np.testing.assert_array_equal(out, vm_grid(z))
    assert list(cache.glob("*.so")), "the shared library is kept in the cache"
    # the rates: on the VM at the first call, compiled once hot, the same to the last bit; against the jets
    t = np.linspace(0.0, 2 * np.pi, 97, endpoint=False)
    first = m.motion(t, 7.0, 2.0)
    for _ in range(Batched.HOT + 1):
        mo = m.motion(t, 7.0, 2.0)
    assert k._groups["rates all"]._entry(t.size)[5], "the last calls ran compiled"
    for got, want in [
        (mo.x, first.x),
        (mo.v, first.v),
        (mo.a, first.a),
        *zip(mo.alpha.values(), first.alpha.values(), strict=True),
    ]:
        np.testing.assert_array_equal(got, want)
    (x, v, a), (ang, om, al) = _jet_motion(m, t, 7.0, 2.0)
    scale = max(1.0, np.abs(a).max())
    np.testing.assert_allclose(mo.x, x, rtol=0, atol=1e-13 * max(1.0, np.abs(x).max()))
    np.testing.assert_allclose(mo.v, v, rtol=0, atol=1e-13 * max(1.0, np.abs(v).max()))
    np.testing.assert_allclose(mo.a, a, rtol=0, atol=1e-12 * scale)
    for name in ang:
        np.testing.assert_allclose(mo.omega[name], om[name], rtol=0, atol=1e-12 * max(1.0, np.abs(om[name]).max()))
        np.testing.assert_allclose(mo.alpha[name], al[name], rtol=0, atol=1e-11 * max(1.0, np.abs(al[name]).max()))


@needs_compiler
@pytest.mark.parametrize("cls", TYPES, ids=lambda c: c.KIND)
def test_the_refinement_in_c_equals_numpys(cls, cache):
    """The driver's bracketing and Newton loop (one C call, ``qropt.kinematics.driver``) gives the numpy route's
    extremes to the last bit, for every group at random mechanisms of every type: the cycle quantities on their
    grid, the exact acceleration and velocity and every joint coordinate on a grid, and samples that are not the
    quantity's (noise: most Newton starts fail and go on to the safeguarded iteration)."""
    rng = np.random.default_rng(3)
    for _, m in random_mechanisms(cls.KIND, 3, seed=31):
        k, p = m._kernel, m._vector
        th = cycle.grid(180)
        coords = k.grid_coords(m.params, th)
        cases = [
            ("cycle", m._grid, k.cycle_requests),
            ("accel", k.group("accel")[0].at(th, p)[0][None, :], [(0, "max"), (0, "min")]),
            ("velocity", k.group("velocity")[0].at(th, p)[0][None, :], [(0, "max"), (0, "min")]),
            ("coords", coords, [(i, kind) for i in range(coords.shape[0]) for kind in ("max", "min")]),
            ("cycle", rng.normal(size=m._grid.shape), k.cycle_requests),
        ]
        for j, (group, q, requests) in enumerate(cases):
            with pytest.MonkeyPatch.context() as mp:
                mp.setitem(k._drivers, group, None)  # the numpy route
                ref = k.refine(group, q, requests, p)
            d = driver.build(k._switch(group).f, f"{group}_refine")
            rows, sgn, *_ = k._plan(requests)
            not_converged = d.refine(np.ascontiguousarray(q), 2 * np.pi / q.shape[1], rows, sgn, p)[1][-1]
            assert not_converged > 0 or j != 4, "the noise sends starts to the safeguarded iteration"
            with pytest.MonkeyPatch.context() as mp:
                mp.setitem(k._drivers, group, d)
                got = k.refine(group, q, requests, p)
            assert len(got) == len(ref) == len(requests)
            for a, b in zip(got, ref, strict=True):
                np.testing.assert_array_equal(a.theta, b.theta)
                np.testing.assert_array_equal(a.value, b.value)
    assert any(e.theta.size for e in got), "the noise has extremes the safeguarded iteration confirms"
    params = random_mechanisms(cls.KIND, 1, seed=32)[0][0]
    for _ in range(Batched.HOT):  # a type analysed often: its cycle's refinement runs in C from then on
        cls(**params).gamma_min()
    assert isinstance(cls(**params)._kernel._drivers.get("cycle"), driver.Driver)


@needs_compiler
def test_the_driver_keeps_the_buffers_of_at_most_kept_request_lists(cache):
    """Each new request list (a kernel's plan, made anew for each design) gets buffers of its own; the driver keeps
    those of at most KEPT lists, so that a long process does not hold them all, and a list's extremes do not
    depend on what it kept."""
    _, m = random_mechanisms("slider-crank", 1, seed=5)[0]
    k, p = m._kernel, m._vector
    d = driver.build(k._switch("cycle").f, "cycle_refine")
    rows, sgn, *_ = k._plan(k.cycle_requests)
    q = np.ascontiguousarray(m._grid)
    h = 2 * np.pi / q.shape[1]
    first = d.refine(q, h, rows, sgn, p)[0].copy()
    for _ in range(driver.Driver.KEPT + 5):
        again = d.refine(q, h, rows.copy(), sgn.copy(), p)[0]
        np.testing.assert_array_equal(again, first)
    assert 0 < len(d._local.calls) <= driver.Driver.KEPT


@needs_compiler
@pytest.mark.parametrize("kind", ["slider-crank", "crank-shaper", "whitworth", "four-bar", "coupler-slider"])
def test_compiled_dynamics_equal_the_jets_route(kind, cache):
    """The inverse dynamics once compiled (kinematics, bodies, the Newton-Euler elimination in one C call per
    angle) against the jets and numpy's elimination, for every case of the dynamics tests (a counterweight, a
    massive block, an offset yoke, gravity, friction's iteration, both senses; a follower torque) and a cutting
    force table: torque, every joint force and the shaking, to 1e-12 of their largest. Both compiled variants
    run (a known load in the call; per unit load for a table and friction)."""
    from qropt.dynamics import compiled
    from qropt.dynamics.inverse import system_of
    from tests.test_dynamics import _case, _designs

    t = np.linspace(0.0, 2 * np.pi, 131, endpoint=False) + 0.01
    used = set()
    for i, m in enumerate(_designs(kind)):
        masses, loads, omega2, alpha2 = _case(kind, i, m)
        if i == 1 and kind != "four-bar":  # a table of the ram's position
            d = m.dead_centres()
            loads = qropt.Loads(((d.x_min, 100.0), (d.x_max, 900.0)), gravity=9.81)
        with pytest.MonkeyPatch.context() as mp:  # the reference: the jets and numpy, whatever is hot
            mp.setattr(compiled, "parts", lambda *a, **k: None)
            jets = m.dynamics(t, omega2, alpha2, masses=masses, loads=loads)
        for _ in range(Batched.HOT + 1):
            hot = m.dynamics(t, omega2, alpha2, masses=masses, loads=loads)
        superposed = isinstance(loads.cutting_force, tuple) or bool(loads.friction)
        f = compiled.kernel(m, system_of(m, masses), superposed)
        assert f._uses.get(t.size, 0) >= Batched.HOT and f._entry(t.size)[5], "ran compiled"
        used.add(superposed)
        for a, b in [(jets.torque, hot.torque), (jets.shaking_force, hot.shaking_force)] + [
            (jets.joint_forces[j], hot.joint_forces[j]) for j in jets.joint_forces
        ]:
            np.testing.assert_allclose(b, a, rtol=0, atol=1e-12 * max(1.0, np.abs(a).max()))
    assert used == ({False} if kind == "four-bar" else {False, True})


def test_threads_analysing_mechanisms_get_the_numbers_of_one_thread():
    """Four threads analyse the same designs at once, past the calls that compile (the cycle's kernels, the
    refinement's C loop, the dynamics): every number equals the one-thread run's to the last bit (as a web server's
    request threads do)."""
    code = (
        "import threading, numpy as np, qropt\n"
        "from tests.randmech import random_mechanisms\n"
        "designs = [p for p, _ in random_mechanisms('drag-link-slider', 6, seed=5)]\n"
        "t = np.linspace(0, 6, 50)\n"
        "masses = qropt.Masses.steel(4e-4, ram=20.0)\n"
        "def run(p):\n"
        "    m = qropt.DragLinkSlider(**p)\n"
        "    d = m.dynamics(t, 10.0, masses=masses, loads=qropt.Loads(1000.0))\n"
        "    return (m.gamma_min().value, m.peak_acceleration(10.0).value, *d.torque)\n"
        "ref = [run(p) for p in designs]\n"
        "wrong = []\n"
        "def work(i):\n"
        "    for k in range(20): wrong.append(run(designs[(i + k) % 6]) != ref[(i + k) % 6])\n"
        "ts = [threading.Thread(target=work, args=(i,)) for i in range(4)]\n"
        "[x.start() for x in ts]; [x.join() for x in ts]\n"
        "print(len(wrong), sum(wrong))\n"
    )
    assert run_child(code, 300, cwd=ROOT).split() == ["80", "0"]


@needs_compiler
@pytest.mark.parametrize("kind", ["crank-shaper", "four-bar"])
def test_dynamics_are_the_same_from_the_first_call_to_the_compiled_ones(kind, cache):
    """A structure's dynamics give the same numbers to the last bit at every call, on CasADi's VM and then
    compiled, so that a dynamic solve does not depend on what the process evaluated before."""
    from qropt.dynamics import compiled
    from qropt.dynamics.inverse import system_of
    from tests.test_dynamics import _case, _designs

    t = np.linspace(0.0, 2 * np.pi, 97, endpoint=False) + 0.02
    m = _designs(kind)[0]
    masses, loads, omega2, alpha2 = _case(kind, 0, m)
    runs = [m.dynamics(t, omega2, alpha2, masses=masses, loads=loads) for _ in range(Batched.HOT + 2)]
    f = compiled.kernel(m, system_of(m, masses), False)
    assert f._entry(t.size)[5], "the last calls ran compiled"
    for r in runs[1:]:
        np.testing.assert_array_equal(r.torque, runs[0].torque)
        for j in r.joint_forces:
            np.testing.assert_array_equal(r.joint_forces[j], runs[0].joint_forces[j])


def test_slider_gives_link_rates_on_demand():
    """slider() computes x, v, a; its link rates, asked for, equal motion()'s."""
    _, m = random_mechanisms("whitworth", 1, seed=4)[0]
    t = np.linspace(0.0, 2 * np.pi, 131, endpoint=False)
    for _ in range(Batched.HOT + 2):
        s, mo = m.slider(t, 3.0, 1.0), m.motion(t, 3.0, 1.0)
    np.testing.assert_array_equal(s.x, mo.x)
    np.testing.assert_array_equal(s.a, mo.a)
    assert set(s.omega) == set(mo.omega)
    for name in mo.omega:
        np.testing.assert_array_equal(s.alpha[name], mo.alpha[name])
    back = pickle.loads(pickle.dumps(m.slider(t, 3.0, 1.0)))  # as data, its link rates with it
    np.testing.assert_array_equal(back.a, mo.a)
    np.testing.assert_array_equal(back.omega["theta4"], mo.omega["theta4"])


def test_a_compiler_error_falls_back_to_the_vm(cache, monkeypatch):
    monkeypatch.setitem(native._STATE, "compiler", "/bin/false")
    x = casadi.SX.sym("x")
    f = casadi.Function("square_plus_one", [x], [x * x + 1])
    assert native.compiled(f) is f
    assert not list(cache.glob("*.so"))


def test_analysis_without_a_compiler_is_the_same():
    """QROPT_NATIVE=0 (no machine code): the paper's mechanism analysed many times gives the same numbers."""
    code = (
        "import qropt, numpy as np\n"
        "from qropt.examples import paper_mechanism\n"
        "p = dict(paper_mechanism().params)\n"
        "for _ in range(40): m = qropt.DragLinkSlider(**p); out = (m.time_ratio(), m.stroke(), m.gamma_min().value,"
        " m.peak_acceleration(10.0).value, float(m.slider(np.linspace(0, 6, 200), 10.0).a.sum()))\n"
        "print(repr(out))\n"
    )
    runs = {}
    for flag in ("0", "1"):
        env = {**os.environ, "QROPT_NATIVE": flag}
        runs[flag] = ast.literal_eval(run_child(code, 300, env=env).strip())
    np.testing.assert_allclose(runs["0"], runs["1"], rtol=1e-13, atol=0)


def test_threads_calling_one_kernel_each_get_their_own_rows():
    """Four threads evaluate one Batched with the same K at once (CasADi runs a buffer without Python's lock): each
    gets its own rows, bit for bit, and the process does not crash (it did with buffers shared by K). In a
    subprocess, so that a crash is this test's failure."""
    code = (
        "import threading, casadi, numpy as np\n"
        "from qropt.kinematics.kernel import Batched\n"
        "x = casadi.MX.sym('z', 4); y = x\n"
        "for _ in range(100): y = casadi.sin(y) * 1.0001 + casadi.cos(y[::-1])\n"
        "b = Batched(casadi.Function('threads', [x], [y]), compiled=False)\n"
        "z = np.random.default_rng(0).standard_normal((2800, 4)); ref = b(z); wrong = []\n"
        "def work(i):\n"
        "    for _ in range(30): wrong.append(not np.array_equal(b(z[i::4]), ref[i::4]))\n"
        "ts = [threading.Thread(target=work, args=(i,)) for i in range(4)]\n"
        "[t.start() for t in ts]; [t.join() for t in ts]\n"
        "print(len(wrong), sum(wrong))\n"
    )
    assert run_child(code, 300).split() == ["120", "0"]
