"""Bad input through the Python API: each is a typed QroptError naming the problem (or a Result with a status),
never a bare Python error or a silent number; arbitrary values drive the public API and only QroptError escapes."""

from __future__ import annotations

import contextlib
import math
import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import qropt
from qropt import AssemblyError, InvalidParameter, NoDeadCentres, ProblemError, QroptError, Solver, solve
from qropt.examples import paper_mechanism, paper_problem
from qropt.studies._family import family
from qropt.studies._reachable import reachable

PAPER = paper_mechanism()


def test_new_targets_keep_the_other_target():
    r = solve(paper_problem(), targets={"time_ratio": 1.8})
    assert r.success
    assert r.quantities["time_ratio"] == pytest.approx(1.8, abs=1e-9)
    assert r.quantities["stroke"] == pytest.approx(0.3, abs=1e-9)


@pytest.mark.parametrize(
    ("options", "words"),
    [
        ({"targets": {"swing": 1.0}}, "not targets of this problem"),
        ({"targets": [1.5]}, "dict"),
        ({"max_rounds": 0}, "max_rounds"),
        ({"starts_n": -3}, "starts_n"),
        ({"extra_starts": [{"r3": 0.2}]}, "every free parameter"),
        ({"extra_starts": [{"r3": 0.2, "r5": "x"}]}, "finite number"),
    ],
)
def test_bad_solve_options_are_problem_errors(options, words):
    with pytest.raises(ProblemError, match=words):
        solve(paper_problem(), **options)


def test_solve_takes_a_problem():
    with pytest.raises(ProblemError, match="Problem"):
        solve({"mechanism": "DragLinkSlider"})


def test_bad_solver_options():
    for kw in ({"tolerances": {"gap": -1}}, {"tolerances": {"bogus": 1e-8}}, {"samples": 1}, {"ipopt_options": 3}):
        with pytest.raises(ProblemError):
            Solver(**kw)


@pytest.mark.parametrize(
    ("call", "words"),
    [
        (lambda m: m.peak_acceleration(10.0, over="bogus"), "cycle"),
        (lambda m: m.slider("60"), "real numbers"),
        (lambda m: m.slider(math.nan), "finite"),
        (lambda m: m.slider([0.1, math.inf]), "finite"),
        (lambda m: m.slider(0.3, omega2=math.nan), "omega2"),
        (lambda m: m.positions(np.zeros(20_000_001)), "at most"),
        (lambda m: m.working_direction(0), "nonzero"),
        (lambda m: m.size("bogus"), "measure"),
    ],
)
def test_bad_mechanism_calls(call, words):
    with pytest.raises(InvalidParameter, match=words):
        call(PAPER)


def test_a_four_bar_that_cannot_reach_an_angle_says_where():
    m = qropt.FourBar(r1=1, r2=0.8, r3=0.3, r4=0.3)  # assembles only where |O4A| <= 0.6
    failures = m.assembly_failures()
    assert failures and all(what.startswith("four-bar") for what, *_ in failures)
    lo, hi = failures[0][1], failures[0][2]
    with pytest.raises(AssemblyError, match="four-bar closure"):
        m.positions((lo + hi) / 2)
    ok = (hi + 1e-3) % (2 * math.pi)  # just past the failing interval it assembles
    assert np.isfinite(m.positions(ok).x).all()


def test_a_four_bar_that_never_assembles_is_an_error():
    with pytest.raises(AssemblyError):
        qropt.FourBar(r1=1, r2=0.1, r3=0.2, r4=0.2)


def test_huge_lengths_are_rejected_without_warnings():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(InvalidParameter, match="out of range"):
            qropt.SliderCrank(r2=1e300, r3=2e300)


def test_an_output_that_reverses_inside_a_stroke_has_no_time_ratio():
    # rod r6 = r5 with the slide line through O4: the slider rests at x = r1 for half a turn
    m = qropt.DragLinkSlider(r1=0.1, r2=0.225, r3=0.25, r4=0.275, r5=0.3, r6=0.3)
    assert m.dead_centres().reversals != 1
    with pytest.raises(NoDeadCentres, match="reverses"):
        m.time_ratio()


def test_mechanisms_are_immutable():
    with pytest.raises(TypeError):
        PAPER.params["r3"] = 1.0
    with pytest.raises(AttributeError):
        PAPER.r3 = 1.0


def test_family_and_reachable_reject_bad_arguments():
    p = qropt.Problem(
        "DragLinkSlider",
        fixed={"r2": 0.225, "r4": 0.275, "r5": 0.15, "r6": 0.3},
        free={"r1": (0.02, 0.2), "r3": (0.05, 0.6)},
        targets={"time_ratio": 1.5},
    )
    with pytest.raises(ProblemError, match="ds"):
        family(p, ds=-0.01)
    with pytest.raises(ProblemError, match="Problem"):
        family(PAPER)
    with pytest.raises(InvalidParameter, match="mechanism"):
        reachable(p, "r3")
    with pytest.raises(InvalidParameter, match="bounds"):
        reachable(PAPER, "r3", bounds=("a", "b"))
    with pytest.raises(InvalidParameter, match="n"):
        reachable(PAPER, "r3", n=10**9)


def test_min_peak_accel_at_zero_crank_speed_is_not_optimal():
    with pytest.raises(ProblemError, match="omega2"):
        paper_problem().replace(objective="min_peak_accel", omega2=0.0)


# ---- arbitrary values through the public API ----------------------------------------------------------------
VALUES = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(min_value=-(10**400), max_value=10**400),
    st.text(max_size=4),
    st.none(),
    st.booleans(),
    st.lists(st.floats(), max_size=3),
    st.dictionaries(st.text(max_size=2), st.floats(), max_size=2),
)
KINDS = [t.KIND for t in qropt.mechanisms.TYPES]


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    kind=st.sampled_from(KINDS),
    params=st.dictionaries(
        st.sampled_from(["r1", "r2", "r3", "r4", "r5", "r6", "e", "h", "sigma", "sigma_slider", "bogus"]),
        VALUES,
        max_size=8,
    ),
)
def test_constructors_raise_only_qropt_errors(kind, params):
    try:
        m = qropt.mechanism_type(kind)(**params)
        m.time_ratio()
    except QroptError:
        pass


@settings(max_examples=150, deadline=None)
@given(theta=VALUES, omega=VALUES, over=VALUES)
def test_methods_raise_only_qropt_errors(theta, omega, over):
    for call in (
        lambda: PAPER.slider(theta, omega),
        lambda: PAPER.peak_acceleration(omega, over),
        lambda: PAPER.working_direction(omega),
        lambda: PAPER.transmission_angles(theta),
        lambda: PAPER.size(over),
    ):
        with contextlib.suppress(QroptError):
            call()


@settings(max_examples=40, deadline=None)
@given(
    opts=st.dictionaries(
        st.sampled_from(["starts_n", "seed", "max_rounds", "targets", "extra_starts"]), VALUES, max_size=2
    )
)
def test_solve_options_raise_only_qropt_errors(opts):
    try:
        r = solve(paper_problem(), **opts)
        assert r.status in qropt.STATUSES
    except QroptError:
        pass


def test_a_required_length_given_as_none_is_missing():
    with pytest.raises(InvalidParameter, match="missing parameter 'r3'"):
        qropt.SliderCrank(r2=0.1, r3=None)
