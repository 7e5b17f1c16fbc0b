"""Families, reachable ranges and adjustable links against closed forms and dense scans."""

from __future__ import annotations

import importlib
import math

import numpy as np
import pytest
from scipy.optimize import brentq, minimize_scalar

from qropt import DragLinkSlider, Problem, ProblemError, grashof
from qropt.examples import paper_mechanism
from qropt.studies._family import family
from qropt.studies._reachable import reachable
from qropt.synthesis import analytic
from tests import brute

R2, R4 = 0.225, 0.275


@pytest.fixture(scope="module")
def paper_family():
    return family(importlib.import_module("problems.paper_family_r1_r3").build())


def closed_form_r3(r1):
    """Eq. (12) at r1 (TR 1.5), kept where the linkage is a Grashof drag-link (equality allowed)."""
    out = []
    for s in analytic.drag_link_r3(1.5, r1, R2, R4):
        g = grashof(r1, R2, s.r3, R4)
        if g.kind in ("drag-link", "change-point") and g.shortest == "r1" and 0.05 <= s.r3 <= 0.6:
            out.append(s.r3)
    return out


def _interp(points, x_key, y_key, x):
    """Cubic through the 4 traced points nearest to x in x_key (valid where x_key is monotone there)."""
    xs = np.array([p.params[x_key] for p in points])
    k = int(np.argmin(np.abs(xs - x)))
    idx = list(range(max(0, k - 2), min(len(points), k + 2)))
    return np.polyval(np.polyfit(xs[idx] - x, [points[i].params[y_key] for i in idx], len(idx) - 1), 0.0)


def test_traced_points_lie_on_the_closed_form(paper_family):
    pts = paper_family.points()
    assert len(paper_family.branches) == 1 and len(pts) > 500
    for p in pts:
        roots = closed_form_r3(p.params["r1"])
        if not roots:  # only the singular end (the change point), where eq. (12)'s root is a Grashof equality
            assert p.params["r1"] - paper_family.ends[0].params["r1"] < 1e-6
            continue
        assert min(abs(p.params["r3"] - r) for r in roots) < 1e-8
    # every point solves the lifted equations (dead-centre velocities, TR) to 1e-10
    assert max(p.residual for p in pts) <= 1e-10
    # the exact TR (paper's eq. 5, and the brute-force simulator) to 1e-10 away from the singular end: within
    # 1e-6 of the change point the dead-centre equations lose their conditioning (there TR error ~1e-9)
    end = paper_family.ends[0].params["r1"]
    far = [p for p in pts if p.params["r1"] - end > 1e-6 or abs(p.params["r3"] - 0.1327) > 1e-3]
    assert len(far) > len(pts) - 40  # the tracer creeps up to the singular end by halving its step
    for p in far:
        assert analytic.paper_time_ratio(p.params["r1"], R2, p.params["r3"], R4) == pytest.approx(1.5, abs=1e-10)
    for p in far[::40]:
        assert analytic.paper_time_ratio(p.params["r1"], R2, p.params["r3"], R4) == pytest.approx(1.5, abs=1e-10)
        t = brute.dead_centres("drag-link-slider", p.params)
        assert brute.time_ratio(t[0], t[1]) == pytest.approx(1.5, abs=1e-10)


def test_closed_form_points_lie_on_the_traced_curve_without_gaps(paper_family):
    pts = paper_family.points()
    fold_r1 = paper_family.folds[0]["r1"]
    ds = max(
        np.linalg.norm([a.params["r1"] - b.params["r1"], a.params["r3"] - b.params["r3"]])
        for a, b in zip(pts[:-1], pts[1:], strict=True)
    )
    for r1 in np.linspace(0.0827, 0.1106, 300):
        for r3 in closed_form_r3(r1):
            # nearest traced point within one step, and the local cubic through the trace meets it
            d = min(math.hypot(p.params["r1"] - r1, p.params["r3"] - r3) for p in pts)
            assert d <= ds
            k = min(range(len(pts)), key=lambda i: math.hypot(pts[i].params["r1"] - r1, pts[i].params["r3"] - r3))
            branch = pts[max(0, k - 3) : k + 4]
            if abs(r1 - fold_r1) > 1e-3:
                assert abs(_interp(branch, "r1", "r3", r1) - r3) < 1e-8
            else:
                assert abs(_interp(branch, "r3", "r1", r3) - r1) < 1e-8
    ends = {e.reason.split(":")[0] for e in paper_family.ends}
    assert ends == {"bound", "singularity at a Grashof change point (grashof drag-link"}


def test_fold_matches_the_discriminant(paper_family):
    r1_fold = brentq(lambda r1: analytic.drag_link_discriminant(1.5, r1, R2, R4), 0.1, 0.2, xtol=1e-15)
    assert len(paper_family.folds) == 1
    assert paper_family.folds[0]["r1"] == pytest.approx(r1_fold, abs=1e-8)
    assert r1_fold == pytest.approx(0.110698047380, abs=1e-11)


def test_family_best_is_refined_by_solve(paper_family):
    best = paper_family.best("max_gamma_min")
    assert best.success
    # every sampled family point has a smaller gamma_min (brute force on a subsample)
    for p in paper_family.points()[::60]:
        assert brute.gamma_min("drag-link-slider", p.params) <= best.objective + 1e-9


def test_reachable_range_of_the_paper_linkage():
    r = reachable(paper_mechanism(), "r3")
    # independent: Grashof interval and a dense scan of the paper's eq. (5)
    assert len(r.intervals) == 1
    assert r.intervals[0][0] == pytest.approx(0.15, abs=1e-9) and r.intervals[0][1] == pytest.approx(0.40, abs=1e-9)
    r3 = np.linspace(0.15, 0.40, 250001)[1:-1]
    tr = np.array([analytic.paper_time_ratio(0.1, R2, x, R4) for x in r3])
    tr = np.append(tr, analytic.paper_time_ratio(0.1, R2, 0.4, R4))  # the change point itself
    lo, at_lo, hi, at_hi = r.time_ratio_range
    assert lo == pytest.approx(tr.min(), abs=1e-6) and hi == pytest.approx(tr.max(), abs=1e-6)
    assert at_lo == pytest.approx(r3[np.argmin(tr[:-1])], abs=1e-5)
    # the paper prints 1.430 <= TR <= 5.538; the upper value is a misprint for 3.538
    assert round(lo, 3) == 1.430 and round(hi, 3) == 3.538
    # discussion issue (1): zero, one or two designs per TR
    assert r.count(1.5) == 2 and r.count(1.42) == 0 and r.count(2.0) == 1 and r.count(1.55) == 2
    assert r.solutions(1.5) == pytest.approx([s.r3 for s in analytic.drag_link_r3(1.5, 0.1, R2, R4)], abs=1e-10)


def test_adjustable_coupler_for_every_reachable_time_ratio():
    r = reachable(paper_mechanism(), "r3")
    lo, at_lo, hi, _ = r.time_ratio_range
    a = r.adjustable(lo, hi)
    assert a.interval[0] == pytest.approx(at_lo, abs=1e-9) and a.interval[1] == pytest.approx(0.4, abs=1e-9)
    a = r.adjustable(1.5, 2.5)
    tr = [analytic.paper_time_ratio(0.1, R2, x, R4) for x in a.interval]
    assert tr == pytest.approx([1.5, 2.5], abs=1e-9)
    assert "once" in a.explanation and a.gamma_min > 0
    with pytest.raises(Exception, match="reachable"):
        r.adjustable(1.2, 1.3)


def test_second_type_family_offset_slider_crank():
    p = Problem(
        "SliderCrank",
        free={"r2": (0.05, 0.149), "r3": (0.1, 2.0), "e": (-0.8, 0.8)},
        targets={"time_ratio": 1.3, "stroke": 0.3},
    )
    f = family(p)
    assert len(f.branches) == 2  # e > 0 and its mirror e < 0
    signs = sorted(np.sign(b[len(b) // 2].params["e"]) for b in f.branches)
    assert signs == [-1, 1]
    for b in f.branches:
        for q in b:
            d = analytic.slider_crank_design(1.3, 0.3, q.params["r2"])
            assert d, q.params
            assert q.params["r3"] == pytest.approx(d[0].r3, abs=1e-8)
            assert abs(q.params["e"]) == pytest.approx(d[0].e, abs=1e-8)
        r2s = [q.params["r2"] for q in b]
        assert min(r2s) == pytest.approx(0.05, abs=1e-12) and max(r2s) == pytest.approx(0.149, abs=1e-12)
        for q in b[:: max(1, len(b) // 10)]:
            t = brute.dead_centres("slider-crank", q.params)
            assert brute.time_ratio(t[0], t[1]) == pytest.approx(1.3, abs=1e-10)
            assert t[2] - t[3] == pytest.approx(0.3, abs=1e-10)


def test_family_needs_one_spare_parameter():
    p = importlib.import_module("problems.paper_drag_link").build()
    with pytest.raises(ProblemError, match="one more free parameter than targets"):
        family(p)


def test_reachable_bad_input():
    m = DragLinkSlider(r1=0.1, r2=R2, r3=0.25, r4=R4, r5=0.15, r6=0.3)
    with pytest.raises(Exception, match="no continuous parameter"):
        reachable(m, "sigma")
    with pytest.raises(Exception, match="give bounds for r5"):
        reachable(m, "r5")


@pytest.mark.parametrize("tr", [1.1, 1.5, 2.2, 2.848, 2.967, 2.986])
def test_the_slider_crank_window_is_where_the_stroke_triangle_gives_a_design(tr):
    """The family's window (bisection) against a dense scan of cranks: every crank of the scan inside it gives a
    slider-crank, none outside; at high TR the window is a sliver of the bounds (0.47-0.5 strokes at TR 2.85,
    0.497-0.5 at TR 2.986, where the triangle's last test fails by rounding 1e-12 below half the stroke)."""
    stroke, lo, hi = 0.834, 0.0417, 4.17
    a, b = analytic.slider_crank_window(tr, stroke, lo, hi)
    scan = np.geomspace(lo, hi, 20001)
    gives = np.array([bool(analytic.slider_crank_design(tr, stroke, float(r2))) for r2 in scan])
    inside = (scan >= a) & (scan <= b)
    assert np.array_equal(gives, inside)
    assert stroke / 2 * (1 - 1e-9) <= b < stroke / 2


def _peak_accel(p, omega2=1.0):
    """The slider's largest |acceleration| by the tests' own simulation: the complex-step velocity's central
    difference on a dense grid, the largest refined by bounded Brent."""
    h = 1e-6

    def accel(t):
        return abs(brute._dx("slider-crank", p, t + h) - brute._dx("slider-crank", p, t - h)) / (2 * h) * omega2**2

    grid = brute.TH[::4]
    values = [accel(float(t)) for t in grid]
    k = int(np.argmax(values))
    step = grid[1] - grid[0]
    best = minimize_scalar(lambda t: -accel(t), bounds=(grid[k] - step, grid[k] + step), method="bounded")
    return -best.fun


def test_a_slider_crank_near_a_toggle_is_refined_along_its_family():
    """At TR 2.848, stroke 0.834 m every slider-crank passes within half a degree of a toggle: IPOPT ends without a
    design from every point of the family, and the bounded 1-D search along it gives the least peak acceleration.
    Checked against a dense scan of the family (2,001 cranks in its window, each design's exact peak) and by the
    tests' own simulation (TR, stroke, peak)."""
    from qropt import Solver
    from qropt.studies import type_problem

    p = type_problem("slider-crank", 2.848, 0.834, objective="min_peak_accel")
    r = Solver().solve(p)
    assert r.status == "optimal", r.message
    assert "1-D search of the exact objective along the family's r2" in r.certificate.global_claim
    a, b = analytic.slider_crank_window(2.848, 0.834, *p.free["r2"])
    scan = []
    for r2 in np.geomspace(a, b, 2003)[1:-1]:
        d = analytic.slider_crank_design(2.848, 0.834, float(r2))[0]
        scan.append(type(r.mechanism)(r2=d.r2, r3=d.r3, e=d.e).peak_acceleration(1.0).value)
    assert r.objective <= min(scan) * (1 + 1e-9)
    assert r.objective >= min(scan) * (1 - 1e-3)  # the scan's spacing
    params = dict(r.mechanism.params)
    t_max, t_min, x_max, x_min = brute.dead_centres("slider-crank", params)
    assert brute.time_ratio(t_max, t_min) == pytest.approx(2.848, abs=1e-8)
    assert x_max - x_min == pytest.approx(0.834, abs=1e-9)
    assert brute.gamma_min("slider-crank", params) < math.radians(0.5)
    assert _peak_accel(params) == pytest.approx(r.objective, rel=1e-6)


def test_a_guarded_types_curve_checks_the_velocity_mid_stroke():
    """A family's curve holds the design's rows (the free parameters and the dead centres): for a type whose output
    may reverse more than once a turn (the coupler slider), also the output velocity mid-stroke of each stroke's
    sign, which its NLP holds by lifted turn-backs instead. Its values are the exact velocity there."""
    from qropt import Solver
    from qropt.studies._design import type_problem
    from qropt.studies._family import _Curve

    p = type_problem("coupler-slider", 2.185, 0.567)
    r = Solver().solve(p)
    branch = {k: r.params[k] for k in p.branches}
    curve = _Curve(p.replace(objective=None), branch, r.stats["orientation"], Solver())
    names = [row.name for row in curve.ineq_rows]
    mid = [i for i, n in enumerate(names) if "mid-stroke" in n]
    assert len(mid) == 2 and not any("turn-back" in n for n in names)
    d = r.mechanism.dead_centres()
    t0, t1 = d.theta_max, d.theta_min if d.theta_min > d.theta_max else d.theta_min + 2 * math.pi
    u = np.array([r.params[k] for k in curve.free] + [t0, t1])
    _, _, g = curve.eval(u)
    fall = t1 - t0
    v = np.ravel(r.mechanism.slider(np.array([t0 + 0.5 * fall, t1 + 0.5 * (2 * math.pi - fall)])).v)
    assert g[mid] == pytest.approx(v, rel=1e-9, abs=1e-12)
    assert v[0] < 0 < v[1] and curve.violation(g)[0] <= 1e-9
