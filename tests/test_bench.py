"""The benchmark suite on a small subset: the tables' structure, and qropt meets every oracle there."""

from __future__ import annotations

import csv
import importlib
import json

import pytest

from benchmarks import suite
from benchmarks.methods import METHODS


def test_suite_subset(tmp_path, capsys):
    rc = suite.main(
        ["--problems", "[sf]*_[rn]*", "--methods", "qropt", "scipy-slsqp", "pylinkage", "--out", str(tmp_path)]
    )
    assert rc == 0
    data = json.loads((tmp_path / "results.json").read_text())
    assert {"meta", "summary", "oracles", "rows"} <= set(data)
    assert {"date", "machine", "python", "versions", "repeat", "seed"} <= set(data["meta"])
    rows = data["rows"]
    assert sorted({r["problem"] for r in rows}) == ["four_bar_narrow", "seed001_redesign"]
    assert [r["method"] for r in rows] == ["qropt", "scipy-slsqp", "pylinkage"] * 2
    for q in (r for r in rows if r["method"] == "qropt"):
        assert q["status"] == "meets oracle" and q["success"] and q["error"] <= 1e-9 and q["violation"] <= 1e-9
    # pylinkage does not model crank-shapers (or is not installed): the column says which
    shaper = next(r for r in rows if r["problem"] == "seed001_redesign" and r["method"] == "pylinkage")
    assert shaper["status"] in ("not applicable", "not installed") and shaper["success"] is None
    with open(tmp_path / "results.csv") as fh:
        table = list(csv.DictReader(fh))
    assert len(table) == 6 and {
        "problem",
        "method",
        "status",
        "objective",
        "oracle",
        "error",
        "violation",
        "seconds",
        "nfev",
    } <= set(table[0])
    md = (tmp_path / "results.md").read_text()
    assert "| method | problems | meets oracle | median time [s] | median time / qropt |" in md
    assert "| qropt | 2 | 100% |" in md


def test_every_problem_declares_an_oracle():
    names = suite.problem_names()
    assert len(names) >= 20
    kinds = set()
    for n in names:
        mod = importlib.import_module(f"problems.{n}")
        assert mod.ORACLE["kind"] in ("closed form", "grid") and 0 < mod.ORACLE["tolerance"] <= 1e-6
        p = mod.build()
        kinds.add((p.mechanism.__name__, p.objective))
    types = {k for k, _ in kinds}
    assert types == {"SliderCrank", "CrankShaper", "Whitworth", "CrankRockerSlider", "DragLinkSlider", "FourBar"}
    for t in types:  # every type by every objective that applies to it
        objectives = {o for k, o in kinds if k == t}
        need = {"max_gamma_min", "min_size"} | (set() if t == "FourBar" else {"min_peak_accel"})
        assert need <= objectives, (t, objectives)
    assert set(METHODS) == {"qropt", "qropt-cold", "scipy-slsqp", "scipy-trust-constr", "scipy-de", "pylinkage"}


def test_evolutions_summary_compares_each_row_with_the_default():
    from benchmarks import evolutions

    default = {
        "tasks": [[1.5, 0.3], [2.0, 1.0]],
        "results": {
            "min_peak_torque": {
                "types": {k: {"objective": [100.0, None], "median_s": 60.0, "worst_s": 90.0} for k in evolutions.TYPES}
            }
        },
    }

    def row(kind, i, obj, s):
        tr, stroke = default["tasks"][i]
        return {"k": 4, "i": i, "type": kind, "tr": tr, "stroke": stroke, "status": "optimal", "obj": obj, "s": s}

    coupler, rocker, drag = evolutions.TYPES
    found = [
        row(coupler, 0, 99.0, 100.0),  # better
        row(rocker, 0, 100.00001, 120.0),  # the same (1e-7)
        row(drag, 0, 101.0, 140.0),  # worse
        row(coupler, 1, 50.0, 200.0),  # a design where the default had none
    ]
    s = evolutions.summary(found, default)
    assert s["counts"] == {"better": 2, "worse": 1, "same": 1}
    assert [r["change"] for r in s["rows"]] == ["better", "same", "worse", "better"]
    assert s["times"][coupler] == {
        "median_s": 150.0,
        "worst_s": 200.0,
        "before_median_s": 60.0,
        "before_worst_s": 90.0,
    }
    md = evolutions.markdown(s)
    assert "2 better, 1 worse, 1 the same" in md and "| none | 50 (better) |" in md


def test_strategies_summary_counts_rows_changed_by_leaving_a_strategy_out():
    from benchmarks import strategies

    def row(pipeline, task, kind, status, value, s, spent=None):
        return {
            "pipeline": pipeline,
            "objective": "min_peak_torque",
            "task": task,
            "type": kind,
            "status": status,
            "value": value,
            "s": s,
            "strategies": spent or {},
        }

    records = [
        row("default", 0, "a", "optimal", 10.0, 5.0, {"evolution": 4.0, "plan": 0.5}),
        row("default", 0, "b", "optimal", 20.0, 7.0, {"evolution": 6.0}),
        row("default", 1, "a", "failed", None, 3.0),
        row("default", 1, "b", "optimal", 30.0, 2.0),
        row("evolution", 0, "a", "optimal", 10.0 * (1 + 1e-9), 1.0),  # the same
        row("evolution", 0, "b", "optimal", 25.0, 1.0),  # worse without it
        row("evolution", 1, "a", "feasible", 9.0, 1.0),  # gained without it
        row("evolution", 1, "b", "failed", None, 1.0),  # lost without it
    ]
    s = strategies.summary(records)
    assert s["left_out"]["evolution"] == {
        "better": 0,
        "worse": 1,
        "gained": 1,
        "lost": 1,
        "same": 1,
        "seconds_saved": 13.0,
    }
    assert s["default_seconds"] == {"evolution": 10.0, "plan": 0.5}
    md = strategies.markdown(s)
    assert "| evolution | 0 | 1 | 1 | 1 | 1 | 13.0 |" in md and "| evolution | 10.0 |" in md
    pipes = strategies.pipelines(["differential evolution", "Sobol multi-start"])
    assert [p.name for p in pipes["default"]] != [p.name for p in pipes["differential evolution"]]
    assert "differential evolution" not in [p.name for p in pipes["differential evolution"]]
    phase = next(p for p in pipes["Sobol multi-start"] if hasattr(p, "stages"))
    assert "Sobol multi-start" not in [p.name for p in phase.stages]
    with pytest.raises(SystemExit, match="unknown strategies"):
        strategies.pipelines(["no such"])


def test_the_tasks_benchmark_takes_the_searchs_numbers():
    """``python -m benchmarks.tasks --settings NAME=VALUE ...``: each a Settings field in its default's type, the
    others left at their defaults; anything else is one line naming it."""
    from benchmarks.tasks import _settings
    from qropt.synthesis.search import Settings

    assert _settings(["relifts=1", "restart_violation=1e-5"]) == Settings(relifts=1, restart_violation=1e-5)
    assert _settings([]) == Settings()
    for bad, said in [
        (["nope=1"], "'nope=1' is not NAME=VALUE of a Settings field"),
        (["relifts"], "'relifts' is not NAME=VALUE"),
        (["to_dict=1"], "'to_dict=1' is not NAME=VALUE of a Settings field"),
        (["relifts=1.5"], "relifts is an integer, got '1.5'"),
        (["relifts=0"], "relifts is a positive int, got 0"),
    ]:
        with pytest.raises(SystemExit, match=said):
            _settings(bad)


def test_the_tasks_benchmark_reads_ipopt_options():
    """``python -m benchmarks.tasks --ipopt NAME=JSON ...``: each value JSON (an option's dict as well); a pair
    without a name or with a value that is not JSON is one line, not a traceback."""
    from benchmarks.tasks import _ipopt

    assert _ipopt(['oracle_options={"cse": true}', "ipopt.max_iter=80"]) == {
        "oracle_options": {"cse": True},
        "ipopt.max_iter": 80,
    }
    assert _ipopt([]) == {}
    for bad in (["oracle_options={cse}"], ["=1"], ["ipopt.tol"]):
        with pytest.raises(SystemExit, match="is not NAME=JSON"):
            _ipopt(bad)
