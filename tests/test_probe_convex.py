"""Bad input to the convex layer found by a hostile probe, as a checklist: each case gives a typed qropt error
naming the problem, or a result with a status and a clear reason; never a bare Python exception. Also the
Mechanism methods the convex layer now relies on (sensitivity with kinks, nearby, working_angle_at)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import qropt
from qropt import cli as qropt_cli
from qropt.convex.servo import speed_profile
from qropt.convex.tolerance import allocate, sensitivities
from qropt.errors import QroptError
from qropt.examples import paper_mechanism

INLINE = qropt.SliderCrank(r2=0.1, r3=0.4)  # TR = 1: the time ratio's kink
SC = qropt.SliderCrank(r2=0.1, r3=0.35, e=0.06)
FOUR_BAR = qropt.FourBar(r1=0.4, r2=0.1, r3=0.35, r4=0.3)


# ---- the Python API: typed errors -----------------------------------------------------------------------
def _profile():
    return speed_profile(paper_mechanism(), omega_max=12.0, v_max=1.5)


def _allocation():
    return allocate(SC, {"time_ratio": 0.01})


RAISES = [
    ("servo omega_max 1e300 overflows", lambda: speed_profile(SC, omega_max=1e300), "omega_max = 1e\\+300 is out"),
    ("servo v_max 1e-300 underflows", lambda: speed_profile(SC, omega_max=10, v_max=1e-300), "v_max = 1e-300 is out"),
    ("servo refuses a FourBar", lambda: speed_profile(FOUR_BAR, omega_max=10.0), "needs a slider output"),
    ("plot into a directory", lambda: _profile().plot("."), "is a directory"),
    ("plot to an unknown format", lambda: _profile().plot("x.xyz"), "picture formats are .png"),
    ("plot without an extension", lambda: _profile().plot("picture"), "picture formats are .png"),
    ("plot into a missing directory", lambda: _profile().plot("no/such/dir/p.png"), "does not exist"),
    ("plot to a non-path", lambda: _profile().plot(5), "must be a str or path-like"),
    ("weights span 1e300", lambda: allocate(SC, {"time_ratio": 0.01}, weights={"r2": 1e300}), "weights span"),
    ("weights not a mapping", lambda: allocate(SC, {"time_ratio": 0.01}, weights=[1, 2]), "weights must be a"),
    ("bounds not a mapping", lambda: allocate(SC, {"time_ratio": 0.01}, bounds=[(0, 1)]), "bounds must be a"),
    (
        "all-zero bounds",
        lambda: allocate(SC, {"time_ratio": 0.01}, bounds={p: (0, 0) for p in ("r2", "r3", "e")}),
        "upper bound must be positive",
    ),
    ("sensitivities of params=5", lambda: sensitivities(SC, params=5), "params must be a parameter name"),
    ("sensitivities of params={}", lambda: sensitivities(SC, params={"r2": 1}), "params must be a parameter name"),
    ("monte carlo seed -1", lambda: _allocation().monte_carlo(100, seed=-1), "seed must be a non-negative"),
    ("monte carlo seed 'x'", lambda: _allocation().monte_carlo(100, seed="x"), "seed must be a non-negative"),
    ("monte carlo seed 1.5", lambda: _allocation().monte_carlo(100, seed=1.5), "seed must be a non-negative"),
    ("monte carlo seed True", lambda: _allocation().monte_carlo(100, seed=True), "seed must be a non-negative"),
    ("sensitivity of an unknown quantity", lambda: SC.sensitivity("speed"), "unknown quantity 'speed'"),
    ("peak acceleration sensitivity without omega2", lambda: SC.sensitivity("peak_acceleration"), "omega2"),
    ("nearby with a wrong row length", lambda: SC.nearby(np.ones((3, 2))), "one row of"),
    ("nearby with nan", lambda: SC.nearby(np.full((1, 4), np.nan)), "finite"),
    ("working angle outside the stroke", lambda: SC.working_angle_at(10.0), "within the stroke"),
]


@pytest.mark.parametrize("case, call, match", RAISES, ids=[c[0] for c in RAISES])
def test_bad_input_gives_a_typed_error(case, call, match):
    with pytest.raises(QroptError, match=match):
        call()


def test_tiny_alpha_max_gives_constant_speed():
    # constant omega_max meets alpha_max = 1e-9 (alpha2 = 0): the envelope is the optimum, found without a solver
    p = speed_profile(paper_mechanism(), omega_max=20.0, alpha_max=1e-9)
    assert p.status == "optimal" and "envelope" in p.message
    assert p.cycle_time == pytest.approx(2 * math.pi / 20.0, rel=1e-12)
    np.testing.assert_allclose(p.omega, 20.0, rtol=1e-15)


def test_tiny_v_max_gives_the_closed_form_profile():
    m = paper_mechanism()
    p = speed_profile(m, omega_max=20.0, v_max=1e-9)
    assert p.status == "optimal"
    xp = np.abs(m.motion(p.theta, 1.0, 0.0).v)
    with np.errstate(divide="ignore"):
        np.testing.assert_allclose(p.omega, np.minimum(20.0, 1e-9 / xp), rtol=1e-12)
    assert p.cycle_time > 2 * m.stroke() / 1e-9 * 0.99  # the stroke out and back at <= 1e-9 length/s


def test_badly_scaled_limits_that_the_solver_cannot_meet_say_why():
    p = speed_profile(paper_mechanism(), omega_max=20.0, alpha_max=1e-9, a_max=50.0)
    assert p.status in ("failed", "optimal", "acceptable")
    if p.status == "failed":  # CLARABEL gives up on coefficients of 1e13: the message says which limit is tiny
        assert "badly scaled" in p.message and "alpha_max = 1e-09" in p.message


def test_equal_huge_weights_are_only_ratios():
    a = allocate(SC, {"time_ratio": 0.01}, weights={"r2": 1e300, "r3": 1e300, "e": 1e300})
    b = allocate(SC, {"time_ratio": 0.01})
    assert a.status == "optimal"
    assert a.tolerances == pytest.approx(b.tolerances, rel=1e-10)


# ---- kinks: TR of the in-line slider-crank at e = 0 -------------------------------------------------------
def tr(e):
    return qropt.SliderCrank(r2=0.1, r3=0.4, e=e).time_ratio()


def test_time_ratio_kink_gives_both_one_sided_derivatives():
    s = sensitivities(INLINE)
    assert "time_ratio" in s.kinks and "TR = 1" in s.kinks["time_ratio"]
    h = 1e-7
    right, left = (tr(h) - 1.0) / h, (1.0 - tr(-h)) / h
    assert right > 0 > left  # TR = 1 is its least: it grows either way
    assert s.right["time_ratio"]["e"] == pytest.approx(right, rel=1e-5)
    assert s.left["time_ratio"]["e"] == pytest.approx(left, rel=1e-5)
    assert abs(s["time_ratio"]["e"]) == pytest.approx(right, rel=1e-5)  # the steeper slope, for the stack-up
    assert not sensitivities(SC).kinks  # an offset slider-crank is smooth


def test_allocation_and_monte_carlo_report_the_kink():
    a = allocate(INLINE, {"time_ratio": 0.01, "stroke": 0.001})
    assert a.status == "optimal" and "time_ratio" in a.kinks and "kink" in a.message
    mc = a.monte_carlo(2000, seed=0, progress=False)
    assert "time_ratio" in mc.kinks and "kink" in repr(mc)
    assert np.all(mc.deviations["time_ratio"] >= -1e-12)  # TR >= 1 near the kink: never below the nominal
    # the first-order model at the kink is |S dp| (not S dp): its error is second order
    assert mc.linearisation["time_ratio"] < 0.05 * 0.01
    assert mc.deviations["time_ratio"].max() <= 0.01 + mc.linearisation["time_ratio"]


# ---- the Mechanism methods the convex layer uses --------------------------------------------------------
@pytest.mark.parametrize("m", [paper_mechanism(), SC, qropt.CrankShaper(r1=0.3, r2=0.1, r4=0.5, r6=0.4, h=0.45)])
def test_working_angle_at_inverts_the_output(m):
    start, length = m.working_arc()
    th = start + length * np.array([0.0, 0.1, 0.5, 0.9, 1.0])
    x = m.positions(th).x
    got = m.working_angle_at(x)
    np.testing.assert_allclose(got, th, atol=1e-9)
    np.testing.assert_allclose(m.positions(got).x, x, atol=1e-14 * m.stroke())


def test_nearby_equals_the_per_mechanism_analysis():
    m = SC
    rng = np.random.default_rng(0)
    scale = np.array([0.0 if k.startswith("sigma") else 1e-3 for k in m.params])  # branch signs stay +-1
    P = np.array(list(m.params.values()))[None, :] * (1 + scale * rng.uniform(-1, 1, (20, len(m.params))))
    qs = ("time_ratio", "stroke", "gamma_min", "peak_acceleration")
    got = m.nearby(P, qs, omega2=10.0)
    for j, row in enumerate(P):
        mm = type(m)(**dict(zip(m.params, row, strict=True)))
        want = [mm.time_ratio(), mm.stroke(), mm.gamma_min().value, mm.peak_acceleration(10.0).value]
        np.testing.assert_allclose(got[:, j], want, rtol=1e-11)


# ---- the command line: one line and a nonzero exit ------------------------------------------------------
SLIDER = ["slider-crank", "--r2", "0.1", "--r3", "0.35", "--e", "0.06"]
CLI_ERRORS = [
    ("servo omega-max 1e300", ["servo", *SLIDER, "--omega-max", "1e300"], 1, "omega_max = 1e+300 is out of range"),
    (
        "servo four-bar",
        ["servo", "four-bar", "--r1", "0.4", "--r2", "0.1", "--r3", "0.35", "--r4", "0.3", "--omega-max", "10"],
        1,
        "needs a slider output",
    ),
    ("servo plot format", ["servo", *SLIDER, "--omega-max", "10", "--plot", "p.xyz"], 2, "picture formats"),
    ("servo plot directory", ["servo", *SLIDER, "--omega-max", "10", "--plot", "."], 2, "is a directory"),
    (
        "tolerance seed -1",
        ["tolerance", "--limit", "time_ratio=0.01", "--monte-carlo", "10", "--seed", "-1"],
        1,
        "seed must be a non-negative",
    ),
    ("tolerance stroke in mm, unit unknown", ["tolerance", *SLIDER, "--limit", "stroke=1mm"], 2, "not declared"),
    ("tolerance time ratio in deg", ["tolerance", "--limit", "time_ratio=1deg"], 2, "dimensionless"),
    ("tolerance gamma_min in mm", ["tolerance", "--limit", "gamma_min=1mm"], 2, "gamma_min is an angle"),
    ("tolerance stroke in deg", ["tolerance", "--limit", "stroke=1deg"], 2, "the stroke is a length"),
    ("tolerance unknown unit", ["tolerance", "--limit", "stroke=1ft"], 2, "not a number in the limit"),
    (
        "tolerance repeated limit",
        ["tolerance", "--limit", "time_ratio=0.01", "--limit", "time_ratio=0.02"],
        2,
        "more than once",
    ),
]


@pytest.mark.parametrize("case, argv, code, match", CLI_ERRORS, ids=[c[0] for c in CLI_ERRORS])
def test_cli_bad_input_prints_one_line(case, argv, code, match, capsys):
    got = qropt_cli.main(argv)
    err = capsys.readouterr().err
    assert got == code and err.startswith("qropt: ") and err.count("\n") == 1, err
    assert match in err and "Traceback" not in err


def test_cli_length_units_convert_to_the_declared_unit(capsys):
    mm = ["slider-crank", "--r2", "100", "--r3", "350", "--e", "60"]  # a design in mm
    assert qropt_cli.main(["tolerance", *mm, "--unit", "mm", "--limit", "stroke=1mm", "--json"]) == 0
    import json

    assert json.loads(capsys.readouterr().out)["limits"]["stroke"] == pytest.approx(1.0)
    assert qropt_cli.main(["tolerance", *mm, "--unit", "mm", "--limit", "stroke=10um", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["limits"]["stroke"] == pytest.approx(0.01)
    assert qropt_cli.main(["tolerance", *mm, "--limit", "stroke=1", "--json"]) == 0  # plain: the design's unit
    assert json.loads(capsys.readouterr().out)["limits"]["stroke"] == pytest.approx(1.0)
    assert qropt_cli.main(["tolerance", "--limit", "stroke=1mm", "--json"]) == 0  # the paper's design is in m
    assert json.loads(capsys.readouterr().out)["limits"]["stroke"] == pytest.approx(0.001)


def test_a_directory_named_like_a_picture_is_refused(tmp_path, capsys):
    d = tmp_path / "d.png"
    d.mkdir()
    with pytest.raises(QroptError, match="is a directory"):
        _profile().plot(d)
    assert qropt_cli.main(["servo", *SLIDER, "--omega-max", "10", "--plot", str(d)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "is a directory" in err
