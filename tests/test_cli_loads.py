"""General loads on the command line: --loads FILE (JSON or TOML), --gravity GX GY and --point-mass JOINT KG, one
set of options and one reader for analyze --dynamics, design, synth and report; the numbers are the library's
under the same loads; a loads file that does not read, does not parse or names a joint the design lacks is one
line and a non-zero exit."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

import qropt
from qropt import cli

SHAPER_FILE = Path(__file__).parents[1] / "problems" / "crank_shaper_torque.toml"  # 3.14 kg/m bars, a 20 kg ram
SHAPER = ["crank-shaper", "--r1", "0.2", "--r2", "0.08", "--r4", "0.5"]
LOADS = qropt.Loads(
    forces=[
        qropt.Force("C", 600.0, "against", "working"),
        qropt.Force(("lever", 0.35, 0.0), 300.0, (0.0, -1.0), "always"),
    ],
    torques=[qropt.Torque("lever", -20.0)],
    gravity=(-3.0, -9.3),
)
TOML = """gravity = [-3.0, -9.3]

[[forces]]
at = "C"
magnitude = 600.0
direction = "against"
window = "working"

[[forces]]
at = ["lever", 0.35, 0.0]
magnitude = 300.0
direction = [0.0, -1.0]
window = "always"

[[torques]]
on = "lever"
magnitude = -20.0
"""


@pytest.fixture
def loads_json(tmp_path):
    path = tmp_path / "loads.json"
    path.write_text(json.dumps(LOADS.to_dict()))
    return path


def _one_line(capsys) -> str:
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "Traceback" not in err, err
    return err


def test_the_file_reads_back_as_the_loads(loads_json, tmp_path):
    toml = tmp_path / "loads.toml"
    toml.write_text(TOML)
    assert cli.read_loads(str(loads_json)) == LOADS
    assert cli.read_loads(str(toml)) == LOADS


@pytest.mark.parametrize("suffix", [".json", ".toml"])
def test_analyze_with_a_loads_file_and_a_point_mass(suffix, loads_json, tmp_path, capsys):
    """The peaks are the library's under the file's loads and the point mass; the picture is written."""
    path = loads_json if suffix == ".json" else tmp_path / "loads.toml"
    if suffix == ".toml":
        path.write_text(TOML)
    plot = tmp_path / "forces.png"
    argv = ["analyze", *SHAPER, "--omega2", "10", "--dynamics", "--density", "3.14", "--ram-mass", "20"]
    assert cli.main([*argv, "--loads", str(path), "--point-mass", "A", "1.5", "--plot", str(plot), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    m = qropt.CrankShaper(r1=0.2, r2=0.08, r4=0.5)
    ex = m.dynamic_extremes(10.0, masses=qropt.Masses.bars(3.14, 20.0, points={"A": 1.5}), loads=LOADS)
    assert out["peak_torque"]["value"] == pytest.approx(ex.peak_torque.value, rel=1e-12)
    assert plot.stat().st_size > 10_000


def test_analyze_takes_gravity_as_a_vector_and_the_text_names_the_loads(loads_json, capsys):
    argv = ["analyze", *SHAPER, "--omega2", "10", "--dynamics", "--density", "3.14", "--ram-mass", "20"]
    assert cli.main([*argv, "--force", "600", "--gravity", "-9.81", "0"]) == 0
    head = capsys.readouterr().out.splitlines()[0]
    assert "cutting force 600 N" in head and "gravity (-9.81, 0) m/s^2" in head
    assert cli.main([*argv, "--loads", str(loads_json)]) == 0
    assert "3 more loads (--loads)" in capsys.readouterr().out


def test_design_with_a_loads_file(loads_json, capsys, tmp_path):
    """The row's peak torque is the library's exact value of its design under the file's loads and the point
    mass; the cut stated as a force gives the shorthand's row."""
    cut = tmp_path / "cut.json"
    cut.write_text(json.dumps({"forces": [{"at": "C", "magnitude": 1000.0}], "gravity": 9.81}))
    argv = ["design", "--tr", "1.5", "--stroke", "0.3", "--types", "crank-shaper", "--objective", "min_peak_torque"]
    dyn = ["--density", "2", "--ram-mass", "5", "--omega2", "10", "--json"]
    assert cli.main([*argv, *dyn, "--loads", str(cut), "--point-mass", "A", "1"]) == 0
    row = json.loads(capsys.readouterr().out)["rows"][0]
    m = qropt.CrankShaper(**row["params"])
    masses = qropt.Masses.bars(2.0, 5.0, points={"A": 1.0})
    loads = qropt.Loads(forces=[qropt.Force("C", 1000.0)], gravity=9.81)
    assert row["peak_torque"] == pytest.approx(m.dynamic_extremes(10.0, masses=masses, loads=loads).peak_torque.value)
    assert cli.main([*argv, *dyn, "--force", "1000", "--gravity", "9.81", "--point-mass", "A", "1"]) == 0
    short = json.loads(capsys.readouterr().out)["rows"][0]
    assert short["peak_torque"] == pytest.approx(row["peak_torque"], rel=1e-6)


def test_synth_with_a_loads_file(tmp_path, capsys):
    """--loads replaces the problem file's loads and --point-mass adds to its masses: the objective is the exact
    peak torque of the design under them."""
    loads = qropt.Loads(forces=[qropt.Force("C", 600.0), qropt.Force("A", 150.0, (0.0, -1.0), "always")])
    path = tmp_path / "loads.json"
    path.write_text(json.dumps(loads.to_dict()))
    assert cli.main(["synth", str(SHAPER_FILE), "--loads", str(path), "--point-mass", "A", "1.5", "--json"]) == 0
    r = json.loads(capsys.readouterr().out)
    m = qropt.CrankShaper(**r["params"])
    masses = qropt.Masses.bars(3.14, 20.0, points={"A": 1.5})  # the file's masses and the point mass
    exact = m.dynamic_extremes(10.0, masses=masses, loads=loads).peak_torque.value
    assert r["objective"] == pytest.approx(exact, rel=1e-6)


def test_report_of_a_problem_with_a_loads_file(loads_json, tmp_path, capsys):
    out = tmp_path / "shaper.html"
    assert (
        cli.main(["report", str(SHAPER_FILE), "--loads", str(loads_json), "--point-mass", "A", "1.5", "-o", str(out)])
        == 0
    )
    text = out.read_text()
    assert "Forces and torque (the problem&#x27;s masses, loads as given)" in text
    for cell in ("<td>F1</td><td>C</td>", "<td>F2</td><td>(lever, 0.35, 0)</td>", "<td>T1</td><td>the lever</td>"):
        assert cell in text
    assert "<td>point mass</td><td>A</td>" in text and "<td>gravity</td>" in text
    assert text.count("data:image/png") >= 2  # the cycle and the forces


BAD = [
    ("broken.json", '{"forces": [', "is not JSON"),
    ("broken.toml", "gravity = [", "is not TOML"),
    ("keys.json", '{"forcez": []}', "loads take"),
    ("joint.json", '{"forces": [{"at": "Q", "magnitude": 1.0}]}', "no joint 'Q'"),
    ("body.json", '{"torques": [{"on": "wheel", "magnitude": 1.0}]}', "no body 'wheel'"),
    ("window.json", '{"forces": [{"at": "C", "magnitude": 1.0, "window": "sometimes"}]}', "a window is named"),
]


@pytest.mark.parametrize(("name", "text", "words"), BAD, ids=[b[0] for b in BAD])
@pytest.mark.parametrize("command", ["analyze", "report", "design"])
def test_a_bad_loads_file_is_one_line(command, name, text, words, tmp_path, capsys):
    path = tmp_path / name
    path.write_text(text)
    argv = {
        "analyze": ["analyze", *SHAPER, "--omega2", "10", "--dynamics", "--density", "3"],
        "report": ["report", "-o", str(tmp_path / "r.html")],
        "design": ["design", "--tr", "1.5", "--stroke", "0.3", "--types", "crank-shaper"],
    }[command]
    if command == "report":
        path.write_text(text.replace('"C"', '"D"'))  # the paper's drag-link-slider: its ram's joint is D
    assert cli.main([*argv, "--loads", str(path)]) != 0
    assert words in _one_line(capsys)
    assert not (tmp_path / "r.html").exists()


@pytest.mark.parametrize(
    ("extra", "words"),
    [
        (["--force", "100"], "not both"),
        (["--gravity", "1", "2", "3"], "one number (along -y) or two"),
        (["--point-mass", "A", "heavy"], "not a number"),
        (["--point-mass", "Q", "1"], "Q"),
    ],
)
def test_bad_load_options_are_one_line(extra, words, loads_json, capsys):
    argv = ["analyze", *SHAPER, "--omega2", "10", "--dynamics", "--density", "3"]
    if extra[0] == "--force":
        extra = [*extra, "--loads", str(loads_json)]
    assert cli.main([*argv, *extra]) != 0
    assert words in _one_line(capsys)


def test_every_dynamic_command_takes_the_same_options():
    p = cli.parser()
    subs = p._subparsers._group_actions[0].choices
    for name in ("analyze", "design", "synth", "report"):
        flags = {o for a in subs[name]._actions for o in a.option_strings}
        assert {"--loads", "--point-mass"} <= flags, name
    for name in ("analyze", "design"):
        flags = {a.dest: a for a in subs[name]._actions}
        assert flags["gravity"].nargs == "+" and flags["force"].default is None, name


def test_report_of_the_papers_project_under_a_loads_file(tmp_path, capsys):
    """The paper's design (its joints O2, A, B, C, D; bodies crank, coupler, follower, rod, ram) under a force at
    a coupler point, a torque on the crank in a window of theta2 and gravity along -x, with a point mass at B."""
    loads = qropt.Loads(
        forces=[qropt.Force("D", 1000.0), qropt.Force(("coupler", 0.05, 0.0), 200.0, (1.0, -1.0), "always")],
        torques=[qropt.Torque("crank", 10.0, qropt.Window(theta2=(0.0, 3.0)))],
        gravity=(-9.81, 0.0),
    )
    path = tmp_path / "paper_loads.json"
    path.write_text(json.dumps(loads.to_dict()))
    out = tmp_path / "paper.html"
    assert cli.main(["report", "--loads", str(path), "--point-mass", "B", "2", "-o", str(out)]) == 0
    text = out.read_text()
    section = text[text.index("<h2>Forces and torque") :]
    section = section[: section.index("<h2>", 5)]
    assert "(assumed masses, loads as given)" in section and "point masses B 2 kg" in section
    assert "<td>T1</td><td>the crank</td><td>counter-clockwise positive</td><td>10 N m</td>" in section
    assert "<td>gravity</td><td>every body&#x27;s centre of mass</td><td>(-9.81, 0), 180 deg from +x</td>" in section
    from qropt.examples import paper_mechanism
    from qropt.io.report import FORCES

    masses = qropt.Masses.steel(FORCES["area"], FORCES["ram"], points={"B": 2.0})
    ex = paper_mechanism().dynamic_extremes(FORCES["omega2"], masses=masses, loads=loads)
    assert f"<td>{ex.peak_torque.value:.6g}</td>" in section
    assert section.count("data:image/png") == 1
