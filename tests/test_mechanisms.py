"""Every type against the independent brute-force simulation, finite differences and CasADi AD."""

from __future__ import annotations

import casadi
import numpy as np
import pytest

from qropt.kinematics.closures import transmission_angle, transmission_cos
from qropt.kinematics.ops import CASADI
from tests import brute
from tests.randmech import KINDS, random_mechanisms

N_RANDOM = 120


def _rel(a, b):
    return abs(a - b) / max(1.0, abs(b))


def _angle_diff(a, b):
    return abs((a - b + np.pi) % (2 * np.pi) - np.pi)


@pytest.mark.parametrize("kind", KINDS)
def test_cycle_quantities_match_brute_force(kind):
    for p, m in random_mechanisms(kind, N_RANDOM, seed=1):
        t_max, t_min, x_max, x_min = brute.dead_centres(kind, p)
        d = m.dead_centres()
        scale = max(1.0, x_max - x_min)
        assert _angle_diff(d.theta_max, t_max) < 1e-9, (p, d, t_max)
        assert _angle_diff(d.theta_min, t_min) < 1e-9, (p, d, t_min)
        assert abs(d.x_max - x_max) < 1e-9 * scale and abs(d.x_min - x_min) < 1e-9 * scale
        assert _rel(m.stroke(), x_max - x_min) < 1e-9
        assert _rel(m.time_ratio(), brute.time_ratio(t_max, t_min)) < 1e-9
        assert _rel(m.gamma_min().value, brute.gamma_min(kind, p)) < 1e-9, p


@pytest.mark.parametrize("kind", KINDS)
def test_gamma_min_is_a_lower_bound_attained(kind):
    for _, m in random_mechanisms(kind, 50, seed=2):
        g = m.gamma_min()
        th = np.linspace(0, 2 * np.pi, 5001)
        sampled = min(v.min() for v in m.transmission_angles(th).values())
        assert g.value <= sampled + 1e-12
        at = m.transmission_angles(np.array([g.theta2]))
        assert abs(at[g.joint][0] - g.value) < 1e-14


def _richardson(f, th, h):
    """First and second derivatives of f at th by Richardson-extrapolated central differences (O(h^4))."""

    def d1(k):
        return (f(th + k) - f(th - k)) / (2 * k)

    def d2(k):
        return (f(th + k) - 2 * f(th) + f(th - k)) / k**2

    return (4 * d1(h / 2) - d1(h)) / 3, (4 * d2(h / 2) - d2(h)) / 3


@pytest.mark.parametrize("kind", KINDS)
def test_rates_match_finite_differences(kind):
    h = 1e-3
    for _, m in random_mechanisms(kind, N_RANDOM, seed=3):
        th = np.linspace(0.1, 2 * np.pi - 0.1, 17)
        w, al = 7.0, -3.0
        mo = m.motion(th, w, al)
        dx, ddx = _richardson(lambda t, m=m: m.positions(t).x, th, h)
        np.testing.assert_allclose(mo.v, dx * w, rtol=1e-7, atol=1e-9 * w)
        np.testing.assert_allclose(mo.a, ddx * w * w + dx * al, rtol=1e-5, atol=1e-7 * w * w)
        for k in mo.angles:
            da, _ = _richardson(lambda t, k=k, m=m: np.unwrap(m.positions(t).angles[k]), th, h)
            np.testing.assert_allclose(mo.omega[k], da * w, rtol=1e-7, atol=1e-9 * w)


def _casadi_derivatives(m):
    t = casadi.SX.sym("t")
    lp = m.loop(CASADI, t, m.params)
    outs = [lp.x] + list(lp.angles.values())
    jac = [casadi.jacobian(o, t) for o in outs]
    hes = [casadi.jacobian(j, t) for j in jac]
    return casadi.Function("d", [t], [casadi.vertcat(*outs), casadi.vertcat(*jac), casadi.vertcat(*hes)])


@pytest.mark.parametrize("kind", KINDS)
def test_rates_match_casadi_ad(kind):
    for _, m in random_mechanisms(kind, N_RANDOM, seed=4):
        f = _casadi_derivatives(m)
        for th in np.linspace(0.05, 2 * np.pi - 0.05, 5):
            val, d1, d2 = (np.array(v).ravel() for v in f(th))
            mo = m.motion(th, 1.0, 0.0)
            jets = [(mo.x[0], mo.v[0], mo.a[0])]
            jets += [(mo.angles[k][0], mo.omega[k][0], mo.alpha[k][0]) for k in mo.angles]
            for i, (v0, v1, v2) in enumerate(jets):
                assert abs(np.cos(val[i]) - np.cos(v0)) < 1e-12 and abs(np.sin(val[i]) - np.sin(v0)) < 1e-12
                assert abs(d1[i] - v1) < 1e-9 * max(1.0, abs(v1))
                assert abs(d2[i] - v2) < 1e-8 * max(1.0, abs(v2))


@pytest.mark.parametrize("kind", KINDS)
def test_numpy_and_casadi_namespaces_agree(kind):
    from qropt.kinematics.ops import NUMPY

    for _, m in random_mechanisms(kind, 40, seed=5):
        t = casadi.SX.sym("t")
        ps = {k: casadi.SX.sym(k) for k in m.params}
        lp = m.loop(CASADI, t, ps)
        names = list(lp.points)
        flat = [lp.x] + [c for k in names for c in lp.points[k]] + list(lp.angles.values())
        flat += [f(CASADI, v) for v in lp.transmission.values() for f in (transmission_angle, transmission_cos)]
        flat += [mg for _, mg in lp.margins]
        f = casadi.Function("f", [t, *ps.values()], [casadi.vertcat(*[casadi.SX(v) for v in flat])])
        for th in np.linspace(0.0, 2 * np.pi, 13):
            sym = np.array(f(th, *m.params.values())).ravel()
            ln = m.loop(NUMPY, th, m.params)
            num = [ln.x] + [c for k in names for c in ln.points[k]] + list(ln.angles.values())
            num += [f(NUMPY, v) for v in ln.transmission.values() for f in (transmission_angle, transmission_cos)]
            num += [mg for _, mg in ln.margins]
            np.testing.assert_allclose(sym, np.array(num, float), rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("kind", KINDS)
def test_positions_close_every_loop(kind):
    for p, m in random_mechanisms(kind, 30, seed=6):
        th = np.linspace(0, 2 * np.pi, 101)
        pos = m.positions(th)
        ref = brute.joints(kind, p, th)
        for name in ("A", "B", "C", "D"):
            if name in pos.points and name in ref and not (kind == "slider-crank" and name == "C"):
                np.testing.assert_allclose(pos.points[name][:, 0], np.real(ref[name][0]), atol=1e-12)
                np.testing.assert_allclose(pos.points[name][:, 1], np.real(ref[name][1]), atol=1e-12)
        if kind == "slider-crank":
            np.testing.assert_allclose(pos.points["C"][:, 0], np.real(ref["D"][0]), atol=1e-12)


def _brute_accel(kind, p, th, h=2e-4):
    """d2x/dtheta2: central differences of the complex-step derivative, Richardson-extrapolated (error ~h^4)."""

    def d(step):
        xp = np.imag(brute.output(kind, p, th + step + 1j * brute.STEP)) / brute.STEP
        xm = np.imag(brute.output(kind, p, th - step + 1j * brute.STEP)) / brute.STEP
        return (xp - xm) / (2 * step)

    return (4 * d(h / 2) - d(h)) / 3


def _grid_peak(f, th):
    """Largest |f| on the grid, refined by bounded Brent around the best sample."""
    from scipy.optimize import minimize_scalar

    k = int(np.argmax(np.abs(f(th))))
    h = th[1] - th[0]
    r = minimize_scalar(
        lambda t: -abs(float(f(np.array([t]))[0])),
        bounds=(th[k] - h, th[k] + h),
        method="bounded",
        options={"xatol": 1e-12},
    )
    return -r.fun


@pytest.mark.parametrize("kind", [k for k in KINDS if k != "four-bar"])
def test_peak_acceleration_matches_brute_force(kind):
    for p, m in random_mechanisms(kind, 20, seed=3):
        brute_peak = _grid_peak(lambda t, p=p: _brute_accel(kind, p, t), brute.TH)
        peak = m.peak_acceleration(1.0)
        assert abs(peak.value - brute_peak) <= 1e-6 * max(1.0, brute_peak), (p, peak, brute_peak)
        assert abs(peak.value - abs(m.motion(peak.theta2).a[0])) <= 1e-12 * max(1.0, peak.value)
        w = m.peak_acceleration(3.0, over="working")
        assert w.value <= 9.0 * peak.value * (1 + 1e-12)
        start, length = m.working_arc(3.0)
        assert (w.theta2 - start) % (2 * np.pi) <= length + 1e-12


@pytest.mark.parametrize("kind", [k for k in KINDS if k != "four-bar"])
def test_peak_working_velocity_matches_brute_force(kind):
    for p, m in random_mechanisms(kind, 20, seed=5):
        start, length = m.working_arc(2.0)
        th = start + length * np.linspace(0.0, 1.0, 20001)

        def v(t, p=p):
            return np.imag(brute.output(kind, p, t + 1j * brute.STEP)) / brute.STEP

        brute_peak = _grid_peak(v, th)
        pv = m.peak_velocity(-2.0)
        assert abs(pv.torque_per_newton - brute_peak) <= 1e-9 * max(1.0, brute_peak), (p, pv, brute_peak)
        assert pv.value == pytest.approx(2.0 * pv.torque_per_newton, rel=1e-15)
        assert (pv.theta2 - start) % (2 * np.pi) <= length + 1e-12
        assert abs(abs(m.motion(pv.theta2, 2.0).v[0]) - pv.value) <= 1e-12 * max(1.0, pv.value)


@pytest.mark.parametrize("kind", KINDS)
def test_bounding_box_matches_brute_force(kind):
    for p, m in random_mechanisms(kind, 20, seed=4):
        j = brute.joints(kind, p, brute.TH)
        pts = [v for k, v in j.items() if k in ("A", "B", "C", "D")] + [(np.zeros(1), np.zeros(1))]
        if kind in ("crank-shaper", "whitworth"):
            pts.append((np.zeros(1), np.full(1, -p["r1"])))
        else:
            pts.append((np.full(1, p.get("r1", 0.0)), np.zeros(1)))
        xs = np.concatenate([np.real(x) for x, _ in pts])
        ys = np.concatenate([np.real(y) for _, y in pts])
        b = m.bounding_box()
        tol = 1e-7 * max(1.0, xs.max() - xs.min())
        assert b.x_min <= xs.min() + 1e-12 and b.x_max >= xs.max() - 1e-12
        assert abs(b.x_min - xs.min()) < tol and abs(b.x_max - xs.max()) < tol, (p, b)
        assert abs(b.y_min - ys.min()) < tol and abs(b.y_max - ys.max()) < tol, (p, b)


def test_extremes_closer_than_a_grid_step_are_each_found():
    """A crank shaper whose rod nears its reach: the ram has two equal maxima 0.08 rad apart with a dip of 5e-6 m
    between, so the 180-angle grid's bracket around the first holds the dip too. Every stationary point is found,
    as the tests' own simulation finds it: the design reverses twice a turn (the solver once returned it as a
    design reversing once, at TR 1.116 and 1.871 m)."""
    from scipy.optimize import brentq

    import qropt

    p = {"r1": 7.037198129315969, "r2": 0.7454177884015692, "r4": 8.831666533384407}
    p.update({"r6": 0.5761765854962286, "h": 9.354999999993968, "sigma_slider": 1.0})
    m = qropt.CrankShaper(**p)
    dx = np.imag(brute.output("crank-shaper", p, brute.TH + 1j * brute.STEP)) / brute.STEP
    cells = np.flatnonzero(np.sign(dx) != np.sign(np.roll(dx, -1)))
    roots = [
        brentq(lambda t: brute._dx("crank-shaper", p, t), brute.TH[i], brute.TH[i] + 2 * np.pi / brute.N, xtol=1e-15)
        for i in cells
    ]
    (tmax, _), (tmin, _) = m._cycle["max"], m._cycle["min"]
    assert m.dead_centres().reversals == 2 == tmax.size == tmin.size
    assert np.sort(np.concatenate([tmax, tmin])) == pytest.approx(np.sort(roots), abs=1e-9)
    assert max(roots) - min(r for r in roots if r > 6) < 0.09


def test_a_turn_back_inside_a_stroke_smaller_than_a_dwell_is_not_a_reversal():
    """cycle.dwells: a maximum and the minimum next to it that differ by less than DWELL of the travel, both inside
    it, are a dwell; a deeper turn back, or one at an end of the travel, is a reversal. A coupler slider's
    gamma_min optimum at TR 2.601, 0.9457 m turns back by 3.2e-6 m over 0.037 rad inside its return stroke (the
    tests' own simulation finds the four stationary points): it reverses once, with the simulation's TR and
    stroke from the global extremes."""
    from scipy.optimize import brentq

    import qropt
    from qropt.kinematics import cycle

    t, lo = np.array([0.5, 4.0]), np.array([3.0, 4.5])  # up to 1 at 0.5 rad, down to 0 at 3, up again (a turn back)
    inside = (t, np.array([1.0, 0.4]), lo, np.array([0.0, 0.4 - 0.5 * cycle.DWELL]))
    assert [a.size for a in cycle.dwells(*inside)] == [1, 1, 1, 1]
    deeper = (t, np.array([1.0, 0.4]), lo, np.array([0.0, 0.4 - 2 * cycle.DWELL]))
    assert [a.size for a in cycle.dwells(*deeper)] == [2, 2, 2, 2]
    at_top = (t, np.array([1.0, 1.0]), lo, np.array([0.0, 1.0 - 0.5 * cycle.DWELL]))
    assert [a.size for a in cycle.dwells(*at_top)] == [2, 2, 2, 2]
    p = {"r1": 1.198195584921906, "r2": 0.3769383314548465, "r3": 0.9622750056248027, "r4": 0.849400025476614}
    p.update({"r5": 4.728499999994298, "beta": 2.113737677334493, "r6": 3.58055534523629, "h": 1.084165444556271})
    p.update({"sigma": -1.0, "sigma_slider": 1.0})

    def dx(th):
        return np.imag(brute.sixbar_x("coupler-slider", p, th + 1j * brute.STEP)) / brute.STEP

    d = dx(brute.TH)
    cells = np.flatnonzero(np.sign(d) != np.sign(np.roll(d, -1)))
    roots = sorted(brentq(dx, brute.TH[i], brute.TH[i] + 2 * np.pi / brute.N, xtol=1e-15) for i in cells)
    x = np.real(brute.sixbar_x("coupler-slider", p, np.array(roots)))
    assert len(roots) == 4 and 2e-6 < np.abs(np.diff(x)).min() < 1e-5 * (x.max() - x.min())
    m = qropt.CouplerSlider(**p)
    assert m.dead_centres().reversals == 1
    b_tr, b_stroke, _ = brute.task_values("coupler-slider", p)
    assert (m.time_ratio(), m.stroke()) == pytest.approx((b_tr, b_stroke), abs=1e-9)
    assert (b_tr, b_stroke) == pytest.approx((2.601, 0.9457), abs=1e-8)


def test_of_equal_transmission_minima_the_first_found_is_named():
    """A centred slider-crank has its least transmission angle at theta2 = pi/2 and 3 pi/2, exactly equal: the
    first refined minimum is named (as numpy's argmin did), not the smaller crank angle."""
    import qropt

    m = qropt.SliderCrank(r2=0.1, r3=0.3, e=0.0)
    t, v = m._cycle["gamma"]["C"]
    assert v.size == 2 and v[0] == v[1]
    assert m.gamma_min().theta2 == t[0]
    swapped = {"C": (t[::-1].copy(), v[::-1].copy())}
    m.__dict__.pop("_gamma_min")  # the cached value, computed again from the minima in the other order
    m.__dict__["_cycle"] = {**m._cycle, "gamma": swapped}
    assert m.gamma_min().theta2 == t[1]


def test_mechanisms_results_and_comparisons_pickle():
    """A mechanism pickles as its type, parameters and unit (rebuilt and checked when loaded): every type, a
    unit other than metres, a Result with its local optima and a design() comparison (for another process)."""
    import pickle

    import qropt
    from qropt.examples import paper_problem
    from qropt.mechanisms import TYPES

    for cls in TYPES:
        _, m = random_mechanisms(cls.KIND, 1, seed=41)[0]
        back = pickle.loads(pickle.dumps(m))
        assert back == m and type(back) is type(m)
        assert back.gamma_min() == m.gamma_min() and back.dead_centres() == m.dead_centres()
    mm = qropt.SliderCrank(r2=100.0, r3=350.0, e=20.0, units="mm")
    assert pickle.loads(pickle.dumps(mm)).units == "mm"
    r = qropt.solve(paper_problem())
    b = pickle.loads(pickle.dumps(r))
    assert (b.status, b.params, b.objective, b.mechanism) == (r.status, r.params, r.objective, r.mechanism)
    assert [o.params for o in b.local_optima] == [o.params for o in r.local_optima]
    c = qropt.design(1.5, 0.3, types=["slider-crank", "whitworth"])
    d = pickle.loads(pickle.dumps(c))
    assert d.markdown() == c.markdown()
    # and a problem, as its plain values: a dynamic one in mm, and one of a type of one's own
    from qropt.studies._design import type_problem
    from tests.test_bodies import PlateSlider

    masses, loads = qropt.Masses.steel(4e-4, ram=20.0), qropt.Loads(1000.0)
    for p in (
        type_problem(
            "drag-link-slider", 1.5, 300.0, objective="min_peak_torque", masses=masses, loads=loads, units="mm"
        ),
        type_problem(PlateSlider, 1.5, 0.3, conditions={"gamma_min": 0.5}),
    ):
        q = pickle.loads(pickle.dumps(p))
        assert q == p and q.to_dict() == p.to_dict()
