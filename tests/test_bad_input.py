"""Bad input refused at the door, one case a line: the builder and user types, relative motion and dynamics, the
mass model, every reader of a user file, the web API and the command line. Each case names what it gives and a
word of the reason the typed error (a qropt error, a 4xx, or one line and a non-zero exit) must carry."""

from __future__ import annotations

import math
import os
import subprocess
import sys
import threading
from pathlib import Path

import pytest

import qropt
from qropt import cli, validate
from qropt.errors import ChartError, InvalidParameter, ProblemError
from qropt.examples import paper_mechanism
from qropt.io.export import load_design, read_design
from qropt.mechanisms import REQUIRED, TYPES, Mechanism, mechanism_type
from qropt.mechanisms.builder import Linkage, LinkageError
from qropt.studies import Chart
from qropt.validate import picture_path

ROOT = Path(__file__).resolve().parent.parent
SHIPPED = {cls.KIND: cls.EXAMPLE for cls in TYPES}  # every shipped type's example design, by its KIND
NAN, INF = math.nan, math.inf


# ---- the builder and user types ------------------------------------------------------------------------------------
def four_bar(sign="sigma", around=math.pi, crank="r2") -> Linkage:
    L = Linkage()
    L.ground("O2", (0, 0))
    L.crank("A", "O2", crank)
    L.rrr("B", ("A", "r3"), ("O4", "r4"), sign=sign, around=around)
    L.ground("O4", ("r1", 0))
    return L.output("theta4")


def slider(line_y="e", rod=("A", "r3"), sign="sigma_slider") -> Linkage:
    L = Linkage()
    L.ground("O2", (0, 0))
    L.crank("A", "O2", "r2")
    L.rrp("C", rod, line_y=line_y, sign=sign)
    return L.output("C")


def user_type(linkage, params=None):
    """A type made from ``linkage`` (its class statement runs the checks)."""
    params = {"r2": REQUIRED, "r3": REQUIRED, "e": 0.0, "sigma_slider": 1.0} if params is None else params

    class Made(Mechanism):
        PARAMS = params
        LENGTHS = ("r2", "r3")
        loop = staticmethod(linkage.loop)

    return Made


BUILDER = [
    ("rrr sign 0", lambda: four_bar(sign=0), "a branch sign must be +1 or -1, got 0"),
    ("rrr sign 0.5", lambda: four_bar(sign=0.5), "+1 or -1, got 0.5"),
    ("rrp sign 2", lambda: slider(sign=2), "+1 or -1, got 2"),
    ("rrp sign True", lambda: slider(sign=True), "a branch sign is a parameter name"),
    ("rrp sign nan", lambda: slider(sign=NAN), "a branch sign must be finite"),
    ("sign an expression", lambda: four_bar(sign="-sigma"), "a branch sign is a parameter name"),
    ("crank length nan", lambda: Linkage().crank("A", "O2", NAN), "crank A length must be finite"),
    ("ground at inf", lambda: Linkage().ground("O2", (INF, 0)), "ground O2 x must be finite"),
    ("around nan", lambda: four_bar(around=NAN), "around (rad) must be finite"),
    ("around 'pi'", lambda: four_bar(around="pi"), "around (rad) must be a number, got 'pi'"),
    ("expression 1e400", lambda: Linkage().ground("O2", ("1e400", 0)), "the number 1e400 must be finite"),
    ("expression r2 + 1e999", lambda: Linkage().ground("O2", ("r2 + 1e999", 0)), "the number 1e999 must be finite"),
    ("the name 'nan'", lambda: Linkage().ground("O2", ("nan", 0)), "'nan' in 'nan' is not a parameter name"),
    ("the name '-inf'", lambda: Linkage().ground("O2", (0, "-inf")), "'inf' in '-inf' is not a parameter name"),
    ("rrr about one centre", lambda: Linkage().rrr("B", ("A", "r3"), ("A", "r4")), "both circles are about 'A'"),
    ("rpr on its own pin", lambda: Linkage().rpr("A", "A"), "turns about its own pin"),
    ("slot_line through its pivot", lambda: Linkage().slot_line("D", ("O4", "O4"), "h"), "through two joints"),
    ("on_ray from a joint to itself", lambda: Linkage().on_ray("C", "O4", "O4", "r5"), "'O4' twice"),
    ("rrp with three bodies", lambda: slider().rrp("D", ("C", "r6"), "h", bodies=("a", "b", "c")), "2 names"),
    ("rrr with one body", lambda: Linkage().rrr("B", ("A", "r3"), ("O4", "r4"), bodies=("c",)), "2 names"),
    ("negative literal rod", lambda: slider(rod=("A", -0.3)), "rod length must be positive, got -0.3"),
    ("literal crank 0", lambda: four_bar(crank=0), "crank A length must be positive, got 0"),
    ("literal crank '0 - 0.1'", lambda: four_bar(crank="0 - 0.1"), "crank A length must be positive"),
    ("a line_y the type lacks", lambda: user_type(slider(line_y="zz")), "the linkage reads ['zz']"),
    ("a sign the type lacks", lambda: user_type(slider(sign="s2")), "the linkage reads ['s2']"),
    (
        "a sign that is not a branch",
        lambda: user_type(slider(sign="e"), {"r2": 1.0, "r3": 3.0, "e": 1.0}),
        "its sign 'e' is not a branch sign",
    ),
    ("PARAMS a list", lambda: user_type(slider(), [("r2", 1)]), "PARAMS is a dict of parameter name -> default"),
    ("a default 'x'", lambda: user_type(slider(), {"r2": "x", "r3": 1.0}), "r2's default is a number"),
]


@pytest.mark.parametrize("case, make, words", BUILDER, ids=[c[0] for c in BUILDER])
def test_the_builder_refuses_a_bad_declaration_when_it_is_made(case, make, words):
    with pytest.raises(InvalidParameter) as e:
        make()
    assert words in str(e.value)
    if "PARAMS" not in words and "default" not in words:
        assert isinstance(e.value, LinkageError)


def test_a_degenerate_rrr_of_two_pivots_at_one_point_is_refused():
    L = Linkage()
    L.ground("O2", (0, 0))
    L.crank("A", "O2", "r2")
    L.ground("O4", (0.0, 0.0))
    L.rrr("B", ("O2", "r3"), ("O4", "r4"))
    L.output("theta4")
    with pytest.raises(LinkageError, match="its centres 'O2' and 'O4' are one point"):
        user_type(L, {"r2": 1.0, "r3": 1.0, "r4": 1.0, "sigma": 1.0})


def test_the_declarations_that_were_refused_are_right_when_corrected():
    good = user_type(slider())
    m = good(r2=0.1, r3=0.3, e=0.05)
    ref = mechanism_type("slider-crank")(r2=0.1, r3=0.3, e=0.05)
    assert m.time_ratio() == pytest.approx(ref.time_ratio(), rel=1e-12) and m.stroke() == pytest.approx(ref.stroke())
    assert four_bar(sign=-1) and four_bar(sign=1.0) and four_bar(around=0)


@pytest.mark.parametrize("returned", [None, (1.0, 2.0), {"points": {}}], ids=["None", "tuple", "dict"])
def test_a_user_loop_that_returns_no_loop_is_named(returned):
    class NoLoop(Mechanism):
        PARAMS = {"r2": 1.0}
        LENGTHS = ("r2",)

        @staticmethod
        def loop(xp, theta2, p):
            return returned

    with pytest.raises(InvalidParameter, match=r"NoLoop\.loop must return a Loop .*got " + type(returned).__name__):
        NoLoop()


# ---- relative motion and dynamics ----------------------------------------------------------------------------------
LINKAGE_TYPES = sorted(k for k in SHIPPED if mechanism_type(k).linkage(SHIPPED[k]) is not None)
MOTION = [
    ("theta2 nan", (NAN, 1.0, 0.0), "theta2 (rad) must be finite, got nan"),
    ("theta2 inf", (INF, 1.0, 0.0), "theta2 (rad) must be finite, got inf"),
    ("theta2 None", (None, 1.0, 0.0), "theta2 (rad) must be a number, got None"),
    ("theta2 a list", ([1.0, 2.0], 1.0, 0.0), "theta2 (rad) must be a number, got [1.0, 2.0]"),
    ("theta2 '1'", ("1", 1.0, 0.0), "theta2 (rad) must be a number"),
    ("omega2 nan", (1.0, NAN, 0.0), "omega2 (rad/s) must be finite"),
    ("omega2 1e13", (1.0, 1e13, 0.0), "omega2 (rad/s) = 1e+13 is out of range (|value| <= 1e+12)"),
    ("alpha2 inf", (1.0, 1.0, INF), "alpha2 (rad/s^2) must be finite"),
    ("alpha2 True", (1.0, 1.0, True), "alpha2 (rad/s^2) must be a number, got True"),
]


def test_every_shipped_linkage_type_is_tried():
    assert len(LINKAGE_TYPES) >= 6


@pytest.mark.parametrize("kind", LINKAGE_TYPES)
@pytest.mark.parametrize("case, args, words", MOTION, ids=[c[0] for c in MOTION])
def test_relative_motion_refuses_a_bad_angle_or_rate(kind, case, args, words):
    m = mechanism_type(kind)(**SHIPPED[kind])
    with pytest.raises(InvalidParameter) as e:
        m.relative_motion(*args)
    assert words in str(e.value)


def test_relative_motion_of_good_input_is_finite_and_closes():
    rm = paper_mechanism().relative_motion(1.0, 2.0, 3.0)
    assert all(math.isfinite(row["magnitude"]) for row in rm.table())
    assert max(e.residual for e in rm.equations) < 1e-9


@pytest.mark.parametrize(
    "call, words",
    [
        (lambda m: m.dynamics(1.0, 1e13), "omega2 = 1e+13 is out of range (|value| <= 1e+12)"),
        (lambda m: m.dynamics(1.0, 1.0, -1e13), "alpha2 = -1e+13 is out of range"),
        (lambda m: m.dynamics(1.0, NAN), "omega2 must be finite"),
        (lambda m: m.dynamic_extremes(2e12), "omega2 = 2e+12 is out of range"),
        (lambda m: m.flywheel(1e13, 0.05), "omega2 = 1e+13 is out of range"),
    ],
    ids=["dynamics omega2", "dynamics alpha2", "dynamics nan", "extremes", "flywheel"],
)
def test_dynamics_applies_the_speed_limit(call, words):
    with pytest.raises(InvalidParameter) as e:
        call(paper_mechanism())
    assert words in str(e.value)


@pytest.mark.parametrize(
    "counterweight, words",
    [
        ({"mass": 1.0}, "{mass, radius, angle?, free?}"),
        ({"radius": 0.1}, "{mass, radius, angle?, free?}"),
        ({"mass": 1.0, "radius": 0.1, "colour": "red"}, "{mass, radius, angle?, free?}"),
        ({"mass": "x", "radius": 0.1}, "the counterweight's mass must be a number"),
        ({"mass": 1.0, "radius": 0.1, "free": "yes"}, "free is true or false"),
        ([1.0, 0.1], "{mass, radius, angle?, free?}"),
    ],
)
def test_a_bad_counterweight_is_a_typed_error(counterweight, words):
    with pytest.raises(InvalidParameter) as e:
        qropt.Masses(counterweight=counterweight)
    assert words in str(e.value)
    with pytest.raises(InvalidParameter):
        qropt.Masses.from_dict({"counterweight": counterweight})


# ---- every reader of a user file -----------------------------------------------------------------------------------
def oversized(folder: Path, name: str) -> Path:
    """A sparse file one byte over the readers' limit (it takes no disk)."""
    f = folder / name
    with open(f, "wb") as fh:
        fh.truncate(validate.MAX_FILE + 1)
    return f


def fifo(folder: Path, name: str) -> Path:
    """A named pipe nobody writes to: opening it for reading would wait for ever."""
    f = folder / name
    os.mkfifo(f)
    return f


def answered(call, seconds=30.0):
    """What ``call()`` raised, in a thread that must end within ``seconds`` (a reader that blocks fails here)."""
    out = {}

    def run():
        try:
            call()
        except Exception as e:  # noqa: BLE001 - the test inspects what was raised
            out["error"] = e

    t = threading.Thread(target=run, daemon=True)
    t.start()
    t.join(seconds)
    assert not t.is_alive(), "the reader did not answer"
    return out.get("error")


READERS = [
    ("load_design", lambda p: load_design(p), InvalidParameter, "design file"),
    ("read_design", lambda p: read_design(p), InvalidParameter, "design file"),
    ("Chart.from_json", lambda p: Chart.from_json(p), ChartError, "not a qropt chart file"),
    ("load_problem .json", lambda p: cli.load_problem(str(p)), ProblemError, "problem file"),
    ("load_problem .toml", lambda p: cli.load_problem(str(p)), ProblemError, "problem file"),
    ("load_problem .py", lambda p: cli.load_problem(str(p)), ProblemError, "problem file"),
]
SUFFIX = {"load_problem .toml": ".toml", "load_problem .py": ".py"}


@pytest.mark.parametrize("case, read, error, words", READERS, ids=[c[0] for c in READERS])
@pytest.mark.parametrize("make, why", [(oversized, "at most 16,777,216"), (fifo, "is not a regular file")])
def test_every_file_reader_refuses_a_pipe_and_an_oversized_file(case, read, error, words, make, why, tmp_path):
    path = make(tmp_path, "bad" + SUFFIX.get(case, ".json"))
    e = answered(lambda: read(path))
    assert isinstance(e, error), repr(e)
    assert why in str(e) and words in str(e) and "\n" not in str(e)


def test_a_design_reader_refuses_a_device_and_a_folder(tmp_path):
    for path, why in (("/dev/zero", "is not a regular file"), (tmp_path, "is not a regular file")):
        e = answered(lambda p=path: load_design(p))
        assert isinstance(e, InvalidParameter) and why in str(e)


@pytest.mark.parametrize(
    "text, words",
    [
        ('{"type": "slider-crank", "params": {"r2": NaN, "r3": 0.3}}', "NaN is not a JSON number"),
        ('{"type": "slider-crank", "params": {"r2": Infinity}}', "Infinity is not a JSON number"),
        ("[" * 300 + "]" * 300, "nested too deeply (more than 200 levels)"),
        (b"\xff\xfe", "not UTF-8 text"),
    ],
    ids=["nan", "infinity", "deep", "not utf-8"],
)
def test_a_design_file_is_strict_json(text, words, tmp_path):
    f = tmp_path / "d.json"
    f.write_bytes(text if isinstance(text, bytes) else text.encode())
    with pytest.raises(InvalidParameter) as e:
        load_design(f)
    assert words in str(e.value)


def cli_run(*args, cwd=ROOT, timeout=120):
    code = "import sys; from qropt.cli import main; sys.exit(main(sys.argv[1:]))"
    return subprocess.run([sys.executable, "-c", code, *args], capture_output=True, text=True, timeout=timeout, cwd=cwd)


@pytest.mark.parametrize(
    "args, words",
    [
        (["analyze", "--from", "/dev/zero"], "/dev/zero is not a regular file"),
        (["tolerance", "/dev/zero", "--limit", "time_ratio=0.01"], "/dev/zero is not a regular file"),
        (["synth", "{fifo}.toml"], "is not a regular file"),
        (["analyze", "--from", "{big}.json"], "a design file has at most 16,777,216"),
        (["synth", "{big}.json"], "a problem file has at most 16,777,216"),
    ],
    ids=["analyze device", "tolerance device", "synth pipe", "analyze oversized", "synth oversized"],
)
def test_the_cli_refuses_a_file_it_cannot_read_in_one_line(args, words, tmp_path):
    fifo(tmp_path, "p.toml")
    oversized(tmp_path, "big.json")
    args = [a.replace("{fifo}", str(tmp_path / "p")).replace("{big}", str(tmp_path / "big")) for a in args]
    r = cli_run(*args, timeout=60)  # it answers at once: a reader that blocks or reads the device fails here
    assert r.returncode != 0 and r.stdout == ""
    assert r.stderr.count("\n") == 1 and words in r.stderr and "Traceback" not in r.stderr


def test_project_with_an_empty_output_path_writes_nothing(tmp_path):
    for extra in ([], ["--count", "2"]):
        r = cli_run("project", "--seed", "1", "-o", "", *extra, cwd=tmp_path)
        assert r.returncode == 2 and r.stderr.count("\n") == 1 and "output path is empty" in r.stderr
    assert list(tmp_path.iterdir()) == []


def test_an_empty_output_path_is_refused_by_the_library():
    for path in ("", " "):
        with pytest.raises(InvalidParameter, match="the picture path is empty"):
            picture_path(path)


# ---- the web API -------------------------------------------------------------------------------------------------
flask = pytest.importorskip("flask")


@pytest.fixture(scope="module")
def client():
    from qropt.app import create_app

    app = create_app(workers=1, queue_size=2, time_limit=60)
    yield app.test_client()
    app.extensions["qropt_jobs"].close()


GOOD = {"type": "slider-crank", "params": SHIPPED["slider-crank"]}
BODIES = [
    ("5,000 nested arrays", "[" * 5000 + "]" * 5000, "nested too deeply (more than 200 levels)"),
    ("3,000 nested objects", '{"a": ' * 3000 + "1" + "}" * 3000, "nested too deeply"),
    ("nan in the body", '{"type": "slider-crank", "params": {"r2": NaN}}', "NaN is not a JSON number"),
    ("not UTF-8", b"\xff\xfe{}", "not UTF-8 text"),
    ("not JSON", "{", "the request body is not JSON"),
]


@pytest.mark.parametrize("case, body, words", BODIES, ids=[c[0] for c in BODIES])
def test_a_malformed_body_is_a_400_and_the_server_goes_on(client, case, body, words):
    r = client.post("/api/analyze", data=body, content_type="application/json")
    assert r.status_code == 400, r.get_json()
    err = r.get_json()["error"]
    assert words in err and "\n" not in err and "Traceback" not in err
    assert client.get("/api/health").status_code == 200


ANALYZE = [
    ("polygons 'yes'", {"polygons": "yes"}, "polygons is true or false"),
    ("polygons 1", {"polygons": 1}, "polygons is true or false"),
    ("polygons null", {"polygons": None}, "polygons is true or false"),
    ("extremes 'no'", {"extremes": "no"}, "extremes is true or false"),
    ("half a counterweight", {"masses": {"counterweight": {"mass": 1.0}}}, "{mass, radius, angle?, free?}"),
    ("theta2 1e300", {"theta2": 1e300}, "theta2 must lie in"),
]


@pytest.mark.parametrize("case, extra, words", ANALYZE, ids=[c[0] for c in ANALYZE])
def test_every_analyze_field_is_checked(client, case, extra, words):
    r = client.post("/api/analyze", json={**GOOD, **extra})
    assert r.status_code == 400, r.get_json()
    assert words in r.get_json()["error"]


JOBS = [
    ("report theta2 'nan'", {"kind": "report", "input": {**GOOD, "theta2": "nan"}}, "theta2 is a finite number"),
    ("report omega2 0", {"kind": "report", "input": {**GOOD, "omega2": 0}}, "omega2 must be nonzero"),
    ("report theta2 1e300", {"kind": "report", "input": {**GOOD, "theta2": 1e300}}, "theta2 must lie in"),
    (
        "design half a counterweight",
        {"kind": "design", "input": {"time_ratio": 1.5, "stroke": 0.3, "masses": {"counterweight": {"mass": 1}}}},
        "{mass, radius, angle?, free?}",
    ),
    (
        "design an unknown condition",
        {"kind": "design", "input": {"time_ratio": 1.5, "stroke": 0.3, "conditions": {"zz": 1.0}}},
        "zz",
    ),
    (
        "design torque without masses",
        {"kind": "design", "input": {"time_ratio": 1.5, "stroke": 0.3, "objective": "min_peak_torque"}},
        "needs masses or loads",
    ),
    (
        "design a bound the types lack",
        {"kind": "design", "input": {"time_ratio": 1.5, "stroke": 0.3, "bounds": {"zz": [0, 1]}}},
        "bounds name ['zz']",
    ),
]


@pytest.mark.parametrize("case, body, words", JOBS, ids=[c[0] for c in JOBS])
def test_a_job_is_checked_whole_before_it_is_queued(client, case, body, words):
    jobs = client.application.extensions["qropt_jobs"]
    before = len(jobs._jobs)
    r = client.post("/api/jobs", json=body)
    assert r.status_code == 400, r.get_json()
    assert words in r.get_json()["error"] and len(jobs._jobs) == before  # nothing queued
