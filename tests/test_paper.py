"""The paper's drag-link project (seed 003/000): Tables 2 and 5, eqs. (2)-(5), (7)-(13), (14)-(17)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from qropt import DragLinkSlider
from qropt.synthesis import analytic
from tests import brute

R1, R2, R4, R5, R6 = 0.1, 0.225, 0.275, 0.15, 0.3
TABLE4_R3 = 0.2504  # the coupler length GNLINK was given (Table 4), rounded from the closed form


def exact_r3():
    return analytic.drag_link_r3(1.5, R1, R2, R4)[1].r3


def paper(r3):
    return DragLinkSlider(r1=R1, r2=R2, r3=r3, r4=R4, r5=R5, r6=R6)


def table5(r3):
    """GNLINK's Table 5 quantities at theta2 = 60 deg, omega2 = 10 rad/s, alpha2 = 0."""
    s = paper(r3).slider(math.radians(60), 10.0, 0.0)
    # GNLINK's vector 6 points from D to C; qropt's theta6 points from C to D.
    return {
        "theta3": s.angles["theta3"][0],
        "omega3": s.omega["theta3"][0],
        "alpha3": s.alpha["theta3"][0],
        "theta4": s.angles["theta4"][0],
        "omega4": s.omega["theta4"][0],
        "alpha4": s.alpha["theta4"][0],
        "theta6": s.angles["theta6"][0] + math.pi,
        "omega6": s.omega["theta6"][0],
        "alpha6": s.alpha["theta6"][0],
        "L7": s.x[0] - R1,  # slider length O4D
        "L7dot": s.v[0],
        "L7ddot": s.a[0],
    }


# Table 5 as printed (4 significant figures).
TABLE5 = {
    "theta3": -0.3247,
    "omega3": 7.566,
    "alpha3": -51.18,
    "theta4": 0.4313,
    "omega4": 11.69,
    "alpha4": -45.41,
    "theta6": 2.931,
    "omega6": -5.430,
    "alpha6": 44.00,
    "L7": 0.4296,
    "L7dot": -1.074,
    "L7ddot": -21.67,
}


def half_ulp(printed):
    """Half a unit in the last of the 4 significant figures the table prints."""
    return 0.5 * 10 ** (math.floor(math.log10(abs(printed))) - 3)


def test_closed_form_r3_of_eqs_7_to_13():
    sols = analytic.drag_link_r3(1.5, R1, R2, R4)
    assert len(sols) == 2
    # The paper prints theta2a = 6.18 or 39.38 deg; eq. (12) gives 7.177 and 40.386 deg (both 1 deg off).
    assert math.degrees(sols[0].theta2a) == pytest.approx(7.177143877989, abs=1e-9)
    assert math.degrees(sols[1].theta2a) == pytest.approx(40.386290262083, abs=1e-9)
    # The paper prints r3 = 0.1544 m; the exact value rounds to 0.1543 m.
    assert sols[0].r3 == pytest.approx(0.154344486256, abs=1e-11)
    assert round(sols[1].r3, 4) == 0.2504
    for s in sols:  # independent check: the brute-force simulation gives TR 1.5 and stroke 2 r5
        p = {"r1": R1, "r2": R2, "r3": s.r3, "r4": R4, "r5": R5, "r6": R6, "h": 0.0, "sigma": -1.0, "sigma_slider": 1.0}
        t_max, t_min, x_max, x_min = brute.dead_centres("drag-link-slider", p)
        assert brute.time_ratio(t_max, t_min) == pytest.approx(1.5, abs=1e-12)
        assert x_max - x_min == pytest.approx(0.3, abs=1e-12)


def test_table5_with_table4_length_to_printed_precision():
    got = table5(TABLE4_R3)
    for k, printed in TABLE5.items():
        assert abs(got[k] - printed) <= half_ulp(printed) * (1 + 1e-9), (k, got[k], printed)


def test_table5_with_exact_closed_form_r3():
    # With the exact r3 = 0.2504281 (not GNLINK's 0.2504) four entries move by one printed unit:
    # theta3 -0.3248, omega3 7.567, theta4 0.4312, L7dot -1.073 (the paper: -0.3247, 7.566, 0.4313, -1.074).
    got = table5(exact_r3())
    for k, printed in TABLE5.items():
        assert abs(got[k] - printed) <= 3 * half_ulp(printed), (k, got[k], printed)
    assert got["L7dot"] == pytest.approx(-1.0734016916, abs=1e-9)
    assert got["L7ddot"] == pytest.approx(-21.674892980, abs=1e-8)


def test_table2_velocity_magnitudes():
    # Table 2 was measured on a velocity polygon; the exact values are 0.1-0.2 % below it.
    r3 = TABLE4_R3
    got = table5(r3)
    exact = {
        "B/A": abs(got["omega3"]) * r3,
        "B": abs(got["omega4"]) * R4,
        "C": abs(got["omega4"]) * R5,
        "D/C": abs(got["omega6"]) * R6,
        "D": abs(got["L7dot"]),
    }
    printed = {"B/A": 1.898, "B": 3.219, "C": 1.756, "D/C": 1.631, "D": 1.075}
    for k in printed:
        assert exact[k] == pytest.approx(printed[k], rel=2.5e-3), k
    assert exact["B/A"] == pytest.approx(1.894608, abs=1e-6)
    assert exact["D"] == pytest.approx(1.073671, abs=1e-6)
    # Table 3's normal components |V|^2 / length (printed 14.39, 37.68, 8.87 m/s^2) follow from Table 2's
    # polygon velocities; from the exact velocities they are 14.335, 37.587, 8.846 m/s^2.
    assert printed["B/A"] ** 2 / r3 == pytest.approx(14.39, abs=0.005)
    assert printed["B"] ** 2 / R4 == pytest.approx(37.68, abs=0.005)
    assert printed["D/C"] ** 2 / R6 == pytest.approx(8.87, abs=0.005)
    assert exact["B/A"] ** 2 / r3 == pytest.approx(14.3352, abs=1e-4)
    assert exact["B"] ** 2 / R4 == pytest.approx(37.5873, abs=1e-4)
    assert exact["D/C"] ** 2 / R6 == pytest.approx(8.8460, abs=1e-4)


def test_eqs_2_to_5_time_ratio_and_stroke():
    for r3 in (exact_r3(), 0.2, 0.3, 0.35):
        m = paper(r3)
        assert analytic.paper_time_ratio(R1, R2, r3, R4) == pytest.approx(m.time_ratio(), abs=1e-12)
        t2a, t2b = analytic.paper_dead_centre_angles(R1, R2, r3, R4)
        d = m.dead_centres()
        # theta2a, theta2b are unsigned triangle angles: on branch sigma = -1 the crank sits at +t2a (TDC)
        assert d.theta_max == pytest.approx(t2a, abs=1e-12)
        assert d.theta_min == pytest.approx(math.pi + t2b, abs=1e-12)
        assert m.stroke() == pytest.approx(2 * R5, abs=1e-15)  # "stroke = 2 * O4C"


def test_eqs_14_to_17_are_dead_centre_values_not_gamma_min():
    lo, hi = analytic.drag_link_r3(1.5, R1, R2, R4)
    g_lo = analytic.paper_transmission_at_dead_centres(R1, R2, lo.r3, R4)
    g_hi = analytic.paper_transmission_at_dead_centres(R1, R2, hi.r3, R4)
    # Paper: min(10.49, 85.94) = 10.47 deg (a misprint: the minimum is 10.49) and min(35.60, 60.83) = 35.60.
    assert np.degrees(g_lo) == pytest.approx([10.49, 85.94], abs=0.005)
    assert np.degrees(g_hi) == pytest.approx([35.60, 60.83], abs=0.005)
    for sol, at_dc in ((lo, g_lo), (hi, g_hi)):
        m = paper(sol.r3)
        d = m.dead_centres()
        tb = m.transmission_angles(np.array([d.theta_max, d.theta_min]))["B"]
        np.testing.assert_allclose(tb, at_dc, atol=1e-12)
        # the true minimum over the turn is lower, where the crank is collinear with the ground
        g = m.gamma_min()
        assert g.joint == "B" and min(g.theta2, 2 * math.pi - g.theta2) < 1e-9
        c = (sol.r3**2 + R4**2 - (R2 - R1) ** 2) / (2 * sol.r3 * R4)  # cosine law at theta2 = 0
        assert g.value == pytest.approx(math.acos(c), abs=1e-12)
        assert g.value < min(at_dc)
    assert math.degrees(paper(hi.r3).gamma_min().value) == pytest.approx(27.008204639, abs=1e-8)
    assert math.degrees(paper(lo.r3).gamma_min().value) == pytest.approx(9.094927743, abs=1e-8)


def test_grashof_feasible_coupler_range():
    # "values of r3 in the range 0.1500 m <= r3 <= 0.4000 m yield drag-link mechanisms"
    from qropt import grashof

    assert grashof(R1, R2, 0.15, R4).kind == "change-point"
    assert grashof(R1, R2, 0.40, R4).kind == "change-point"
    assert grashof(R1, R2, 0.2, R4).kind == "drag-link"
    assert grashof(R1, R2, 0.149, R4).kind == "non-Grashof"
    assert grashof(R1, R2, 0.401, R4).kind == "non-Grashof"


@pytest.mark.parametrize("tr", [1.2, 1.5, 2.0, 2.5])
def test_every_stroke_triangle_design_meets_its_task(tr):
    """The offset slider-crank's stroke triangle, over cranks from 1/60 to 2/3 of the stroke: every design it
    returns meets the TR and stroke by brute force, and a crank it returns nothing for has a triangle whose
    folded dead centre falls behind O2 (x_max < stroke), where the slider cannot follow it."""
    stroke, returned = 0.3, 0
    for r2 in np.geomspace(0.005, 0.2, 40):
        designs = analytic.slider_crank_design(tr, stroke, r2)
        for d in designs:
            q = {"r2": d.r2, "r3": d.r3, "e": d.e, "sigma_slider": 1.0}
            t_max, t_min, x_max, x_min = brute.dead_centres("slider-crank", q)
            assert brute.time_ratio(t_max, t_min) == pytest.approx(tr, abs=1e-9)
            assert x_max - x_min == pytest.approx(stroke, abs=1e-9)
            returned += 1
        if not designs:  # the triangle itself, solved here independently
            phi = math.pi * (tr - 1) / (tr + 1)
            low = max(np.roots([2 * (1 - math.cos(phi)), 4 * r2 * (1 - math.cos(phi)), 4 * r2 * r2 - stroke**2]).real)
            high = low + 2 * r2
            e = high * low * math.sin(phi) / stroke
            assert low <= 0 or abs(e) >= low or high * high - e * e < stroke * stroke
    assert returned >= 2  # the window of valid cranks narrows as TR grows
