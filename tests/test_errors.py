"""Bad input: a typed error that names the problem, and the CLI's one line with a non-zero exit."""

from __future__ import annotations

import math

import numpy as np
import pytest

import qropt
from qropt import cli
from tests import brute

PAPER = dict(r1=0.1, r2=0.225, r3=0.2504, r4=0.275, r5=0.15, r6=0.3)

# (constructor, kwargs, error type, message fragment, equivalent CLI arguments)
CASES = [
    (
        "DragLinkSlider",
        {**PAPER, "r1": -0.1},
        qropt.InvalidParameter,
        "length r1 must be positive, got -0.1",
        ["--r1", "-0.1"],
    ),
    (
        "DragLinkSlider",
        {**PAPER, "r4": 0.0},
        qropt.InvalidParameter,
        "length r4 must be positive, got 0",
        ["--r4", "0"],
    ),
    ("DragLinkSlider", {**PAPER, "r3": math.inf}, qropt.InvalidParameter, "r3 must be finite", ["--r3", "inf"]),
    ("DragLinkSlider", {**PAPER, "r5": "0.15"}, qropt.InvalidParameter, "r5 must be a number, got '0.15'", None),
    ("DragLinkSlider", {**PAPER, "r7": 0.1}, qropt.InvalidParameter, "unknown parameter(s) ['r7']", None),
    (
        "DragLinkSlider",
        {k: v for k, v in PAPER.items() if k != "r3"},
        qropt.InvalidParameter,
        "missing parameter 'r3'",
        "drop-r3",
    ),
    (
        "DragLinkSlider",
        {**PAPER, "sigma": 0.5},
        qropt.InvalidParameter,
        "branch sign sigma must be +1 or -1",
        ["--sigma", "0.5"],
    ),
    (
        "SliderCrank",
        {"r2": 0.1, "r3": 0.12, "e": 0.05},
        qropt.InvalidParameter,
        "full rotation needs r3 >= r2 + |e|",
        None,
    ),
    ("CrankShaper", {"r1": 0.1, "r2": 0.2, "r4": 0.3}, qropt.InvalidParameter, "needs crank r2 < centres r1", None),
    (
        "Whitworth",
        {"r1": 0.2, "r2": 0.1, "r5": 0.1, "r6": 0.3},
        qropt.InvalidParameter,
        "needs crank r2 > centres r1",
        None,
    ),
    ("DragLinkSlider", {**PAPER, "r1": 0.3, "r2": 0.1}, qropt.GrashofError, "got crank-rocker: shortest r2=0.1", None),
    ("DragLinkSlider", {**PAPER, "r3": 0.5}, qropt.GrashofError, "got non-Grashof", ["--r3", "0.5"]),
    ("CrankRockerSlider", PAPER, qropt.GrashofError, "needs a Grashof crank-rocker (r2 shortest", None),
    (
        "DragLinkSlider",
        {**PAPER, "r6": 0.05},
        qropt.AssemblyError,
        "rod CD reaching the slide line fails for theta2 in [",
        ["--r6", "0.05"],
    ),
    (
        "CrankShaper",
        {"r1": 0.2, "r2": 0.1, "r4": 0.3, "h": 0.1},
        qropt.InvalidParameter,
        "h (slide-line height) needs",
        None,
    ),
    ("FourBar", {"r1": 1, "r2": 1, "r3": 1, "r4": True}, qropt.InvalidParameter, "r4 must be a number, got True", None),
]


def _cli_args(name, kw, extra):
    kind = qropt.mechanism_type(name).KIND
    base = {**kw}
    if extra == "drop-r3":
        return ["analyze", kind] + [a for k, v in base.items() for a in (f"--{k}", str(v))]
    base = {k: v for k, v in base.items() if isinstance(v, (int, float))}
    args = ["analyze", kind] + [a for k, v in base.items() for a in (f"--{k.replace('_', '-')}", str(v))]
    return args + list(extra)


@pytest.mark.parametrize("name, kw, err, fragment, cli_extra", CASES)
def test_typed_error_with_message(name, kw, err, fragment, cli_extra):
    with pytest.raises(err) as info:
        getattr(qropt, name)(**kw)
    assert fragment in str(info.value)
    assert isinstance(info.value, qropt.QroptError) and isinstance(info.value, ValueError)


@pytest.mark.parametrize("name, kw, err, fragment, cli_extra", [c for c in CASES if c[4] is not None])
def test_cli_one_line_nonzero(name, kw, err, fragment, cli_extra, capsys):
    rc = cli.main(_cli_args(name, kw, cli_extra))
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert rc != 0 and len(lines) == 1 and "Traceback" not in captured.err
    assert err.__name__ in lines[0] or "error" in lines[0]


@pytest.mark.parametrize(
    "argv, fragment",
    [
        (["analyze", "crank-shaper", "--r1", "1", "--r2", "0.5", "--r4", "2", "--theta2", "abc"], "not an angle"),
        (["analyze", "nonsense", "--r1", "1"], "unknown mechanism type 'nonsense'"),
        (["analyze", "--r1", "1"], "give the mechanism TYPE"),
        (["analyze", "whitworth", "--r1", "x"], "not a number"),
        (["frobnicate"], "invalid choice"),
        (["analyze", "four-bar", "--r1", "3.5", "--r2", "1.6", "--r3", "2.14", "--r4", "2.06"], "104.6361, 255.3639"),
        (["analyze", "four-bar", "--r1", "0.1", "--r2", "0.3", "--r3", "0.3", "--r4", "0.3"], "no regular extremes"),
    ],
)
def test_cli_usage_errors(argv, fragment, capsys):
    rc = cli.main(argv)
    err = capsys.readouterr().err
    assert rc != 0 and len(err.strip().splitlines()) == 1 and fragment in err


def test_assembly_error_keeps_input_and_names_the_angles():
    kw = {**PAPER, "r6": 0.05}
    with pytest.raises(qropt.AssemblyError) as info:
        qropt.DragLinkSlider(**kw)
    e = info.value
    assert {k: e.params[k] for k in kw} == kw
    # independent: where |y_C - h| > r6 on a dense brute-force grid
    p = {**kw, "h": 0.0, "sigma": -1.0, "sigma_slider": 1.0}
    th = np.radians(np.arange(0, 360, 1e-3))
    yc = np.real(brute.joints("four-bar", p, th)["B"][1]) * p["r5"] / p["r4"]
    bad = np.abs(yc) > p["r6"]
    edges = sorted(np.degrees(th[np.flatnonzero(bad != np.roll(bad, 1))]))
    got = sorted(math.degrees(t) % 360 for _, lo, hi in e.failures for t in (lo, hi))
    assert got == pytest.approx(edges, abs=2e-3)


def test_unknown_type_and_grashof_error_attributes():
    with pytest.raises(qropt.InvalidParameter, match="unknown mechanism type"):
        qropt.mechanism_type("shaper-thing")
    with pytest.raises(qropt.GrashofError) as info:
        qropt.DragLinkSlider(**{**PAPER, "r3": 0.5})
    assert info.value.kind == "non-Grashof" and info.value.required == "drag-link"
    assert info.value.params["r3"] == 0.5


def test_drag_link_four_bar_has_no_swing():
    with pytest.raises(qropt.NoDeadCentres):
        qropt.FourBar(r1=0.1, r2=0.225, r3=0.25, r4=0.275).swing()


def test_mechanisms_are_immutable_and_keep_their_cached_results():
    m = qropt.DragLinkSlider(**PAPER)
    tr = m.time_ratio()
    with pytest.raises(AttributeError, match="immutable"):
        m.params = {}
    assert m.time_ratio() == tr and m.params["r3"] == 0.2504
