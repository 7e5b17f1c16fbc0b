"""The schema version of saved files (qropt.schema): every problem (JSON, TOML), design file, Result dictionary
and chart file carries "schema" and "qropt" and reads back the same; a file of a newer schema is refused in one
line naming its schema and this qropt's; a file of none (written before files carried one) is read as before."""

from __future__ import annotations

import json

import pytest

from qropt import schema
from qropt.cli import load_problem, main
from qropt.errors import ChartError, InvalidParameter, ProblemError
from qropt.examples import paper_mechanism, paper_problem
from qropt.io.export import load_design, read_design, save_design
from qropt.studies._chart import Chart
from qropt.studies._chart_run import chart
from qropt.synthesis.problem import Problem
from qropt.synthesis.result import Result

NEWER = schema.SCHEMA + 1
REFUSED = rf"has schema {NEWER}\b.*newer than this qropt's schema {schema.SCHEMA} \(qropt {schema.VERSION}\)"


def refused(e) -> None:
    text = str(e.value)
    assert "\n" not in text and f"schema {NEWER}" in text and f"schema {schema.SCHEMA}" in text


@pytest.fixture(scope="module")
def small_chart():
    p = Problem(
        mechanism="SliderCrank",
        fixed={"r2": 0.3},
        free={"r3": (0.2, 20.0), "e": (0.0, 10.0)},
        targets={"time_ratio": 1.5, "stroke": 1.0},
        objective="max_gamma_min",
        name="schema_chart",
    )
    return chart(p, ("time_ratio", (1.2, 1.45)), progress=False)  # the stroke triangle's closed form: quick


def test_schema_is_one_whole_number_and_stamps_lead():
    assert isinstance(schema.SCHEMA, int) and schema.SCHEMA >= 1
    assert schema.stamp() == {"schema": schema.SCHEMA, "qropt": schema.VERSION}


@pytest.mark.parametrize("form", ["json", "toml"])
def test_problem_round_trip(tmp_path, form):
    p = paper_problem()
    text = p.to_json() if form == "json" else p.to_toml()
    d = json.loads(text) if form == "json" else __import__("tomllib").loads(text)
    assert d["schema"] == schema.SCHEMA and d["qropt"] == schema.VERSION
    assert list(d)[:2] == ["schema", "qropt"]
    assert (Problem.from_json(text) if form == "json" else Problem.from_toml(text)) == p
    f = tmp_path / f"p.{form}"
    f.write_text(text)
    assert load_problem(str(f)) == p
    assert "schema" not in p.to_dict()  # the plain values (equality, the app's forms) carry no stamp


def test_problem_of_a_newer_schema_is_refused(tmp_path, capsys):
    d = {**json.loads(paper_problem().to_json()), "schema": NEWER, "qropt": "9.0.0"}
    with pytest.raises(ProblemError, match=REFUSED) as e:
        Problem.from_dict(d)
    refused(e)
    assert "written by qropt 9.0.0" in str(e.value)
    f = tmp_path / "new.json"
    f.write_text(json.dumps(d))
    assert main(["synth", str(f)]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(f"qropt: ProblemError: {f}: the problem has schema {NEWER}")


def test_problem_without_a_schema_and_the_repositorys_problem_file_still_read(tmp_path):
    d = json.loads(paper_problem().to_json())
    del d["schema"], d["qropt"]
    assert Problem.from_dict(d) == paper_problem()
    assert Problem.from_dict({**d, "schema": 0}) == paper_problem()  # an older schema: read as before
    from pathlib import Path

    assert load_problem(str(Path(__file__).resolve().parents[1] / "problems" / "paper_task.toml")).free


@pytest.mark.parametrize("bad", ["1", 1.0, -1, True, None])
def test_a_schema_that_is_not_a_whole_number_is_refused(bad):
    d = {**json.loads(paper_problem().to_json()), "schema": bad}
    with pytest.raises(ProblemError, match="'schema' is the schema version"):
        Problem.from_dict(d)


def test_design_file_round_trip_newer_and_older(tmp_path):
    m = paper_mechanism()
    f = tmp_path / "d.json"
    save_design(m, f, note="kept")
    d = json.loads(f.read_text())
    assert (d["schema"], d["qropt"], d["note"]) == (schema.SCHEMA, schema.VERSION, "kept")
    back = load_design(f)
    assert type(back) is type(m) and back.params == m.params and back.units == m.units
    with pytest.raises(InvalidParameter, match="design file's own field"):
        save_design(m, tmp_path / "x.json", schema=7)
    f.write_text(json.dumps({**d, "schema": NEWER}))
    with pytest.raises(InvalidParameter, match=REFUSED) as e:
        load_design(f)
    refused(e)
    assert str(e.value).startswith(f"{f} has schema {NEWER}")
    old = {k: v for k, v in d.items() if k not in schema.FIELDS}
    f.write_text(json.dumps(old))
    assert load_design(f).params == m.params and read_design(f) == old


def test_result_round_trip_newer_and_older(small_chart):
    r = small_chart.cell(1, 0).result
    assert r.success
    d = r.to_dict()
    assert list(d)[:2] == ["schema", "qropt"] and d["schema"] == schema.SCHEMA
    back = Result.from_dict(json.loads(json.dumps(d)))
    assert back.to_dict() == d and back.params == r.params
    with pytest.raises(ProblemError, match=REFUSED) as e:
        Result.from_dict({**d, "schema": NEWER})
    refused(e)
    old = {k: v for k, v in d.items() if k not in schema.FIELDS}
    assert Result.from_dict(old).to_dict() == d


def test_a_saved_result_is_a_design_file(tmp_path, small_chart):
    r = small_chart.cell(1, 0).result  # what qropt synth --json prints: analyze --from reads it back
    f = tmp_path / "r.json"
    f.write_text(json.dumps(r.to_dict()))
    assert load_design(f).params == r.mechanism.params


def test_chart_round_trip_newer_and_older(tmp_path, small_chart):
    f = tmp_path / "c.json"
    small_chart.to_json(f)
    d = json.loads(f.read_text())
    assert (d["schema"], d["qropt"]) == (schema.SCHEMA, schema.VERSION)
    back = Chart.from_json(f)
    assert back.to_dict() == small_chart.to_dict() and back.shape == small_chart.shape
    f.write_text(json.dumps({**d, "schema": NEWER}))
    with pytest.raises(ChartError, match=REFUSED) as e:
        Chart.from_json(f)
    refused(e)
    old = {k: v for k, v in d.items() if k not in schema.FIELDS}
    f.write_text(json.dumps(old))
    assert Chart.from_json(f).to_dict() == small_chart.to_dict()
