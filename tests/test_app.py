"""The web API (``qropt app``): the four documented calls answer what the library computes, jobs run in worker
processes with progress, cancellation, a time limit and a bounded queue, and every bad input gets a 4xx with a
one-line reason while the server keeps serving."""

from __future__ import annotations

import json
import math
import time

import numpy as np
import pytest

pytest.importorskip("flask")

import qropt
from qropt.app import create_app
from qropt.app.defaults import default_params
from qropt.dynamics.cycle import CycleDynamics
from qropt.dynamics.model import Loads, Masses
from qropt.examples import paper_mechanism
from qropt.io.export import load_design
from qropt.mechanisms import TYPES, mechanism_type

SHIPPED = {cls.KIND: cls.EXAMPLE for cls in TYPES}  # every shipped type's example design, by its KIND
PAPER = {"r1": 0.1, "r2": 0.225, "r3": 0.2504281217548, "r4": 0.275, "r5": 0.15, "r6": 0.3}
README_PROBLEM = {
    "mechanism": "DragLinkSlider",
    "fixed": {"r1": 0.1, "r2": 0.225, "r4": 0.275, "r6": 0.3},
    "free": {"r3": [0.05, 1.0], "r5": [0.01, 0.5]},
    "targets": {"time_ratio": 1.5, "stroke": 0.3},
    "conditions": {"grashof": "drag-link"},
    "objective": "max_gamma_min",
}


@pytest.fixture(scope="module")
def client():
    app = create_app(["problems/user_watt_sixbar.py"], workers=1, time_limit=120)
    yield app.test_client()
    app.extensions["qropt_jobs"].close()


def _wait(client, jid, timeout=120):
    end = time.time() + timeout
    while time.time() < end:
        s = client.get(f"/api/jobs/{jid}").get_json()
        if s["state"] not in ("queued", "running"):
            return s
        time.sleep(0.05)
    raise AssertionError(f"job {jid} did not end in {timeout} s")


def test_health_and_types(client):
    h = client.get("/api/health").get_json()
    assert h["status"] == "ok" and "drag-link-slider" in h["types"]
    info = {t["type"]: t for t in client.get("/api/types").get_json()}
    assert "problems.user_watt_sixbar:WattSixBarShaper" in info  # the problem file's type, served
    assert set(SHIPPED) <= set(info) and all(info[k]["params"] for k in SHIPPED)
    for name, t in info.items():
        if name not in SHIPPED and not t["params"]:  # a type of this process with no design known: no default
            continue
        m = mechanism_type(name)(**t["params"])  # every type with a default opens with a valid design
        assert m.stroke() > 0
        if name in SHIPPED and name != "four-bar":
            assert m.time_ratio() == pytest.approx(1.5, abs=2e-3) and m.stroke() == pytest.approx(0.3, abs=1e-3)
    watt = info["problems.user_watt_sixbar:WattSixBarShaper"]
    m = mechanism_type("problems.user_watt_sixbar:WattSixBarShaper")(**watt["params"])
    from qropt.cli import load_problem

    targets = load_problem("problems/user_watt_sixbar.py").targets  # it opens with its problem's solved design
    assert m.time_ratio() == pytest.approx(targets["time_ratio"], abs=1e-6)
    assert m.stroke() == pytest.approx(targets["stroke"], abs=1e-6)
    assert list(watt["params"]) == [k for k in watt["kinds"] if k in watt["params"]]  # in the type's order


def test_analyze_equals_the_library(client):
    body = {"type": "drag-link-slider", "params": PAPER, "theta2": 1.0, "omega2": 10.0}
    body |= {"masses": {"density": 1.57, "ram": 20.0}, "loads": {"cutting_force": 1000.0, "gravity": 9.81}}
    r = client.post("/api/analyze", json=body)
    assert r.status_code == 200, r.get_json()
    a = r.get_json()
    m = paper_mechanism()
    assert a["time_ratio"] == pytest.approx(m.time_ratio(), rel=1e-12)
    assert a["stroke"] == pytest.approx(0.3, rel=1e-12)
    assert a["gamma_min"]["value_deg"] == pytest.approx(27.0082, abs=1e-4)
    assert a["peak_accel"]["value"] == pytest.approx(m.peak_acceleration(10.0).value, rel=1e-12)
    mo = m.motion(np.array([1.0]), 10.0)
    assert a["state"]["v"] == pytest.approx(mo.v[0], rel=1e-12) and a["state"]["a"] == pytest.approx(mo.a[0], rel=1e-12)
    assert len(a["cycle"]["x"]) == 181 and a["cycle"]["x"][30] == pytest.approx(m.motion(np.radians([60.0])).x[0])
    # the polygons close on the ram's exact velocity and acceleration
    for q, exact in (("velocity", mo.v[0]), ("acceleration", mo.a[0])):
        (eq,) = [e for e in a["polygons"] if e["joint"] == "D" and e["quantity"] == q]
        total = np.sum([t["vector"] for t in eq["terms"]], axis=0)
        assert total == pytest.approx([exact, 0.0], abs=1e-9 * max(1.0, abs(exact)))
    # the forces: the same exact dynamics as the library
    cd = CycleDynamics(m, 10.0, 0.0, Masses(1.57, 20.0), Loads(1000.0, gravity=9.81))
    d = cd.at(np.array([1.0]))
    assert a["dynamics"]["at"]["torque"] == pytest.approx(d.torque[0], rel=1e-12)
    assert a["dynamics"]["peak_torque"]["value"] == pytest.approx(cd.extremes().peak_torque.value, rel=1e-12)
    f = d.joint_forces["O4"][0]
    assert a["dynamics"]["at"]["joint_forces"]["O4"] == pytest.approx(f.tolist(), abs=1e-12 * np.hypot(*f))
    # the drawing: the ram on the stroke's line, the working stroke the slow one
    start, length = (math.radians(v) for v in a["working_arc_deg"])
    assert length > math.pi  # TR 1.5: 216 deg
    ram = [s for s in a["drawing"]["shapes"] if s["part"] == "joint" and s["name"] == "D"][0]
    assert ram["points"][0][0] == pytest.approx(mo.x[0] + 0.0, abs=1e-12) or ram["points"][0][0] == pytest.approx(
        m.positions(np.array([1.0])).points["D"][0][0]
    )


def test_analyze_frames_and_a_user_type(client):
    info = {t["type"]: t for t in client.get("/api/types").get_json()}
    name = "problems.user_watt_sixbar:WattSixBarShaper"
    r = client.post("/api/analyze", json={"type": name, "params": info[name]["params"], "frames": 12})
    assert r.status_code == 200, r.get_json()
    d = r.get_json()["drawing"]
    assert len(d["frames"]) == 12 and [f["theta2_deg"] for f in d["frames"]][:2] == pytest.approx([0.0, 30.0])
    assert {f["working"] for f in d["frames"]} == {True, False}
    # a hand-written loop has no polygons: the answer says why (the app writes it in the polygons' boxes)
    a = client.post("/api/analyze", json={"type": name, "params": info[name]["params"]}).get_json()
    assert a["polygons"] is None and "not declared with the linkage builder" in a["polygons_reason"]
    paper = client.post("/api/analyze", json={"type": "drag-link-slider", "params": info["drag-link-slider"]["params"]})
    assert paper.get_json()["polygons"] and paper.get_json()["polygons_reason"] == ""


@pytest.mark.parametrize(
    "body, status, words",
    [
        ("not json", 400, "not JSON"),
        ([1, 2], 400, "JSON object"),
        ({"params": {}}, 400, "missing field(s): type"),
        ({"type": "nope", "params": {}}, 400, "unknown mechanism type 'nope'"),
        ({"type": "os:system", "params": {}}, 400, "load a type of your own"),
        ({"type": "slider-crank", "params": {"r2": -1, "r3": 1}}, 400, "r2 must be positive"),
        ({"type": "slider-crank", "params": {"r2": 0.1}}, 400, "r3"),
        ({"type": "slider-crank", "params": {"r2": 0.1, "r3": 0.3, "zz": 1}}, 400, "zz"),
        ({"type": "slider-crank", "params": {"r2": "a", "r3": 0.3}}, 400, "finite number"),
        ({"type": "slider-crank", "params": {"r2": 0.1, "r3": 0.3}, "omega2": 0}, 400, "omega2 must be nonzero"),
        ({"type": "slider-crank", "params": {"r2": 0.1, "r3": 0.3}, "theta2": 1e300}, 400, "theta2 must lie"),
        ({"type": "slider-crank", "params": {"r2": 0.1, "r3": 0.3}, "frames": 10**9}, 400, "frames"),
        ({"type": "slider-crank", "params": {"r2": 0.1, "r3": 0.3}, "masses": 3}, 400, "masses"),
        ({"type": "slider-crank", "params": {"r2": 0.1, "r3": 0.05}}, 400, ""),  # does not assemble
        ({"type": "slider-crank", "params": {"r2": 0.1, "r3": 0.3}, "extra": 1}, 400, "unknown field(s): extra"),
    ],
)
def test_bad_analyze_input_is_a_4xx_with_one_line(client, body, status, words):
    r = client.post("/api/analyze", data=body if isinstance(body, str) else json.dumps(body))
    assert r.status_code == status
    err = r.get_json()["error"]
    assert words in err and "\n" not in err and "Traceback" not in err
    assert client.get("/api/health").status_code == 200  # still serving


def test_routes_and_limits(client):
    assert client.get("/api/nothing").status_code == 404
    assert "error" in client.get("/api/nothing").get_json()
    assert client.get("/api/analyze").status_code == 405
    big = {"type": "slider-crank", "params": {"r2": 0.1, "r3": 0.3}, "pad": "x" * (2 << 20)}
    assert client.post("/api/analyze", json=big).status_code == 413
    page = client.get("/")
    assert page.status_code == 200 and b"app.js" in page.data
    assert b"http://" not in page.data and b"https://" not in page.data  # no external resources
    for f in ("/app.js", "/app.css"):
        text = client.get(f).data
        assert b"https://" not in text and b"http://" not in text.replace(b"http://www.w3.org/2000/svg", b"")


def test_solve_equals_the_library(client):
    r = client.post("/api/solve", json=README_PROBLEM)
    assert r.status_code == 200, r.get_json()
    got = r.get_json()
    want = qropt.solve(qropt.Problem.from_dict(README_PROBLEM))
    assert got["status"] == want.status == "optimal"
    assert got["params"]["r3"] == pytest.approx(want.params["r3"], rel=1e-10)
    assert got["certificate"]["global_claim"] == want.certificate.global_claim
    assert qropt.Result.from_dict(got).params == pytest.approx(want.params)


@pytest.mark.parametrize(
    "problem, words",
    [
        ({**README_PROBLEM, "mechanism": "os:system"}, "load a type of your own"),
        ({**README_PROBLEM, "free": {"r3": [1.0, 0.5]}}, ""),
        ({**README_PROBLEM, "objective": "max_happiness"}, "max_happiness"),
        ({**README_PROBLEM, "colour": "red"}, "colour"),
        ([1], "JSON object"),
    ],
)
def test_bad_problems(client, problem, words):
    r = client.post("/api/solve", json=problem)
    assert r.status_code == 400
    assert words in r.get_json()["error"]


def test_design_equals_the_library(client):
    body = {"time_ratio": 1.8, "stroke": 0.5, "objective": "max_gamma_min", "types": ["slider-crank", "crank-shaper"]}
    r = client.post("/api/design", json=body)
    assert r.status_code == 200, r.get_json()
    rows = r.get_json()["rows"]
    want = qropt.design(1.8, 0.5, types=["slider-crank", "crank-shaper"])
    assert [x["type"] for x in rows] == [x.type for x in want.rows]
    for got, w in zip(rows, want.rows, strict=True):
        assert got["gamma_min"] == pytest.approx(w.criteria["gamma_min"], rel=1e-9)
        assert got["mechanism"] == w.result.mechanism.KIND
    for bad, words in (
        ({"time_ratio": 0.5, "stroke": 0.3}, "time_ratio must lie"),
        ({"time_ratio": 1.5}, "missing field(s): stroke"),
        ({"time_ratio": 1.5, "stroke": 0.3, "objective": "fastest"}, "objective is one of"),
        ({"time_ratio": 1.5, "stroke": 0.3, "types": ["nope"]}, "unknown mechanism type"),
        ({"time_ratio": 1.5, "stroke": 0.3, "bounds": [1]}, "bounds is an object"),
    ):
        r = client.post("/api/design", json=bad)
        assert r.status_code == 400 and words in r.get_json()["error"], (bad, r.get_json())


USER = "problems.user_watt_sixbar:WattSixBarShaper"
MASSES = {"density": 1.57, "ram": 20.0, "block": 0.0, "bodies": {}}
LOADS = {"cutting_force": 1000.0, "friction": 0.0, "gravity": 9.81, "follower_torque": 0.0}


def test_design_options_come_from_the_registries(client):
    """The Design page's choices: every objective of the criteria registry (the dynamic ones marked), design's
    eight built-in rows and the served user type, and the longest budget a job may have."""
    from qropt.studies._design import TYPES as ROWS
    from qropt.synthesis import criteria

    o = client.get("/api/design/options").get_json()
    assert [x["criterion"] for x in o["objectives"]] == list(criteria.CRITERIA)
    by = {x["criterion"]: x for x in o["objectives"]}
    assert by["peak_torque"]["objective"] == "min_peak_torque" and by["peak_torque"]["dynamic"]
    assert by["footprint"] == {**by["footprint"], "objective": "min_size", "size": "footprint", "dynamic": False}
    assert [t["type"] for t in o["types"] if t["built_in"]] == list(ROWS)
    (user,) = [t for t in o["types"] if t["type"] == USER]  # other tests of this process may register types too
    assert user | {"name": "watt-sixbar-shaper", "type": USER, "class": "WattSixBarShaper", "built_in": False} == user
    assert user["ram"] == "D" and "D" in user["joints"]  # where loads act: its declared bodies
    assert o["time_limit"] == 120


def test_design_job_dynamic_objective_with_masses_loads_and_budget(client):
    """min_peak_torque with a mass model, loads, omega2 and a 3 s budget: the job ends near the budget, with
    progress per row, the certificate's claim naming what the budget left out, and the row's peak torque the exact
    one of its design."""
    body = {"time_ratio": 1.5, "stroke": 0.3, "objective": "min_peak_torque", "omega2": 10.0, "types": ["whitworth"]}
    body |= {"masses": MASSES, "loads": LOADS, "time_limit": 3}
    r = client.post("/api/jobs", json={"kind": "design", "input": body})
    assert r.status_code == 202, r.get_json()
    s = _wait(client, r.get_json()["id"])
    assert s["state"] == "done" and s["progress"] == {"done": 1, "total": 1}, s
    assert s["seconds"] < 3 + 10  # the budget holds (a margin for a loaded machine)
    c = s["result"]
    assert c["objective"] == "min_peak_torque" and c["omega2"] == 10.0 and c["units"]["peak_torque"] == "N m"
    (row,) = c["rows"]
    said = row["claim"] or row["reason"]
    assert "the time limit (" in said and "left out:" in said, said
    if row["mechanism"]:  # a design within the budget: its numbers are its design's exact ones
        m = mechanism_type(row["mechanism"])(**row["params"])
        assert m.time_ratio() == pytest.approx(1.5, abs=1e-6) and m.stroke() == pytest.approx(0.3, abs=1e-6)
        cd = CycleDynamics(m, 10.0, 0.0, Masses.from_dict(MASSES), Loads.from_dict(LOADS))
        assert row["peak_torque"] == pytest.approx(cd.extremes().peak_torque.value, rel=1e-6)
        assert row["objective"] == pytest.approx(row["peak_torque"], rel=1e-12)


def test_design_types_filter_with_a_user_type(client):
    """types names a built-in row and the served user type (by its module:Class name): one row each, every design
    meeting the task."""
    body = {"time_ratio": 1.4, "stroke": 0.5, "types": ["crank-shaper", USER]}
    r = client.post("/api/design", json=body)
    assert r.status_code == 200, r.get_json()
    rows = r.get_json()["rows"]
    assert sorted(x["type"] for x in rows) == ["crank-shaper", "watt-sixbar-shaper"]
    for x in rows:
        assert x["mechanism"] in ("crank-shaper", USER), x
        m = mechanism_type(x["mechanism"])(**x["params"])
        assert m.time_ratio() == pytest.approx(1.4, abs=1e-6) and m.stroke() == pytest.approx(0.5, abs=1e-6)


GOOD_TASK = {"time_ratio": 1.5, "stroke": 0.3, "types": ["slider-crank"]}


@pytest.mark.parametrize(
    "extra, words",
    [
        ({"time_limit": -1}, "time_limit must lie"),
        ({"time_limit": "soon"}, "time_limit is a finite number"),
        ({"time_limit": 1e6}, "at most 120 s"),
        ({"objective": "min_peak_torque"}, "needs masses or loads"),
        ({"objective": "min_happiness"}, "objective is one of max_gamma_min"),
        ({"masses": {"density": -1}, "objective": "min_peak_torque"}, "density (kg/m) must be zero or positive"),
        ({"masses": MASSES, "loads": {"cutting_force": "x"}}, "cutting_force (N) must be a number"),
        ({"masses": MASSES, "loads": {"cutting_force": 1.0, "zz": 1}}, "loads take"),
        ({"masses": MASSES, "omega2": 0, "objective": "min_rms_torque"}, "omega2"),
        ({"types": []}, "choose at least one type"),
        ({"types": ["four-bar"]}, "FourBar has no slider"),
        ({"types": ["os:system"]}, "load a type of your own"),
        ({"types": [USER], "objective": "min_peak_torque", "masses": MASSES}, "min_peak_torque does not apply"),
    ],
)
def test_bad_design_input_is_a_400_with_a_reason(client, extra, words):
    for path, body in (
        ("/api/design", {**GOOD_TASK, **extra}),
        ("/api/jobs", {"kind": "design", "input": {**GOOD_TASK, **extra}}),
    ):
        r = client.post(path, json=body)
        assert r.status_code == 400, (path, r.get_json())
        err = r.get_json()["error"]
        assert words in err and "\n" not in err, err
    assert client.get("/api/health").status_code == 200  # still serving


def test_jobs_progress_and_cancel(client):
    r = client.post("/api/jobs", json={"kind": "design", "input": {"time_ratio": 1.6, "stroke": 0.4}})
    assert r.status_code == 202
    jid = r.get_json()["id"]
    seen = 0
    for _ in range(400):
        s = client.get(f"/api/jobs/{jid}").get_json()
        seen = max(seen, s["progress"]["done"])
        if seen >= 1:
            break
        time.sleep(0.05)
    assert s["progress"]["total"] == 8 and seen >= 1  # rows report as they finish
    c = client.delete(f"/api/jobs/{jid}").get_json()
    assert c["id"] == jid
    assert _wait(client, jid)["state"] == "cancelled"
    # the next job runs in a new worker process
    r = client.post("/api/jobs", json={"kind": "solve", "input": README_PROBLEM})
    s = _wait(client, r.get_json()["id"])
    assert s["state"] == "done" and s["result"]["status"] == "optimal"
    assert client.get("/api/jobs/99999").status_code == 404
    assert client.delete("/api/jobs/99999").status_code == 404
    assert client.post("/api/jobs", json={"kind": "shell", "input": {}}).status_code == 400


def test_export_and_report(client, tmp_path):
    d = {"type": "drag-link-slider", "params": PAPER, "theta2": 0.5}
    dxf = client.post("/api/export/dxf", json=d)
    assert dxf.status_code == 200 and b"SECTION" in dxf.data
    svg = client.post("/api/export/svg", json=d)
    assert svg.status_code == 200 and b"<svg" in svg.data
    js = client.post("/api/export/json", json=d)
    (tmp_path / "d.json").write_bytes(js.data)
    assert load_design(tmp_path / "d.json").params == paper_mechanism().params | {"r3": PAPER["r3"]}
    assert client.post("/api/export/exe", json=d).status_code == 404
    r = client.post("/api/jobs", json={"kind": "report", "input": {**d, "omega2": 10.0}})
    s = _wait(client, r.get_json()["id"])
    assert s["state"] == "done" and "time ratio" in s["result"]["html"] and "polygons" in s["result"]["html"]


def test_time_limit_and_bounded_queue():
    app = create_app(workers=1, queue_size=1, time_limit=1.0)
    c = app.test_client()
    try:
        slow = {"kind": "design", "input": {"time_ratio": 2.2, "stroke": 1.0, "objective": "min_peak_accel"}}
        first = c.post("/api/jobs", json=slow).get_json()["id"]
        for _ in range(200):  # running: the queue is empty again
            if c.get(f"/api/jobs/{first}").get_json()["state"] == "running":
                break
            time.sleep(0.05)
        second = c.post("/api/jobs", json=slow)
        assert second.status_code == 202
        third = c.post("/api/jobs", json=slow)
        assert third.status_code == 429 and "waiting" in third.get_json()["error"]
        s = _wait(c, first, 30)
        assert s["state"] == "timeout" and "time limit of 1 s" in s["error"]
        c.delete(f"/api/jobs/{second.get_json()['id']}")
        r = c.post("/api/design", json={"time_ratio": 2.2, "stroke": 1.0, "objective": "min_peak_accel"})
        assert r.status_code == 408 and "time limit" in r.get_json()["error"]
    finally:
        app.extensions["qropt_jobs"].close()


def test_cli_app_bad_input(capsys):
    from qropt.cli import main

    assert main(["app", "--port", "70000", "--no-browser"]) != 0
    err = capsys.readouterr().err.strip()
    assert "--port" in err and "\n" not in err
    assert main(["app", "no_such_problem.py", "--no-browser", "--port", "0"]) != 0
    assert "no_such_problem.py" in capsys.readouterr().err


def test_defaults_follow_the_types():
    for kind in SHIPPED:
        cls = mechanism_type(kind)
        assert set(default_params(cls)) <= set(cls.PARAMS)
        assert set(cls.required()) <= set(default_params(cls))


def test_the_default_design_is_the_librarys_example(client):
    """Every shipped type opens with the example design it declares; the drag-link slider's is the paper's design
    (qropt.examples, the README: sigma = -1 and the exact r3), its slider at x = 0.529649 m at theta2 = 60 deg."""
    info = {t["type"]: t for t in client.get("/api/types").get_json()}
    for cls in TYPES:
        assert default_params(cls) == cls.EXAMPLE, cls.KIND
        assert cls(**info[cls.KIND]["params"]) == cls(**cls.EXAMPLE), cls.KIND
    drag = mechanism_type("drag-link-slider")(**info["drag-link-slider"]["params"])
    assert drag == paper_mechanism() and drag.params["sigma"] == -1.0
    assert drag.params["r3"] == pytest.approx(PAPER["r3"], abs=1e-13)
    body = {"type": "drag-link-slider", "params": info["drag-link-slider"]["params"], "theta2": math.radians(60.0)}
    r = client.post("/api/analyze", json=body)
    assert r.status_code == 200, r.get_json()
    assert r.get_json()["cycle"]["x"][30] == pytest.approx(0.529649, abs=5e-7)  # the README's x at 60 deg


def test_a_problem_file_read_as_the_cli_reads_it(client):
    """qropt's own .toml and .json problem files come back as Problem.to_dict's form; a .py problem is refused
    with why (code runs only when the command line names it); a bad file is a 400 with its reason."""
    from pathlib import Path

    from qropt.synthesis.problem import Problem

    text = Path("problems/paper_task.toml").read_text()
    r = client.post("/api/problem/read", json={"name": "paper_task.toml", "text": text})
    assert r.status_code == 200, r.get_json()
    assert r.get_json() == Problem.from_toml(text).to_dict()
    as_json = Problem.from_toml(text).to_json()
    r = client.post("/api/problem/read", json={"name": "task.JSON", "text": as_json})
    assert r.get_json() == Problem.from_json(as_json).to_dict()
    for name, text, words in (
        ("paper_drag_link.py", "import os\n", "runs it only when the command line names it (qropt app"),
        ("task.toml", "mechanism = [", "task.toml is not TOML"),
        ("task.json", "{nope", "task.json is not a JSON problem"),
        ("task.toml", 'mechanism = "os:system"', "load a type of your own"),
        ("task.toml", 'mechanism = "slider-crank"\nhappiness = 1', "unknown: ['happiness']"),
        ("task.txt", "", "qropt's are .json or .toml"),
    ):
        r = client.post("/api/problem/read", json={"name": name, "text": text})
        assert r.status_code == 400 and words in r.get_json()["error"], (name, r.get_json())
    assert client.post("/api/problem/read", json={"name": "a.toml"}).status_code == 400
    assert client.get("/api/health").status_code == 200


def test_design_rows_say_why_in_words():
    """A row without a design says in a sentence which target is beyond the range the type reaches (proved by a
    closed form: 'can reach'; sampled: 'found'); a design with a violent peak acceleration or a small gamma_min
    is flagged."""
    from qropt.app.api import row_warnings, row_words

    reach = {"time_ratio": (1.0, 1.0779), "stroke": (0.0549, 0.617)}
    assert row_words("failed", reach, 20.0, 0.3, "m") == (
        "No design: TR 20 is above the highest found for this type within its bounds (1 to 1.078)."
    )
    assert "this type can reach" in row_words("infeasible", reach, 20.0, 0.3, "m")
    both = row_words("failed", reach, 1.05, 0.3, "m")
    assert both.startswith("No design found: each target alone is within reach (TR 1 to 1.078, the stroke")
    assert "the stroke 0.01 m is below the lowest" in row_words("failed", reach, 1.05, 0.01, "m")
    assert row_words("failed", {}, 1.5, 0.3, "m") == ""
    calm = {"peak_accel": 0.25 * 100, "gamma_min": math.radians(40)}
    assert row_warnings(calm, 1.5, 0.3, 10.0) == []
    wild = {"peak_accel": 1000 * 0.3 * 100, "gamma_min": math.radians(5)}
    w = row_warnings(wild, 20.0, 0.3, 10.0)
    assert len(w) == 2 and "1000 times stroke" in w[0] and "17.1°" in w[0] and "gamma_min is only 5°" in w[1]


def test_an_impossible_design_job_answers_in_words(client):
    """TR 20: the slider-crank's row says in words that TR 20 is beyond what it reaches, its solver's account kept
    as the reason; the crank-shaper's design is exact but flagged as extreme; every row names its parameter kinds."""
    job = client.post(
        "/api/jobs",
        json={
            "kind": "design",
            "input": {"time_ratio": 20, "stroke": 0.3, "omega2": 10, "types": ["slider-crank", "crank-shaper"]},
        },
    ).get_json()
    s = _wait(client, job["id"])
    assert s["state"] == "done", s
    rows = {r["type"]: r for r in s["result"]["rows"]}
    sc, cs = rows["slider-crank"], rows["crank-shaper"]
    assert sc["mechanism"] is None and sc["words"].startswith("No design: TR 20 is above the highest found"), sc
    assert "ipopt" in sc["reason"] or "sampled" in sc["reason"]
    assert cs["mechanism"] == "crank-shaper" and cs["words"] == "" and cs["kinds"]["r1"] == "length"
    assert any(w.startswith("extreme: its peak acceleration") for w in cs["warnings"]), cs["warnings"]
    m = mechanism_type("crank-shaper")(**cs["params"])
    assert m.time_ratio() == pytest.approx(20, rel=1e-6)


def test_types_say_which_parameter_is_which_link(client):
    info = {t["type"]: t for t in client.get("/api/types").get_json()}
    assert info["slider-crank"]["summary"].startswith("Offset slider-crank (r2 crank, r3 rod, e slide-line offset)")
    assert all(t["summary"] for t in info.values())


SLIDER = {"r2": 0.1, "r3": 0.41, "e": 0.05, "sigma_slider": 1.0}
GENERAL_MASSES = {"density": 1.57, "ram": 20.0, "points": {"C": 2.0}}
GENERAL_LOADS = {  # as the panel sends them: a force at 150 deg, one against the crank pin's motion, a torque
    "cutting_force": 1000.0,
    "friction": 0.05,
    "gravity": [-9.81, 0.0],  # a vertical machine: gravity along -x
    "follower_torque": 0.0,
    "forces": [
        {"at": "C", "magnitude": 300.0, "direction": [-math.sqrt(3) / 2, 0.5], "window": "always"},
        {"at": "A", "magnitude": 50.0, "direction": "against", "window": "return"},
    ],
    "torques": [{"on": "rod", "magnitude": 5.0, "window": "working"}],
    "pin_friction": {"mu": 0.1, "radius": 0.02},
}


def test_analyze_with_general_loads_equals_the_library(client):
    """The panel's loads as Loads.from_dict reads them: the crank torque at theta2, every joint force, the peak and
    RMS torque, the flywheel, the efficiency of the working stroke and of the turn (m.efficiency) and the motor's
    peak and RMS torque (m.drive_check) are the library's for the same Loads, Masses and Drive."""
    body = {"type": "slider-crank", "params": SLIDER, "theta2": 1.2, "omega2": 10.0}
    body |= {"masses": GENERAL_MASSES, "loads": GENERAL_LOADS, "drive": {"ratio": 10.0, "efficiency": 0.9}}
    r = client.post("/api/analyze", json=body)
    assert r.status_code == 200, r.get_json()
    a = r.get_json()
    assert (a["joints"], a["bodies"], a["ram"]) == (["A", "C", "O2"], ["crank", "rod", "ram"], "C")
    m = mechanism_type("slider-crank")(**SLIDER)
    masses, loads = Masses.from_dict(GENERAL_MASSES), Loads.from_dict(GENERAL_LOADS)
    assert len(loads.forces) == 2 and loads.torques and loads.pin_friction.mu == 0.1 and masses.points == {"C": 2.0}
    dy = a["dynamics"]
    at = m.dynamics([1.2], 10.0, masses=masses, loads=loads)
    assert dy["at"]["torque"] == pytest.approx(at.torque[0], rel=1e-12)
    for k, f in at.joint_forces.items():
        assert dy["at"]["joint_forces"][k] == pytest.approx(f[0].tolist(), abs=1e-12 * max(1.0, np.hypot(*f[0])))
    ex = m.dynamic_extremes(10.0, masses=masses, loads=loads)
    assert dy["peak_torque"]["value"] == pytest.approx(ex.peak_torque.value, rel=1e-12)
    assert dy["rms_torque"] == pytest.approx(ex.rms_torque, rel=1e-12)
    assert dy["flywheel"]["inertia"] == pytest.approx(m.flywheel(10.0, 0.05, masses=masses, loads=loads).inertia)
    eff = m.efficiency(10.0, masses=masses, loads=loads)
    assert dy["efficiency"]["working"]["efficiency"] == pytest.approx(eff.working.efficiency, rel=1e-12)
    assert dy["efficiency"]["turn"]["efficiency"] == pytest.approx(eff.turn.efficiency, rel=1e-12)
    assert 0 < eff.turn.efficiency < 1 and dy["efficiency"]["turn"]["friction"] == pytest.approx(eff.turn.friction)
    dc = m.drive_check(qropt.Drive(10.0, 0.9), 10.0, masses=masses, loads=loads)
    assert dy["drive"]["peak_torque"]["value"] == pytest.approx(dc.peak_torque.value, rel=1e-12)
    assert dy["drive"]["rms_torque"] == pytest.approx(dc.rms_torque, rel=1e-12)
    # the loads change the torque (they are applied, not dropped), and the live answer applies them too
    plain = client.post("/api/analyze", json=body | {"loads": {"cutting_force": 1000.0}, "drive": None}).get_json()
    assert plain["dynamics"]["at"]["torque"] != pytest.approx(at.torque[0], rel=1e-3)
    assert "efficiency" not in plain["dynamics"] and "drive" not in plain["dynamics"]
    live = client.post("/api/analyze", json=body | {"extremes": False}).get_json()["dynamics"]
    assert live["at"]["torque"] == pytest.approx(at.torque[0], rel=1e-12) and "peak_torque" not in live


@pytest.mark.parametrize(
    "change, words",
    [
        ({"loads": {"forces": [{"at": "Z", "magnitude": 100.0}]}}, "the force at Z: SliderCrank has no joint 'Z'"),
        ({"loads": {"torques": [{"on": "lever", "magnitude": 5.0}]}}, "the torque on lever: SliderCrank has no body"),
        ({"loads": {"cutting_force": -5.0}}, "cutting_force (N) must be zero or positive, got -5"),
        ({"masses": {"density": 1.0, "points": {"C": -2.0}}}, "the point mass at C (kg) must be zero or positive"),
        ({"masses": {"density": 1.0, "points": {"Q": 2.0}}}, "SliderCrank has no joint 'Q'"),
        ({"loads": {"pin_friction": {"mu": -0.1, "radius": 0.01}}}, "pin friction: mu (a coefficient) must be zero"),
        ({"loads": {"forces": [{"at": "C", "magnitude": 1.0, "window": "sometimes"}]}}, "a window is named one of"),
        ({"drive": {"ratio": -10.0}}, "the drive's ratio (motor speed / crank speed) must be positive"),
        ({"drive": {"ratio": 10.0, "efficiency": 1.5}}, "the drive's efficiency must lie in (0, 1]"),
        ({"masses": None, "drive": {"ratio": 10.0}}, "loads and a drive act with a mass model"),
    ],
)
def test_a_bad_load_is_a_400_naming_it(client, change, words):
    """A load, point mass or drive the library refuses or cannot apply: 400, one line naming it, marked as the
    panel's (field "loads") for the page to say beside it; never dropped."""
    body = {"type": "slider-crank", "params": SLIDER, "theta2": 1.0, "omega2": 10.0, "masses": {"density": 1.0}}
    for extremes in (False, True):
        r = client.post("/api/analyze", json=body | change | {"extremes": extremes})
        assert r.status_code == 400, r.get_json()
        e = r.get_json()
        assert words in e["error"] and "\n" not in e["error"] and e["field"] == "loads", e


def test_design_with_general_loads_and_a_drive(client):
    """The Design page's loads and drive: min_rms_motor_torque (offered as needing the drive) with the panel's
    forces, gravity vector and point mass gives the row's RMS motor torque of its design as the library computes
    it; a load a ticked type cannot take, pin friction (which the NLP cannot state) and the motor objective
    without a drive are 400s naming them, before any job."""
    from qropt.dynamics.drive import rms_motor_torque

    (o,) = [o for o in client.get("/api/design/options").get_json()["objectives"] if o["drive"]]
    assert o["objective"] == "min_rms_motor_torque" and o["dynamic"]
    rows = {t["name"]: t for t in client.get("/api/design/options").get_json()["types"]}
    assert rows["crank-shaper"]["joints"] == ["A", "C", "O2", "O4"] and rows["crank-shaper-rod"]["ram"] == "D"
    loads = {k: v for k, v in GENERAL_LOADS.items() if k not in ("pin_friction", "torques")}
    body = {"time_ratio": 1.5, "stroke": 0.3, "objective": "min_rms_motor_torque", "omega2": 10.0}
    body |= {"types": ["slider-crank"], "masses": GENERAL_MASSES, "loads": loads, "time_limit": 120}
    body |= {"drive": {"ratio": 10.0, "efficiency": 0.9}}
    r = client.post("/api/design", json=body)
    assert r.status_code == 200, r.get_json()
    (row,) = r.get_json()["rows"]
    assert row["mechanism"] == "slider-crank", row
    m = mechanism_type("slider-crank")(**row["params"])
    cd = CycleDynamics(m, 10.0, 0.0, Masses.from_dict(GENERAL_MASSES), Loads.from_dict(loads))
    want = rms_motor_torque(cd, qropt.Drive(10.0, 0.9), split=False)
    assert row["objective"] == pytest.approx(want, rel=1e-9) and row["rms_motor_torque"] == row["objective"]
    for change, words in (
        ({"types": ["slider-crank", "whitworth"], "loads": {"forces": [{"at": "C", "magnitude": 1.0}]}}, None),
        ({"types": ["crank-shaper", "whitworth"], "loads": {"forces": [{"at": "ram", "magnitude": 1.0}]}}, None),
        (
            {"types": ["crank-shaper", "whitworth"], "loads": {"forces": [{"at": "D", "magnitude": 1.0}]}},
            "the force at D: the crank-shaper row's CrankShaper has no joint 'D'",
        ),
        ({"loads": {"pin_friction": {"mu": 0.1, "radius": 0.01}}}, "cannot apply pin friction"),
        ({"drive": None}, "min_rms_motor_torque needs the drive"),
        ({"drive": {"ratio": 0}}, "the drive's ratio (motor speed / crank speed) must be positive"),
    ):
        if words is None:  # C is a joint of both, "ram" the ram's joint of each (a check only: no job is made)
            from qropt.app.server import _design_input

            _design_input(body | change)
            continue
        r = client.post("/api/jobs", json={"kind": "design", "input": body | change})
        assert r.status_code == 400, r.get_json()
        e = r.get_json()
        assert words in e["error"] and e["field"] == "loads", e
