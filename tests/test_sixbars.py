"""The two six-bar types (CouplerSlider, SlotRamShaper): each checked by an independent route.

- the exact analysis against the brute-force simulation of ``tests.brute`` (written from scratch: the cosine law at
  O4, a rotated unit vector for the coupler point, similar triangles for the slot-ram; dense sampling refined by
  brentq on a complex-step derivative; x, v, a by Richardson-extrapolated central differences);
- the slot-ram shaper's closed forms against the exact analysis;
- solve(): the closed forms' enumeration and family, a coupler-slider synthesis confirmed by the brute force, a
  design whose ram reverses twice refused; the bodies draw.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import qropt
from qropt.io import drawing
from qropt.synthesis import analytic
from tests import brute

TH_CHECK = np.array([0.3, 1.7, 2.9, 4.0, 5.5])  # crank angles (rad) where x, v, a are compared
OMEGA2 = 3.0


def _rel(a, b):
    return abs(a - b) / max(1.0, abs(b))


def _angle_diff(a, b):
    return abs((a - b + np.pi) % (2 * np.pi) - np.pi)


def _coupler_designs(n, seed):
    """n valid coupler sliders (crank-rocker and drag-link alternately) whose ram reverses once a turn (brute)."""
    rng = np.random.default_rng(seed)
    out = []
    while len(out) < n:
        r = rng.uniform(0.2, 1.0, 4)
        kind = ("crank-rocker", "drag-link")[len(out) % 2]
        i = 1 if kind == "crank-rocker" else 0
        r[i] = r.min() * rng.uniform(0.3, 0.95)
        p = {"r1": r[0], "r2": r[1], "r3": r[2], "r4": r[3], "r5": rng.uniform(0.2, 1.2) * r[2]}
        p.update(beta=rng.uniform(-math.pi, math.pi), h=rng.uniform(-0.5, 0.5), r6=1.0)
        p.update(sigma=rng.choice([-1.0, 1.0]), sigma_slider=rng.choice([-1.0, 1.0]))
        if qropt.grashof(*r).kind != kind:
            continue
        with np.errstate(invalid="ignore"):
            py = brute.sixbar_joints("coupler-slider", p, brute.TH)["P"][1]
        p["r6"] = float(np.abs(p["h"] - py).max() * rng.uniform(1.2, 3.0))
        if brute.sixbar_reversals("coupler-slider", p) != 1:
            continue
        out.append((p, qropt.CouplerSlider(**p)))
    return out


def _slot_ram_designs(n, seed):
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        r1 = rng.uniform(0.1, 1.0)
        p = {"r1": r1, "r2": r1 * rng.uniform(0.05, 0.9), "h": r1 * rng.uniform(0.1, 3.0)}
        out.append((p, qropt.SlotRamShaper(**p)))
    return out


DESIGNS = {"coupler-slider": _coupler_designs, "slot-ram-shaper": _slot_ram_designs}


# ---- the exact analysis against the brute force ------------------------------------------------------------------
@pytest.mark.parametrize("kind", list(DESIGNS))
def test_cycle_quantities_and_rates_match_brute_force(kind):
    """Dead centres, TR, stroke, gamma_min within 1e-9 (the brute force's brentq and bounded-Brent refinement of
    a 20000-point grid agrees to ~1e-13 here); x within 1e-12; v within 1e-8 and a within 1e-6, relative to
    max(1, |value|) at omega2 = 3 rad/s: Richardson-extrapolated central differences at step 1e-3 (measured worst
    ~2e-11 for v and ~4e-8 for a, their rounding error ~ 1e-16 |x| / step^2 omega2^2)."""
    for p, m in DESIGNS[kind](12, seed=11):
        t_max, t_min, x_max, x_min, tr, stroke, gamma = brute.sixbar_cycle(kind, p)
        d = m.dead_centres()
        assert d.reversals == 1
        assert _angle_diff(d.theta_max, t_max) < 1e-9 and _angle_diff(d.theta_min, t_min) < 1e-9, (p, d)
        scale = max(1.0, x_max - x_min)
        assert abs(d.x_max - x_max) < 1e-9 * scale and abs(d.x_min - x_min) < 1e-9 * scale
        assert _rel(m.time_ratio(), tr) < 1e-9, p
        assert _rel(m.stroke(), stroke) < 1e-9, p
        assert _rel(m.gamma_min().value, gamma) < 1e-9, p
        mo = m.motion(TH_CHECK, OMEGA2)
        x, v, a = brute.sixbar_motion(kind, p, TH_CHECK, OMEGA2)
        assert np.allclose(mo.x, x, rtol=1e-12, atol=1e-12)
        assert np.allclose(mo.v, v, rtol=1e-8, atol=1e-8), (p, mo.v, v)
        assert np.allclose(mo.a, a, rtol=1e-6, atol=1e-6), (p, mo.a, a)


def test_coupler_slider_transmission_angles_match_brute_force():
    """Both transmitting joints (B and D) at every crank angle of a grid, to rounding."""
    th = np.linspace(0, 2 * np.pi, 97)
    for p, m in _coupler_designs(6, seed=3):
        exact, ref = m.transmission_angles(th), brute.sixbar_transmissions("coupler-slider", p, th)
        assert set(exact) == {"B", "D"}
        for j in ("B", "D"):
            assert np.allclose(exact[j], ref[j], atol=1e-12)


# ---- the slot-ram shaper's closed forms ----------------------------------------------------------------------------
def test_slot_ram_shaper_closed_forms_match_exact_analysis():
    """TR = (pi + 2 asin(r2/r1)) / (pi - 2 asin(r2/r1)), stroke = 2 h r2 / sqrt(r1^2 - r2^2), gamma_min =
    acos(r2/r1), within 1e-12 relative, over random r1, r2 < r1 and h > 0 (the transmission minimum at D)."""
    rng = np.random.default_rng(5)
    for _ in range(40):
        r1 = rng.uniform(0.05, 5.0)
        r2, h = r1 * rng.uniform(0.02, 0.95), r1 * rng.uniform(0.05, 4.0)
        m = qropt.SlotRamShaper(r1=r1, r2=r2, h=h)
        b = math.asin(r2 / r1)
        assert _rel(m.time_ratio(), (math.pi + 2 * b) / (math.pi - 2 * b)) < 1e-12
        assert _rel(m.time_ratio(), analytic.crank_shaper_time_ratio(r1, r2)) < 1e-12
        assert abs(m.stroke() - 2 * h * r2 / math.sqrt(r1**2 - r2**2)) < 1e-12 * max(1.0, m.stroke())
        assert abs(m.stroke() - analytic.slot_ram_shaper_stroke(r1, r2, h)) < 1e-12 * max(1.0, m.stroke())
        g = m.gamma_min()
        assert abs(g.value - math.acos(r2 / r1)) < 1e-12 and g.joint == "D"
        assert abs(g.value - analytic.slot_ram_shaper_gamma_min(r1, r2)) < 1e-12


def test_slot_ram_shaper_rules_and_declarations():
    with pytest.raises(qropt.InvalidParameter, match="r2 < centres r1"):
        qropt.SlotRamShaper(r1=0.2, r2=0.25, h=0.3)
    with pytest.raises(qropt.InvalidParameter, match="h > 0"):
        qropt.SlotRamShaper(r1=0.2, r2=0.1, h=-0.3)
    m = qropt.SlotRamShaper(r1=0.2, r2=0.1, h=0.3)
    assert qropt.mechanism_type("slot-ram-shaper") is qropt.SlotRamShaper and m.output_joint() == "D"
    assert [b.kind for b in m.bodies()] == ["bar", "block", "slot-lever", "ram"]
    assert m.transmission_angles(np.array([1.0]))["A"][0] == pytest.approx(math.pi / 2)


def test_coupler_slider_declarations():
    m = qropt.CouplerSlider(r1=0.4, r2=0.1, r3=0.35, r4=0.3, r5=0.2, beta=-0.5, r6=0.6)
    assert qropt.mechanism_type("coupler-slider") is qropt.CouplerSlider and m.params["h"] == 0.0
    assert "beta" not in qropt.CouplerSlider.LENGTHS and m.grashof().kind == "crank-rocker"
    assert [(b.name, b.kind) for b in m.bodies()] == [
        ("crank", "bar"),
        ("coupler", "plate"),
        ("follower", "bar"),
        ("rod", "bar"),
        ("ram", "ram"),
    ]
    assert qropt.CouplerSlider(r1=0.1, r2=0.3, r3=0.35, r4=0.3, r5=0.2, beta=2.0, r6=0.9).grashof().kind == "drag-link"
    with pytest.raises(qropt.GrashofError, match="crank-rocker .* or drag-link"):
        qropt.CouplerSlider(r1=0.4, r2=0.3, r3=0.1, r4=0.35, r5=0.2, beta=0.5, r6=0.6)  # a double-rocker


# ---- solve -----------------------------------------------------------------------------------------------------
TR, STROKE = 1.6, 0.3


def _slot_ram_closed_form(r1):
    k = analytic.crank_shaper_ratio(TR)
    return k * r1, STROKE * math.sqrt(1 - k * k) / (2 * k)


def test_slot_ram_shaper_solve_by_enumeration():
    """r1 fixed, r2 and h free: the closed form's one design, certified, to 1e-9."""
    p = qropt.Problem(
        "slot-ram-shaper",
        fixed={"r1": 0.25},
        free={"r2": (0.01, 0.24), "h": (0.05, 2.0)},
        targets={"time_ratio": TR, "stroke": STROKE},
    )
    r = qropt.solve(p)
    assert r.status == "optimal" and r.stats["plan"] == "enumeration", r.message
    r2, h = _slot_ram_closed_form(0.25)
    assert abs(r.params["r2"] - r2) < 1e-9 and abs(r.params["h"] - h) < 1e-9
    m = r.mechanism
    assert _rel(m.time_ratio(), TR) < 1e-9 and _rel(m.stroke(), STROKE) < 1e-9


@pytest.mark.parametrize("size", ["sum", "longest"])
def test_slot_ram_shaper_min_size_takes_the_least_r1(size):
    """r1, r2, h free: the optima form a continuum along r1 (the motion depends on r2/r1 and h only); min_size
    returns its least-size end, the smallest r1 in bounds."""
    p = qropt.Problem(
        "slot-ram-shaper",
        free={"r1": (0.1, 0.5), "r2": (0.01, 0.5), "h": (0.05, 2.0)},
        targets={"time_ratio": TR, "stroke": STROKE},
        objective="min_size",
        size=size,
    )
    w = analytic.warm_starts(p)
    assert w.kind == "family" and len(w.points) == analytic.FAMILY_POINTS
    r = qropt.solve(p)
    assert r.status == "optimal" and r.stats["plan"] == "family", r.message
    r2, h = _slot_ram_closed_form(0.1)
    assert abs(r.params["r1"] - 0.1) < 1e-9 and abs(r.params["r2"] - r2) < 1e-9 and abs(r.params["h"] - h) < 1e-9
    assert _rel(r.mechanism.time_ratio(), TR) < 1e-9 and _rel(r.mechanism.stroke(), STROKE) < 1e-9


def test_coupler_slider_solve_is_certified_and_confirmed_by_brute_force():
    """A crank-rocker (r1..r4, r6, h fixed) with the coupler point's r5 and beta free meets TR 1.5 and stroke 0.3:
    the certified design's TR and stroke agree with the brute force to 1e-9 and the targets to 1e-6."""
    p = qropt.Problem(
        "coupler-slider",
        fixed={"r1": 0.4, "r2": 0.1, "r3": 0.35, "r4": 0.3, "r6": 0.6, "h": 0.0},
        free={"r5": (0.05, 0.6), "beta": (-math.pi, math.pi)},
        targets={"time_ratio": 1.5, "stroke": 0.3},
    )
    r = qropt.solve(p)
    assert r.status == "optimal" and r.certificate is not None, r.message
    q = {**r.params}
    _, _, _, _, tr, stroke, gamma = brute.sixbar_cycle("coupler-slider", q)
    assert brute.sixbar_reversals("coupler-slider", q) == 1
    assert _rel(r.mechanism.time_ratio(), tr) < 1e-9 and _rel(r.mechanism.stroke(), stroke) < 1e-9
    assert abs(tr - 1.5) < 1e-6 and abs(stroke - 0.3) < 1e-6
    assert _rel(r.quantities["gamma_min"], gamma) < 1e-9


# the coupler slider without closed forms: free parameters of fixed shapes, and the design row (all eight free)
_FOURBAR = {"r1": 0.4, "r2": 0.1, "r3": 0.35, "r4": 0.3, "r6": 0.6, "h": 0.0}
COUPLER_TASKS = {
    "r4, r5, beta": ({k: v for k, v in _FOURBAR.items() if k != "r4"}, {"r4": (0.2, 0.45)}),
    "r3, r4, r5, beta": (
        {k: v for k, v in _FOURBAR.items() if k not in ("r3", "r4")},
        {"r3": (0.2, 0.5), "r4": (0.2, 0.45)},
    ),
}


@pytest.mark.parametrize("task", [*COUPLER_TASKS, "design row"])
def test_coupler_slider_default_solve_finds_what_a_large_multistart_finds(task):
    """The default solve (a grid screen of rule points for its starts, more starts the more parameters are free)
    reaches the best gamma_min of a multi-start eight times as large, and its certificate says it rests on a
    multi-start; the design row's (whose shape is in the atlas) starts from the atlas and reaches the best of a
    256-start multi-start without it."""
    if task == "design row":
        from qropt.studies._design import type_problem

        p = type_problem("coupler-slider", 1.5, 0.3)
    else:
        fixed, free = COUPLER_TASKS[task]
        p = qropt.Problem(
            "coupler-slider",
            fixed=fixed,
            free={**free, "r5": (0.05, 0.6), "beta": (-math.pi, math.pi)},
            targets={"time_ratio": 1.5, "stroke": 0.3},
        )
    r = qropt.solve(p)
    assert r.status == "optimal", r.message
    if task == "design row":  # a design row's shape is in the atlas: its designs start the solve
        assert "designs of the atlas" in r.certificate.global_claim
        big = qropt.Solver(starts_n=64, seed=5, atlas=False).solve(p)  # 256 starts, without the atlas
    else:
        assert "distinct local optima from" in r.certificate.global_claim
        big = qropt.Solver(starts_n=8 * r.stats["starts"], seed=5).solve(p)
    assert big.status == "optimal", big.message
    assert r.objective >= big.objective - 1e-7, (r.objective, big.objective)
    q = dict(r.params)
    _, _, _, _, tr, stroke, gamma = brute.sixbar_cycle("coupler-slider", q)
    assert abs(tr - 1.5) < 1e-6 and abs(stroke - 0.3) < 1e-6 and _rel(r.objective, gamma) < 1e-9


def test_no_sampled_design_that_turns_is_no_proof_of_infeasibility():
    """At TR 2.4 the coupler slider's default solve may not reach the gamma_min optimum, but designs exist (one
    is checked by brute force here): the solve says 'failed' and names a design, never 'infeasible'."""
    from qropt.studies._design import type_problem

    p = type_problem("coupler-slider", 2.4, 0.2)
    r = qropt.solve(p)
    assert r.status in ("optimal", "acceptable", "failed"), r.message
    if r.status == "failed":
        shown = r.message.split("(one: ")[1].split(")")[0]
        q = {k: float(v) for k, v in (kv.split("=") for kv in shown.split(", "))}
        _, _, _, _, tr, stroke, _ = brute.sixbar_cycle("coupler-slider", {**q, "sigma": -1.0, "sigma_slider": 1.0})
        assert abs(tr - 2.4) < 1e-4 and abs(stroke - 0.2) < 1e-4


@pytest.mark.parametrize("kind", ["slot-ram-shaper", "crank-shaper"])
def test_a_continuum_of_optima_is_broken_by_the_least_size(kind):
    """The motion depends on r2/r1, so every design of the closed-form family has the same gamma_min: the design
    row returns the least footprint of a dense scan of the family over r1 (to 1e-6)."""
    tr, s = 1.6, 0.3
    row = qropt.design(tr, s, types=[kind]).rows[0].result
    assert row.status == "optimal", row.message
    assert "continuum along r1" in row.message
    lo, hi = (s / 20, 5 * s)
    k = analytic.crank_shaper_ratio(tr)
    sizes, gammas = [], []
    for r1 in np.geomspace(lo, hi, 4001):
        q = {"r1": r1, "r2": k * r1}
        q |= {"h": s * math.sqrt(1 - k * k) / (2 * k)} if kind == "slot-ram-shaper" else {"r4": s / (2 * k)}
        if not all(lo <= v <= hi for n, v in q.items() if n != "h"):
            continue
        m = qropt.mechanism_type(kind)(**q)
        sizes.append(m.size("footprint"))
        gammas.append(m.gamma_min().value)
    assert max(gammas) - min(gammas) < 1e-9 and abs(row.objective - gammas[0]) <= 2e-9  # the tie: 1e-9 relative
    assert row.quantities["size"] <= min(sizes) * (1 + 1e-6), (row.quantities["size"], min(sizes))
    # where the footprint is flat along the family, the largest r1 of the least footprint (to a scan step)
    least = [r1 for r1, size in zip(_family_r1(kind, tr, s), sizes, strict=True) if size <= min(sizes) * (1 + 1e-9)]
    assert row.params["r1"] >= max(least) * (1 - 2e-3)


def _family_r1(kind, tr, s):
    """The r1 of the closed-form family's designs inside the bounds, in the order of the test above."""
    lo, hi = (s / 20, 5 * s)
    k = analytic.crank_shaper_ratio(tr)
    out = []
    for r1 in np.geomspace(lo, hi, 4001):
        q = {"r1": r1, "r2": k * r1}
        q |= {"h": s * math.sqrt(1 - k * k) / (2 * k)} if kind == "slot-ram-shaper" else {"r4": s / (2 * k)}
        if all(lo <= v <= hi for n, v in q.items() if n != "h"):
            out.append(r1)
    return out


@pytest.mark.parametrize("kind", ["crank-shaper-rod", "whitworth"])
def test_the_least_peak_acceleration_of_a_continuum_takes_its_least_size(kind):
    """By min_peak_accel too, the crank shaper with a rod and the Whitworth (whose least-size solves under a
    bound at the optimum end at degenerate designs) take the least size of the continuum: r1 and r2 of the tie-free
    optimum scaled together by one factor, the same motion (TR, stroke and peak acceleration by the tests' own
    simulation), a smaller footprint, and none smaller nearby along the continuum."""
    from qropt.studies._design import type_problem
    from qropt.synthesis import search
    from qropt.synthesis.search.least_size import LeastSize
    from qropt.synthesis.solver import Solver

    p = type_problem(kind, 2.373, 2.3207, objective="min_peak_accel")
    row = Solver().solve(p)
    assert row.status == "optimal" and "scaled together" in row.message, row.message
    tied = Solver(pipeline=[s for s in search.DEFAULT if not isinstance(s, LeastSize)]).solve(p)
    assert row.params["r2"] / row.params["r1"] == pytest.approx(tied.params["r2"] / tied.params["r1"], rel=1e-9)
    assert row.quantities["size"] < tied.quantities["size"]
    assert abs(row.objective - tied.objective) <= 2e-9 * abs(tied.objective)
    mech = row.mechanism.KIND  # the row's mechanism (the crank shaper's, with its rod)
    tr, stroke, _ = brute.task_values(mech, dict(row.params))
    assert (tr, stroke) == pytest.approx((2.373, 2.3207), abs=1e-8)
    th, h = np.linspace(0, 2 * np.pi, 7200, endpoint=False), 1e-3  # the whole turn (accel_over "cycle")
    x = [brute.output(mech, dict(row.params), th + k * h) for k in (-1, 0, 1)]
    a = (x[0] - 2 * x[1] + x[2]) / h**2  # error about 1e-7 of the peak
    assert np.max(np.abs(a)) == pytest.approx(row.quantities["peak_accel"], rel=1e-4)
    for f in (0.98, 0.995):  # smaller along the continuum: a larger footprint, or no design
        q = {**row.params, "r1": f * row.params["r1"], "r2": f * row.params["r2"]}
        try:
            bigger = qropt.mechanism_type(mech)(**q).size("footprint")
        except qropt.QroptError:
            continue
        assert bigger >= row.quantities["size"] * (1 - 1e-9)


# a crank-rocker whose coupler point (r5 = 1.169 at beta = 1.796 rad) folds the ram's x-motion: two reversals a turn
TWICE = {"r1": 0.996, "r2": 0.365, "r3": 0.568, "r4": 0.806, "r5": 1.169, "beta": 1.796, "r6": 5.0, "h": 0.0}


def test_a_ram_that_reverses_twice_has_no_time_ratio_and_is_never_a_solution():
    m = qropt.CouplerSlider(**TWICE)
    assert m.dead_centres().reversals == 2
    assert brute.sixbar_reversals("coupler-slider", {**TWICE, "sigma": -1.0}) == 2
    with pytest.raises(qropt.NoDeadCentres, match="reverses 2 times"):
        m.time_ratio()
    fixed = {k: v for k, v in TWICE.items() if k != "r6"}
    for targets in ({"stroke": m.stroke()}, {"stroke": m.stroke(), "time_ratio": 1.2}):
        r = qropt.solve(qropt.Problem("coupler-slider", fixed=fixed, free={"r6": (4.9, 5.1)}, targets=targets))
        assert r.status != "optimal" and not r.success, r.message


# ---- bodies and pictures ---------------------------------------------------------------------------------------
def test_bodies_fit_the_joints_and_draw(tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from qropt.io.plots import cycle_figure

    cs = qropt.CouplerSlider(r1=0.4, r2=0.1, r3=0.35, r4=0.3, r5=0.46, beta=-2.72, r6=0.6)
    srs = qropt.SlotRamShaper(r1=0.25, r2=0.0887, h=0.3955)
    for m in (cs, srs):
        bodies, ground, out = drawing.check(m)
        assert ground == ("O2", "O4") and out == "D" and bodies[0].joints == ("O2", "A")
        fig = cycle_figure(m)
        fig.savefig(tmp_path / f"{m.KIND}.png", dpi=50)
        plt.close(fig)
        assert (tmp_path / f"{m.KIND}.png").stat().st_size > 0
    # the slot-ram shaper's lever reaches D at its farthest: max(r1 + r2, h r1 / sqrt(r1^2 - r2^2)) (the contract)
    sc = drawing.scene(srs, 3601)
    r1, r2, h = (srs.params[k] for k in ("r1", "r2", "h"))
    assert sc.reach["lever"] == pytest.approx(max(r1 + r2, h * r1 / math.sqrt(r1 * r1 - r2 * r2)), rel=1e-5)
