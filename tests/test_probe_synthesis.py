"""Bad input on the synthesis side found by a hostile probe, as a checklist: each case gives a typed qropt error
naming the problem (ProblemError, InvalidParameter), or a Result with a status and a reason; never a bare Python
exception, an endless run or a warning."""

from __future__ import annotations

import importlib
import json
import time
import warnings

import pytest

import qropt
from qropt import cli as qropt_cli
from qropt.errors import QroptError
from qropt.examples import paper_problem
from qropt.studies._design import design
from qropt.studies._family import MAX_POINTS, family
from qropt.synthesis.problem import MAX_OMEGA2, MAX_TIME_RATIO, Problem
from qropt.synthesis.result import Result


def _result_dict(**changes) -> dict:
    d = Result("infeasible", "no design", reachable={"stroke": (0.1, 0.2)}).to_dict()
    return {**d, **changes}


def _deep_local(depth: int) -> dict:
    d = _result_dict()
    for _ in range(depth):
        d = _result_dict(local_optima=[d])
    return d


def _family_problem() -> Problem:
    return importlib.import_module("problems.paper_family_r1_r3").build()


SC = {
    "mechanism": "slider-crank",
    "free": {"r2": (0.01, 1), "r3": (0.01, 2), "e": (-1, 1)},
    "targets": {"time_ratio": 1.2, "stroke": 0.2},
}

RAISES = [
    # Result.from_dict: types and statuses
    ("Result status junk", lambda: Result.from_dict(_result_dict(status="junk")), "status must be one of"),
    ("Result objective a string", lambda: Result.from_dict(_result_dict(objective="abc")), "objective must be"),
    ("Result message None", lambda: Result.from_dict(_result_dict(message=None)), "message must be a string"),
    ("Result from None", lambda: Result.from_dict(None), "a table of fields, got NoneType"),
    ("Result from a list", lambda: Result.from_dict([1, 2]), "a table of fields, got list"),
    ("Result from a str", lambda: Result.from_dict("optimal"), "a table of fields, got str"),
    ("Result reachable a str", lambda: Result.from_dict(_result_dict(reachable="abc")), "reachable must be"),
    ("Result local_optima [5]", lambda: Result.from_dict(_result_dict(local_optima=[5])), "a table of fields"),
    ("Result residuals [1]", lambda: Result.from_dict(_result_dict(residuals=[1])), "residuals must be"),
    ("Result 5000-deep local_optima", lambda: Result.from_dict(_deep_local(5000)), "nested deeper than 8"),
    ("Result params not numbers", lambda: Result.from_dict(_result_dict(params={"r2": "x"})), "params must be"),
    ("Result certificate junk", lambda: Result.from_dict(_result_dict(certificate={"gap": 1})), "certificate"),
    ("Result units junk", lambda: Result.from_dict(_result_dict(units="furlong")), "length unit is one of"),
    ("Result() status junk", lambda: Result("junk", "x"), "status is one of"),
    # Problem files
    ("JSON nested 1e5 deep", lambda: Problem.from_json("[" * 10**5 + "]" * 10**5), "nested deeper than 200"),
    ("TOML nested 1e5 deep", lambda: Problem.from_toml("a = " + "[" * 10**5 + "]" * 10**5), "nested deeper"),
    ("from_json(None)", lambda: Problem.from_json(None), "is text \\(str\\), got NoneType"),
    ("from_toml(None)", lambda: Problem.from_toml(None), "is text \\(str\\), got NoneType"),
    ("from_toml(bytes)", lambda: Problem.from_toml(b"mechanism = 'slider-crank'"), "got bytes"),
    ("from_json(bytes)", lambda: Problem.from_json(b"{}"), "got bytes"),
    # Problem magnitudes
    ("omega2 1e300", lambda: Problem(**SC, omega2=1e300), "omega2 = 1e\\+300 rad/s is out of range"),
    ("omega2 just above the limit", lambda: Problem(**SC, omega2=-2 * MAX_OMEGA2), "out of range"),
    ("fixed r1 1e200", lambda: paper_problem().replace(fixed={"r1": 1e200}), "fixed r1 = 1e\\+200 is out of range"),
    ("fixed length 1e-200", lambda: paper_problem().replace(fixed={"r1": 1e-200}), "out of range"),
    ("bound 1e200", lambda: paper_problem().replace(free={"r3": (0.05, 1e200), "r5": (0.01, 0.5)}), "out of range"),
    ("stroke 1e200", lambda: paper_problem().replace(targets={"time_ratio": 1.5, "stroke": 1e200}), "out of range"),
    ("time_ratio 1e308", lambda: Problem(**{**SC, "targets": {"time_ratio": 1e308}}), "is beyond 1e\\+06"),
    ("time_ratio above the limit", lambda: Problem(**{**SC, "targets": {"time_ratio": 2 * MAX_TIME_RATIO}}), "beyond"),
    ("max_footprint 1e300", lambda: Problem(**SC, conditions={"max_footprint": 1e300}), "out of range"),
    # design()
    ("design types [['x']]", lambda: design(1.5, 0.3, types=[["x"]]), "unknown type \\['x'\\]"),
    ("design conditions a list", lambda: design(1.5, 0.3, conditions=["gamma_min"]), "conditions is a dict"),
    ("design omega2 1e200", lambda: design(1.5, 0.3, objective="min_peak_accel", omega2=1e200), "out of range"),
    ("design progress 5", lambda: design(1.5, 0.3, progress=5), "progress is a callable"),
    ("design solver 'x'", lambda: design(1.5, 0.3, solver="x"), "solver is a qropt.Solver"),
    ("design pareto junk", lambda: design(1.5, 0.3, pareto=("junk", "min_size")), "unknown objective 'junk'"),
    ("design pareto 'x'", lambda: design(1.5, 0.3, pareto="x"), "objectives is a pair"),
    ("design pareto n=0", lambda: design(1.5, 0.3, pareto=("max_gamma_min", "min_size"), n=0), "n is the number"),
    ("design stroke 1e300", lambda: design(1.5, 1e300), "stroke 1e\\+300 m is out of range"),
    ("design units junk", lambda: design(1.5, 0.3, units="parsec"), "length unit is one of"),
    # family()
    ("family ds 1e-9", lambda: family(_family_problem(), ds=1e-9, max_points=10**9), "max_points must be"),
    ("family ds 1e-9", lambda: family(_family_problem(), ds=1e-9), "ds = 1e-09 is below"),
    ("family ds 1e-300", lambda: family(_family_problem(), ds=1e-300), "ds = 1e-300 is below"),
    ("family along a list", lambda: family(_family_problem(), along=["r1"]), "along is the name"),
    ("family starts_n 'x'", lambda: family(_family_problem(), starts_n="x"), "starts_n must be an integer"),
    ("family seed 'x'", lambda: family(_family_problem(), seed="x"), "seed must be an integer"),
    ("family max_points above the cap", lambda: family(_family_problem(), max_points=MAX_POINTS + 1), "from 2 to"),
    ("family solver 'x'", lambda: family(_family_problem(), solver="x"), "solver is a qropt.Solver"),
]


@pytest.mark.parametrize("case, call, match", RAISES, ids=[c[0] for c in RAISES])
def test_bad_input_raises_a_typed_error(case, call, match):
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no numpy RuntimeWarning leaks
        with pytest.raises(QroptError, match=match):
            call()
    assert time.perf_counter() - t0 < 5.0  # refused at once, before any solve


def test_family_ds_at_its_limit_still_traces():
    p = _family_problem()
    f = family(p, ds=1e-3, max_points=20)
    assert f.points() and all(len(b) <= 40 for b in f.branches)


@pytest.fixture(scope="module")
def small_family():
    return family(_family_problem(), max_points=40)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"objective": None}, "best takes an objective"),
        ({"sample": 0}, "sample is how many"),
        ({"sample": "x"}, "sample is how many"),
        ({"sample": True}, "sample is how many"),
    ],
)
def test_family_best_bad_input(small_family, kwargs, match):
    with pytest.raises(QroptError, match=match):
        small_family.best(**kwargs)


def test_design_without_an_objective_compares_without_sorting():
    c = design(1.5, 0.3, objective=None, types=["slider-crank", "whitworth"])
    assert [r.type for r in c.rows] == ["slider-crank", "whitworth"] and all(r.success for r in c.rows)


def test_a_bad_pareto_argument_refuses_before_any_solve_on_the_command_line(capsys):
    t0 = time.perf_counter()
    code = qropt_cli.main(["design", "--tr", "1.5", "--stroke", "0.3", "--pareto", "junk", "min_size"])
    err = capsys.readouterr().err
    assert code == 1 and "unknown objective 'junk'" in err and err.count("\n") == 1
    assert time.perf_counter() - t0 < 5.0


def test_design_far_beyond_range_says_why_once(capsys):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert qropt_cli.main(["design", "--tr", "1.5", "--stroke", "1e300"]) == 1
    err = capsys.readouterr().err
    assert err.count("out of range") == 1 and err.count("\n") == 1


def test_a_result_round_trip_still_works():
    r = qropt.solve(paper_problem())
    d = json.loads(json.dumps(r.to_dict()))
    assert Result.from_dict(d).to_dict() == d


@pytest.mark.parametrize("command", ["synth", "family", "pareto", "chart", "report"])
def test_cli_deeply_nested_problem_file_prints_one_line(tmp_path, capsys, command):
    f = tmp_path / "deep.json"
    f.write_text("[" * 10**5 + "]" * 10**5)
    extra = {"pareto": ["--objectives", "max_gamma_min", "min_size"], "chart": ["--x", "time_ratio", "1.4,1.5"]}
    argv = [command, str(f), *extra.get(command, [])]
    if command == "report":
        argv = ["report", str(f), "-o", str(tmp_path / "r.html")]
    code = qropt_cli.main(argv)
    err = capsys.readouterr().err
    assert code in (1, 2) and err.count("\n") == 1 and "Traceback" not in err
    assert "nested" in err


def test_cli_deeply_nested_design_file_for_tolerance_prints_one_line(tmp_path, capsys):
    f = tmp_path / "deep.json"
    f.write_text("[" * 10**5 + "]" * 10**5)
    code = qropt_cli.main(["tolerance", str(f), "--limit", "time_ratio=0.01"])
    err = capsys.readouterr().err
    assert code == 1 and err.count("\n") == 1 and "nested too deeply" in err
