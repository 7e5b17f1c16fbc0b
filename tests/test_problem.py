"""Problem: value equality, JSON and TOML round trips, and malformed input as ProblemError (arbitrary values too)."""

from __future__ import annotations

import contextlib
import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from qropt import Problem, ProblemError, QroptError, solve
from qropt.examples import paper_problem

BASE = {
    "mechanism": "DragLinkSlider",
    "fixed": {"r1": 0.1, "r2": 0.225, "r4": 0.275, "r6": 0.3},
    "free": {"r3": (0.05, 1.0), "r5": (0.01, 0.5)},
    "targets": {"time_ratio": 1.5, "stroke": 0.3},
}


def rich():
    return paper_problem().replace(
        conditions={
            "grashof": "drag-link",
            "gamma_min": 0.2,
            "linear": [({"r3": 1.0, "r5": -1.0}, 0.0, 1.0)],
            "ratio": [("r3", "r5", 0.5, 5.0)],
        },
        objective=None,
        branches={"sigma": (-1, 1)},
    )


@pytest.mark.parametrize(
    "p", [paper_problem(), rich(), paper_problem().replace(objective="min_size", size="footprint")]
)
def test_round_trips_through_json_and_toml(p):
    for back in (Problem.from_json(p.to_json()), Problem.from_toml(p.to_toml()), Problem.from_dict(p.to_dict())):
        assert back == p and hash(back) == hash(p)
        assert back.objective == p.objective and back.conditions == p.conditions


def test_value_equality_and_a_solved_round_trip():
    a, b = Problem(**BASE), Problem(**BASE)
    assert a == b and a is not b and len({a, b}) == 1
    assert a != a.replace(targets={"time_ratio": 1.6, "stroke": 0.3})
    r = solve(Problem.from_toml(paper_problem().to_toml()))
    assert r.params["r3"] == pytest.approx(0.2504281217548, abs=1e-12)


@pytest.mark.parametrize(
    ("change", "words"),
    [
        ({"conditions": {"linear": [({"r3": 1}, 0.1)]}}, "linear condition is"),
        ({"conditions": {"linear": 3}}, "malformed"),
        ({"conditions": {"ratio": [("r3",)]}}, "ratio condition is"),
        ({"conditions": {"gamma_min": "x"}}, "gamma_min"),
        ({"fixed": [0.1, 0.2]}, "fixed must be a dict"),
        ({"free": [1, 2]}, "free must be a dict"),
        ({"mechanism": 3}, "unknown mechanism"),
        ({"free": {"r3": ("a", "b"), "r5": (0.01, 0.5)}}, "bounds of r3"),
        ({"targets": {"time_ratio": math.nan, "stroke": 0.3}}, "finite"),
        ({"objective": "min_peak_accel", "omega2": 0.0}, "omega2"),
        ({"omega2": math.nan}, "omega2"),
        ({"name": 3}, "name"),
        ({"branches": {"sigma": "x"}}, "branch sigma"),
    ],
)
def test_malformed_problems_name_the_problem(change, words):
    with pytest.raises(ProblemError, match=words):
        Problem(**{**BASE, **change})


def test_bad_files_are_problem_errors():
    with pytest.raises(ProblemError, match="TOML"):
        Problem.from_toml("mechanism = ")
    with pytest.raises(ProblemError, match="JSON"):
        Problem.from_json("{")
    with pytest.raises(ProblemError, match="fields"):
        Problem.from_dict({"mechanism": "DragLinkSlider", "bogus": 1})
    with pytest.raises(ProblemError, match="table"):
        Problem.from_dict([1, 2])


VALUES = st.recursive(
    st.one_of(st.none(), st.booleans(), st.floats(), st.integers(-(10**30), 10**30), st.text(max_size=5)),
    lambda inner: st.one_of(st.lists(inner, max_size=3), st.dictionaries(st.text(max_size=4), inner, max_size=3)),
    max_leaves=6,
)


@settings(max_examples=200, deadline=None)
@given(
    field=st.sampled_from(
        [
            "mechanism",
            "fixed",
            "free",
            "targets",
            "conditions",
            "objective",
            "size",
            "omega2",
            "accel_over",
            "branches",
            "name",
        ]
    ),
    value=VALUES,
)
def test_arbitrary_values_raise_only_problem_errors(field, value):
    with contextlib.suppress(QroptError):
        Problem(**{**BASE, field: value})


@settings(max_examples=100, deadline=None)
@given(value=VALUES, key=st.sampled_from(["r3", "r5", "time_ratio", "grashof", "linear", "ratio", "gamma_min"]))
def test_arbitrary_nested_values_raise_only_problem_errors(value, key):
    for where in ("free", "targets", "conditions"):
        with contextlib.suppress(QroptError):
            Problem(**{**BASE, where: {**BASE.get(where, {}), key: value}})
