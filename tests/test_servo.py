"""Servo crank-speed profiles (qropt.servo): closed forms, monotone limits, exact simulation, examples, errors."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import scipy.integrate

import qropt
from qropt import cli as qropt_cli
from qropt.convex.servo import speed_profile
from qropt.errors import InvalidParameter
from qropt.examples import paper_mechanism

INLINE = qropt.SliderCrank(r2=0.1, r3=0.4)  # geometric TR 1
CUT = dict(omega_max=20.0, v_cut=0.5, a_max=40.0, alpha_max=400.0, v_max=2.0)
TORQUE = dict(omega_max=13.0, alpha_max=200.0, force=1000.0, inertia=1.0, torque_max=113.0)


def speed_only_time(m, omega_max, v_max):
    """integral of max(1/omega_max, |x'|/v_max) over a turn, by adaptive quadrature split at the kinks."""

    def f(t):
        return max(1 / omega_max, abs(m.motion(np.array([t]), 1.0, 0.0).v[0]) / v_max)

    th = np.linspace(0, 2 * math.pi, 20001)
    g = np.abs(m.motion(th, 1.0, 0.0).v) - v_max / omega_max
    pts = [0.0, *th[np.flatnonzero(np.diff(np.sign(g)))].tolist(), 2 * math.pi]
    quad = scipy.integrate.quad
    return sum(quad(f, a, b, epsabs=1e-14, epsrel=1e-13, limit=200)[0] for a, b in zip(pts[:-1], pts[1:], strict=True))


def simulate(p, refine=10):
    """Independent check: b = omega^2 interpolated linearly on a grid `refine` times finer, t by the midpoint
    rule on dt = dtheta / omega, x from exact positions, v and a by finite differences in time."""
    u = np.arange(refine) / refine
    th = np.append((p.theta[:-1, None] + u * np.diff(p.theta)[:, None]).ravel(), p.theta[-1])
    omega = np.sqrt(np.interp(th, p.theta, p.omega**2))
    mid = 0.5 * (th[1:] + th[:-1])
    w_mid = np.sqrt(np.interp(mid, p.theta, p.omega**2))
    dt = np.diff(th) / w_mid  # midpoint rule per sub-cell
    t = np.concatenate([[0.0], np.cumsum(dt)])
    x = p.mechanism.positions(th).x
    v = np.diff(x) / dt  # at the sub-cell midpoints
    a = np.diff(v) / (0.5 * (dt[1:] + dt[:-1]))  # at the inner nodes
    return t, th, omega, mid, v, a


@pytest.mark.parametrize(
    "m, omega_max, v_max", [(qropt.SliderCrank(r2=0.1, r3=0.35, e=0.06), 20.0, 1.5), (paper_mechanism(), 12.0, 1.5)]
)
def test_speed_limits_only_match_the_closed_form(m, omega_max, v_max):
    exact = speed_only_time(m, omega_max, v_max)
    errors = {}
    for n in (360, 720):
        p = speed_profile(m, omega_max=omega_max, v_max=v_max, n=n)
        assert p.status == "optimal"
        xp = np.abs(m.motion(p.theta, 1.0, 0.0).v)
        with np.errstate(divide="ignore"):
            best = np.minimum(omega_max, v_max / xp)  # the fastest speed each node allows
        np.testing.assert_allclose(p.omega, best, rtol=1e-6)
        errors[n] = abs(p.cycle_time - exact) / exact
    assert errors[720] < 3e-5  # O(h^2): piecewise-linear b between the nodes
    assert errors[360] > 2.5 * errors[720] or errors[720] < 5e-6


def test_each_added_limit_never_shortens_the_cycle():
    m = paper_mechanism()
    steps = [
        dict(omega_max=12.0),
        dict(omega_max=12.0, v_max=2.0),
        dict(omega_max=12.0, v_max=2.0, a_max=50.0),
        dict(omega_max=12.0, v_max=2.0, a_max=50.0, alpha_max=100.0),
        dict(omega_max=12.0, v_max=2.0, a_max=50.0, alpha_max=100.0, force=1000.0, inertia=1.0, torque_max=140.0),
        dict(omega_max=12.0, v_max=1.2, a_max=50.0, alpha_max=100.0, force=1000.0, inertia=1.0, torque_max=140.0),
    ]
    times = [speed_profile(m, **kw).cycle_time for kw in steps]
    assert times[0] == pytest.approx(2 * math.pi / 12.0, rel=1e-9)
    assert all(b >= a * (1 - 1e-9) for a, b in zip(times[:-1], times[1:], strict=True)), times
    assert times[-1] > times[0] * 1.05  # the limits do bind


def test_exact_simulation_respects_the_limits_within_the_stated_error():
    p = speed_profile(INLINE, **CUT)
    t, th, omega, mid, v, a = simulate(p)
    assert t[-1] == pytest.approx(p.cycle_time, rel=1e-6)  # midpoint rule on a 10x grid vs exact cell times
    assert omega.max() <= CUT["omega_max"] * (1 + 1e-7)
    assert np.abs(v).max() <= CUT["v_max"] * (1 + 1e-4)  # O(h^2) between nodes, measured 1.4e-5
    assert np.abs(a).max() <= CUT["a_max"] * (1 + 1e-4)
    lo, hi = p.theta[p.cut_cells[0]], p.theta[p.cut_cells[1]]
    inside = (mid > lo) & (mid < hi)
    assert np.abs(np.abs(v[inside]) / CUT["v_cut"] - 1).max() < 2e-4
    # the library's own exact sampling: excess O(h^2), bounded by h^2/8 max|q''| per cell
    excess = p.check()
    assert max(excess.values()) < 1e-4
    coarse = speed_profile(INLINE, **CUT, n=360).check()
    for k in ("v_max", "v_cut"):
        assert coarse[k] > 2.5 * excess[k]  # second order in the cell size
    s = p.motion(10)
    q = (s.v**2).reshape(-1, 11)  # v^2 per cell, smooth inside a cell
    h = np.diff(p.theta)
    d2 = np.abs(np.diff(q, 2, axis=1)).max(axis=1) / (h / 10) ** 2
    bound = (h**2 / 8 * d2).max() / CUT["v_max"] ** 2
    assert 0 < excess["v_max"] <= bound


def test_inline_slider_crank_reaches_tr_2_with_constant_cutting_speed():
    assert INLINE.time_ratio() == pytest.approx(1.0, abs=1e-12)
    p = speed_profile(INLINE, **CUT)
    assert p.status == "optimal"
    assert p.time_ratio >= 2.0 and p.working_time > p.return_time
    assert p.time_ratio == pytest.approx(p.working_time / p.return_time)
    s = p.motion()
    k = np.repeat(np.arange(p.alpha.size), 11)
    inside = (k >= p.cut_cells[0]) & (k < p.cut_cells[1])
    x = s.x[inside]
    travel = x.max() - x.min()
    assert travel == pytest.approx(0.8 * INLINE.stroke(), rel=1e-12)  # the central 80% of the stroke
    assert np.all(s.v[inside] < 0)  # the working stroke moves -x
    c = p.constant_speed()
    assert c.cycle_time == pytest.approx(2 * math.pi / 20.0) and c.time_ratio == pytest.approx(1.0)


def test_min_return_time_is_no_slower_on_the_return():
    kw = dict(omega_max=20.0, v_cut=0.5, a_max=15.0, alpha_max=300.0)
    fast_cycle = speed_profile(INLINE, **kw)
    fast_return = speed_profile(INLINE, **kw, objective="min_return_time")
    assert fast_return.status == "optimal"
    assert fast_return.return_time <= fast_cycle.return_time * (1 + 1e-6)
    assert fast_return.cycle_time >= fast_cycle.cycle_time * (1 - 1e-6)


def test_paper_drag_link_peak_torque_cut_by_a_speed_profile():
    m = paper_mechanism()
    start, length = m.working_arc()
    th = start + np.linspace(0, length, 200001)
    constant_peak = 1000.0 * np.abs(m.motion(th, 1.0, 0.0).v).max()  # F |x'| at any constant speed
    p = speed_profile(m, **TORQUE)
    assert p.status == "optimal"
    assert p.constant_speed().peak_torque == pytest.approx(constant_peak, rel=1e-8)
    assert p.peak_torque <= 113.0 * (1 + 1e-4) and p.peak_torque < 0.7 * constant_peak
    assert p.cycle_time < 2 * math.pi / 12.0  # faster than a constant 12 rad/s crank with 162 N m peaks
    # independent torque: inertia * alpha + F |dx/dtheta| from the simulated motion
    t, th, omega, mid, v, a = simulate(p)
    alpha = np.diff(omega**2) / (2 * np.diff(th))
    working = (mid - start) % (2 * math.pi) < length
    slope = np.abs(np.diff(p.mechanism.positions(th).x) / np.diff(th))
    torque = 1.0 * alpha + 1000.0 * slope * working
    assert np.abs(torque).max() <= 113.0 * (1 + 1e-4)


def test_infeasible_limits_name_the_binding_ones():
    p = speed_profile(INLINE, omega_max=2.0, v_cut=0.5)  # the cut needs omega2 = v_cut / |x'| > 2 rad/s
    assert p.status == "infeasible" and p.time is None and p.cycle_time is None
    assert set(p.binding) == {"omega_max", "v_cut"} and "omega_max" in p.message
    q = speed_profile(paper_mechanism(), omega_max=12.0, force=1000.0, inertia=0.05, torque_max=113.0)
    assert q.status == "infeasible" and "torque_max" in q.binding and "torque_max +" in q.message
    with pytest.raises(InvalidParameter, match="no profile"):
        q.motion()


@pytest.mark.parametrize(
    "kw, match",
    [
        (dict(omega_max=0.0), "omega_max"),
        (dict(omega_max=-1.0), "omega_max"),
        (dict(omega_max=10.0, v_max=-1.0), "v_max"),
        (dict(omega_max=10.0, a_max=0.0), "a_max"),
        (dict(omega_max=10.0, alpha_max=float("nan")), "alpha_max"),
        (dict(omega_max=10.0, v_cut=2.0, v_max=1.0), "v_cut = 2 is above v_max"),
        (dict(omega_max=10.0, v_cut=0.5, cut_fraction=1.0), "cut_fraction"),
        (dict(omega_max=10.0, n=35), "n"),
        (dict(omega_max=10.0, n=720.0), "n"),
        (dict(omega_max=10.0, objective="fastest"), "objective"),
        (dict(omega_max=10.0, torque_max=5.0), "needs a force or an inertia"),
        (dict(omega_max=10.0, force=-1.0), "force"),
        (dict(omega_max="10"), "omega_max"),
    ],
)
def test_bad_input_raises_a_typed_error(kw, match):
    with pytest.raises(InvalidParameter, match=match):
        speed_profile(INLINE, **kw)


def test_not_a_mechanism():
    with pytest.raises(InvalidParameter):
        speed_profile("slider-crank", omega_max=10.0)


def test_plot(tmp_path):
    from PIL import Image

    p = speed_profile(paper_mechanism(), **TORQUE)
    f = tmp_path / "servo.png"
    p.plot(f)
    w, h = Image.open(f).size
    assert w > 600 and h > 600
    assert "cycle_time=0.5197" in repr(p) and "peak_torque=113" in repr(p)


# ---- command line ---------------------------------------------------------------------------------------
def cli(argv, capsys):
    """(exit code, stdout, stderr) of ``qropt ...`` through ``qropt.cli.main`` (one line on error)."""
    code = qropt_cli.main(argv)
    out = capsys.readouterr()
    return code, out.out, out.err


def test_cli_text_csv_and_plot(tmp_path, capsys):
    csv_file, png = tmp_path / "p.csv", tmp_path / "p.png"
    args = [
        "servo",
        "slider-crank",
        "--r2",
        "0.1",
        "--r3",
        "0.4",
        "--omega-max",
        "20",
        "--v-cut",
        "0.5",
        "--a-max",
        "40",
        "--alpha-max",
        "400",
        "--v-max",
        "2",
        "--csv",
        str(csv_file),
        "--plot",
        str(png),
    ]
    code, out, _ = cli(args, capsys)
    p = speed_profile(INLINE, **CUT)
    assert code == 0
    assert f"time ratio        {p.time_ratio:.6f}; 1.000000 at constant speed" in out
    assert f"cycle time        {p.cycle_time:.6f} s" in out
    rows = np.loadtxt(csv_file, delimiter=",", skiprows=1)
    assert rows.shape == (720, 8)
    np.testing.assert_allclose(rows[:, 2], p.omega[:-1], rtol=1e-10)
    assert png.stat().st_size > 10_000


def test_cli_json_torque_example(capsys):
    code, out, _ = cli(
        [
            "servo",
            "--omega-max",
            "13",
            "--alpha-max",
            "200",
            "--force",
            "1000",
            "--inertia",
            "1",
            "--torque-max",
            "113",
            "--json",
        ],
        capsys,
    )
    r = json.loads(out)
    assert code == 0 and r["type"] == "drag-link-slider" and r["status"] == "optimal"
    assert r["peak_torque"] < 113.02 and r["constant_speed"]["peak_torque"] == pytest.approx(162.0910124, rel=1e-8)
    assert r["cycle_time"] == pytest.approx(speed_profile(paper_mechanism(), **TORQUE).cycle_time, rel=1e-12)


def test_cli_infeasible_and_bad_input(capsys):
    code, out, _ = cli(
        ["servo", "slider-crank", "--r2", "0.1", "--r3", "0.4", "--omega-max", "2", "--v-cut", "0.5"], capsys
    )
    assert code == 1 and "infeasible: the limits omega_max, v_cut cannot all hold" in out
    code, out, err = cli(["servo", "slider-crank", "--r2", "0.1", "--r3", "0.4", "--omega-max", "-3"], capsys)
    assert code == 1 and err.count("\n") == 1 and "omega_max must be positive" in err and "Traceback" not in err
    code, _, err = cli(["servo", "--omega-max", "10", "--n", "12"], capsys)
    assert code == 1 and err.count("\n") == 1 and "n (cells per turn)" in err


def test_readme_examples():
    p = speed_profile(INLINE, **CUT)
    assert (p.time_ratio, p.cycle_time, p.working_time) == pytest.approx((2.51495, 0.564075, 0.403596), abs=1e-5)
    q = speed_profile(paper_mechanism(), **TORQUE)
    assert (q.peak_torque, q.cycle_time) == pytest.approx((113.002, 0.519758), abs=1e-3)
    assert tuple(q.constant_speed()) == pytest.approx((0.483322, 1.5, 162.091), abs=1e-3)
    r = speed_profile(INLINE, omega_max=2, v_cut=0.5)
    assert r.binding == ("omega_max", "v_cut") and "78.3% off v_cut" in r.message


# ---- the full inertia (masses and loads) -----------------------------------------------------------------------
GENERAL = qropt.Loads(
    forces=[qropt.Force("C", 100.0, "against", "working")], torques=[qropt.Torque("rod", 0.5)], gravity=(3.0, -9.0)
)


@pytest.mark.parametrize("loads", [qropt.Loads(100.0, gravity=9.81), GENERAL], ids=["cut and gravity", "general"])
def test_a_profile_with_every_links_inertia_is_checked_by_the_inverse_dynamics(loads):
    """With a mass model the torque is M alpha2 + M' omega2^2 / 2 + Q, linear in omega2^2: the profile's torque at
    its samples equals the Newton-Euler inverse dynamics run at the same crank angle, speed and acceleration, and a
    binding torque limit holds to the profile's O(h^2) discretisation; under the cutting force and gravity, and
    under general loads (a force, a torque on the rod, a tilted gravity)."""
    m = qropt.SliderCrank(r2=0.1, r3=0.4, e=0.05)  # TR 1.04: the servo's working arc is the slow stroke
    masses = qropt.Masses.bars(2.0, 5.0)
    free = qropt.speed_profile(m, omega_max=20, v_cut=0.5, a_max=40, alpha_max=400, v_max=2, masses=masses, loads=loads)
    sp = qropt.speed_profile(
        m, omega_max=20, v_cut=0.5, a_max=40, alpha_max=400, v_max=2, masses=masses, loads=loads, torque_max=12.0
    )
    assert sp.status == "optimal" and free.peak_torque > 12.5 and sp.cycle_time > free.cycle_time
    s = sp.motion()
    k = slice(None, None, 7)
    inverse = [
        m.dynamics(np.array([t]), w, a, masses=masses, loads=loads).torque[0]
        for t, w, a in zip(s.theta[k], s.omega[k], s.alpha[k], strict=True)
    ]
    assert np.abs(np.array(inverse) - s.torque[k]).max() <= 1e-9 * np.abs(s.torque).max()
    assert abs(sp.check()["torque_max"]) < 1e-4  # binding, and held to the O(h^2) of the cells


def test_the_shorthands_are_the_massless_case_and_never_count_twice():
    m = qropt.SliderCrank(r2=0.1, r3=0.4, e=0.05)
    kw = dict(omega_max=20, v_cut=0.5, alpha_max=400, torque_max=10.1)
    short = qropt.speed_profile(m, force=100.0, **kw)
    full = qropt.speed_profile(m, loads=qropt.Loads(100.0), **kw)
    assert short.status == full.status == "optimal" and full.peak_torque == pytest.approx(short.peak_torque, rel=1e-9)
    assert full.cycle_time == pytest.approx(short.cycle_time, rel=1e-7)
    with pytest.raises(qropt.InvalidParameter, match="once"):
        qropt.speed_profile(m, force=200.0, loads=qropt.Loads(200.0), **kw)
    with pytest.raises(qropt.InvalidParameter, match="once"):
        qropt.speed_profile(m, inertia=0.1, masses=qropt.Masses.bars(2.0), **kw)
    with pytest.raises(qropt.InvalidParameter, match="friction"):
        qropt.speed_profile(m, loads=qropt.Loads(200.0, friction=0.1), **kw)
