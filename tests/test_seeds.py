"""Seed 001 (crank-and-slotted-lever lab rig) and seed 002 (vector-loop position analysis)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from qropt import AssemblyError, CrankShaper, FourBar
from qropt.synthesis import analytic

# Seed 001, Table 1: crank angle q (deg) -> theoretical slider position (mm).
SEED001 = [
    70.00,
    78.36,
    86.58,
    94.53,
    102.08,
    109.07,
    115.36,
    120.77,
    125.12,
    128.21,
    129.82,
    129.71,
    127.65,
    123.39,
    116.79,
    107.81,
    96.66,
    83.80,
    70.00,
    56.20,
    43.34,
    32.19,
    23.21,
    16.61,
    12.35,
    10.29,
    10.18,
    11.79,
    14.88,
    19.23,
    24.64,
    30.93,
    37.92,
    45.47,
    53.42,
    61.64,
    70.00,
]


def rig():
    """Crank OB 40 mm, centres OA 160 mm, lever AC 240 mm, yoke-driven slider."""
    return CrankShaper(r1=160.0, r2=40.0, r4=240.0)


def seed_x(m, q_deg):
    """The seed's q is measured from the line of centres away from the lever pivot and turns clockwise
    in qropt's frame (theta2 = 90 deg - q); its scale reads 70 mm at mid-stroke."""
    return 70.0 + m.slider(np.radians(90.0 - np.asarray(q_deg, float))).x


def test_seed001_table_to_001_mm():
    x = seed_x(rig(), np.arange(0, 361, 10))
    np.testing.assert_allclose(x, SEED001, atol=0.005 + 1e-9)


def test_seed001_seed_formula_is_the_same_model():
    # the seed's own recipe: a = atan(40 sin q / (160 + 40 cos q)), X = 70 + 240 sin a
    q = np.radians(np.arange(0, 361, 1.0))
    a = np.arctan(40 * np.sin(q) / (160 + 40 * np.cos(q)))
    np.testing.assert_allclose(seed_x(rig(), np.degrees(q)), 70 + 240 * np.sin(a), atol=1e-12)


def test_seed001_exact_extremes_stroke_and_time_ratio():
    m = rig()
    d = m.dead_centres()
    # The seed's "maximum 129.82 mm / minimum 10.18 mm" are its 10-degree samples; the extremes are exact:
    assert 70 + d.x_max == pytest.approx(130.0, abs=1e-12)
    assert 70 + d.x_min == pytest.approx(10.0, abs=1e-12)
    assert m.stroke() == pytest.approx(120.0, abs=1e-12)
    # They occur where the lever is tangent to the crank circle, q = 90 +/- asin(40/160) = 104.48 / 255.52 deg
    # (the seed reads "between 100 and 110" and "260").
    q_max = (90.0 - math.degrees(d.theta_max)) % 360
    q_min = (90.0 - math.degrees(d.theta_min)) % 360
    assert q_max == pytest.approx(90 + math.degrees(math.asin(0.25)), abs=1e-9)
    assert q_min == pytest.approx(270 - math.degrees(math.asin(0.25)), abs=1e-9)
    # Stroke angles: the seed says 200 deg cutting / 160 deg return (TR 1.25) from 10-degree samples;
    # exactly they are 208.955 / 151.045 deg, TR 1.38340.
    a, b = sorted(np.degrees(m.stroke_angles()))[::-1]
    assert a == pytest.approx(208.95502437, abs=1e-7) and b == pytest.approx(151.04497563, abs=1e-7)
    assert m.time_ratio() == pytest.approx(1.3833960613578, abs=1e-12)
    assert m.time_ratio() == pytest.approx(analytic.crank_shaper_time_ratio(160, 40), abs=1e-13)
    # the seed turns the crank clockwise (q increasing): its cutting stroke, q = 260 -> 360 -> 100 deg,
    # raises the reading from 10 to 130 mm (+x); turned counter-clockwise the slow stroke is -x
    assert m.working_direction(omega2=-1.0) == "+x" and m.working_direction(omega2=1.0) == "-x"
    assert m.gamma_min().value == pytest.approx(math.pi / 2, abs=0)


def test_seed001_dense_grid_agrees():
    # independent check of the exact values on a 0.001-degree grid with the seed's own formula
    q = np.radians(np.arange(0, 360, 0.001))
    x = 70 + 240 * np.sin(np.arctan(40 * np.sin(q) / (160 + 40 * np.cos(q))))
    assert x.max() == pytest.approx(130.0, abs=1e-6) and x.min() == pytest.approx(10.0, abs=1e-6)
    span = (np.degrees(q[np.argmin(x)]) - np.degrees(q[np.argmax(x)])) % 360
    assert span == pytest.approx(151.04497563, abs=2e-3)


A, B, C, D = 1.6, 2.14, 2.06, 3.5


def vector_loop_residual(t2, t3, t4):
    # a e^{i t2} + b e^{i t3} - c e^{i t4} - d = 0 (seed 002, slide 13)
    return A * np.exp(1j * t2) + B * np.exp(1j * t3) - C * np.exp(1j * t4) - D


def test_seed002_open_and_crossed():
    t2 = math.radians(51.3)
    open_ = FourBar(r1=D, r2=A, r3=B, r4=C, sigma=-1).positions(t2).angles
    crossed = FourBar(r1=D, r2=A, r3=B, r4=C, sigma=+1).positions(t2).angles
    # The seed prints the open solution as theta3 = 21 deg, theta4 = 104 deg (rounded).
    assert math.degrees(open_["theta3"][0]) == pytest.approx(21, abs=0.5)
    assert math.degrees(open_["theta4"][0]) == pytest.approx(104, abs=0.5)
    for s in (open_, crossed):
        assert abs(vector_loop_residual(t2, s["theta3"][0], s["theta4"][0])) < 1e-14
    assert math.degrees(open_["theta3"][0]) == pytest.approx(20.5386742, abs=1e-6)
    assert math.degrees(open_["theta4"][0]) == pytest.approx(103.9220584, abs=1e-6)
    assert math.degrees(crossed["theta3"][0]) % 360 == pytest.approx(286.3722050, abs=1e-6)
    assert math.degrees(crossed["theta4"][0]) % 360 == pytest.approx(202.9888207, abs=1e-6)


def test_seed002_grashof_and_toggles():
    m = FourBar(r1=D, r2=A, r3=B, r4=C)
    g = m.grashof()
    assert g.kind == "non-Grashof" and g.s_plus_l == pytest.approx(5.1) and g.p_plus_q == pytest.approx(4.2)
    toggles = m.toggle_positions()
    assert [k for _, k in toggles] == ["extended", "extended"]
    t = math.degrees(math.acos((A * A + D * D - (B + C) ** 2) / (2 * A * D)))
    assert [math.degrees(x) for x, _ in toggles] == pytest.approx([t, 360 - t], abs=1e-10)
    assert t == pytest.approx(104.636073037, abs=1e-8)
    # independent: the loop stops closing exactly there (dense scan of the vector-loop condition)
    q = np.radians(np.arange(0, 360, 1e-4))
    reach = np.hypot(A * np.cos(q) - D, A * np.sin(q)) <= B + C
    edges = np.degrees(q[np.flatnonzero(reach != np.roll(reach, 1))])
    assert sorted(edges) == pytest.approx([t, 360 - t], abs=2e-4)
    fails = m.assembly_failures()
    assert len(fails) == 1 and math.degrees(fails[0][1]) == pytest.approx(t, abs=1e-9)
    assert math.degrees(fails[0][2]) == pytest.approx(360 - t, abs=1e-9)
    # transmission angle is zero at the toggle
    assert m.transmission_angles(np.array([toggles[0][0]]))["B"][0] == pytest.approx(0, abs=1e-6)
    with pytest.raises(AssemblyError, match="104.6361, 255.3639"):
        m.time_ratio()
