"""The report states its loads: a table of each force and torque (named as the figure names them: its point,
direction, magnitude and window), the shorthands, gravity, pin friction and the point masses; the forces section
under given loads carries the library's numbers and the figure with the loads drawn."""

from __future__ import annotations

import math
import re

import pytest

import qropt
from qropt.examples import paper_mechanism
from qropt.io.report import FORCES, _forces, loads_table, render


def _rows(html: str) -> list[list[str]]:
    return [re.findall(r"<td>(.*?)</td>", r) for r in re.findall(r"<tr>(.*?)</tr>", html) if "<td>" in r]


def test_the_table_states_every_load():
    loads = qropt.Loads(
        cutting_force=((0.1, 0.0), (0.2, 800.0)),
        friction=0.1,
        forces=[
            qropt.Force("D", 150.0, "slide", qropt.Window(x=(0.25, 0.45), stroke="return")),
            qropt.Force(("follower", 0.1, 0.0), 40.0, (0.0, -1.0), "always"),
            qropt.Force("C", ((0.0, 10.0), (math.pi, 20.0)), against="theta2"),
        ],
        torques=[qropt.Torque("follower", -5.0, qropt.Window(theta2=(0.0, math.pi)))],
        gravity=(0.0, -9.81),
        pin_friction=qropt.PinFriction(0.1, 0.01, {"A": (0.2, 0.02)}),
    )
    rows = _rows(loads_table(loads, qropt.Masses(points={"C": 1.5}), "m"))
    by = {r[0]: r for r in rows}
    assert [r[0] for r in rows] == [
        "cutting force",
        "slide friction",
        "F1",
        "F2",
        "F3",
        "T1",
        "gravity",
        "pin friction",
        "point mass",
    ]
    assert by["cutting force"][3].startswith("0 .. 800 N, a table against x [m]")
    assert by["F1"] == [
        "F1",
        "D",
        "along the slide line&#x27;s +x (signed)",
        "150 N",
        "x from 0.25 to 0.45 m, on the return stroke",
    ]
    assert by["F2"][1:4] == ["(follower, 0.1, 0)", "fixed: (0, -1), -90 deg from +x", "40 N"]
    assert by["F2"][4] == "always"
    assert (
        by["F3"][2] == "against its point&#x27;s velocity"
        and "a table against theta2 (0 deg: 10; 180 deg: 20)" in by["F3"][3]
    )
    assert by["F3"][4] == "on the working stroke"
    assert by["T1"] == ["T1", "the follower", "counter-clockwise positive", "-5 N m", "theta2 from 0 to 180 deg"]
    assert by["gravity"][2:4] == ["(0, -9.81), -90 deg from +x", "9.81 m/s^2"]
    assert "A: mu 0.2, r 0.02 m" in by["pin friction"][1] and by["pin friction"][3] == "mu 0.1"
    assert by["point mass"][1:4] == ["C", "", "1.5 kg"]
    assert "No loads" in loads_table(qropt.Loads())
    (named,) = _rows(loads_table(qropt.Loads(1000.0, working="+x")))[1:]
    assert named[0] == "working stroke" and named[2] == "moves +x"


def test_the_assumed_forces_section_states_its_load():
    text = _forces(paper_mechanism())
    assert "Forces and torque (assumed masses and load)" in text and "20 mm x 10 mm" in text
    rows = {r[0]: r for r in _rows(text)}
    assert rows["cutting force"][3] == "1000 N" and rows["gravity"][3] == "9.81 m/s^2"


def test_the_paper_under_given_loads_and_a_point_mass():
    """The paper's design under a force at a coupler point and a tilted gravity: the section's peak torque is the
    library's under the assumed masses with the point mass, and the figure is there."""
    m = paper_mechanism()
    loads = qropt.Loads(forces=[qropt.Force("D", 800.0)], torques=[qropt.Torque("crank", 5.0)], gravity=(2.0, -9.6))
    text = _forces(m, loads=loads, points={"B": 2.0}, source="as given")
    masses = qropt.Masses.steel(FORCES["area"], FORCES["ram"], points={"B": 2.0})
    ex = m.dynamic_extremes(FORCES["omega2"], masses=masses, loads=loads)
    assert f"<td>{ex.peak_torque.value:.6g}</td>" in text
    assert "assumed masses, loads as given" in text and "point masses B 2 kg" in text
    rows = {r[0]: r for r in _rows(text)}
    assert rows["F1"][1] == "D" and rows["T1"][1] == "the crank" and rows["point mass"][1:4] == ["B", "", "2 kg"]
    assert text.count("data:image/png") == 1


def test_render_checks_the_loads_before_any_section(tmp_path):
    bad = qropt.Loads(forces=[qropt.Force("Q", 1.0)])
    with pytest.raises(qropt.InvalidParameter, match="no joint 'Q'"):
        render(None, tmp_path / "r.html", loads=bad)
    with pytest.raises(qropt.InvalidParameter, match="Loads"):
        render(None, tmp_path / "r.html", loads={"forces": []})
    assert not (tmp_path / "r.html").exists()


def test_a_problem_with_masses_and_loads_reports_its_forces():
    problem = qropt.Problem(
        "slider-crank",
        free={"r2": (0.015, 1.5), "r3": (0.015, 1.5), "e": (-1.5, 1.5)},
        targets={"time_ratio": 1.2, "stroke": 0.3},
        conditions={"gamma_min": math.radians(30)},
        objective="min_peak_torque",
        masses=qropt.Masses.bars(2.0, 5.0),
        loads=qropt.Loads(forces=[qropt.Force("C", 500.0)], gravity=(0.0, -9.81)),
        omega2=10.0,
    )
    text = render(problem)
    assert "Forces and torque (the problem&#x27;s masses and loads)" in text
    rows = {r[0]: r for r in _rows(text)}
    assert rows["F1"][1:4] == ["C", "against its point&#x27;s velocity", "500 N"]
    plain = qropt.Problem("slider-crank", free=problem.free, targets=problem.targets, conditions=problem.conditions)
    assert "Forces and torque" not in render(plain)
