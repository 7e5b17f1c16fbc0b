"""The dynamics on the command line and in the report: the same numbers as the library, one-line errors."""

from __future__ import annotations

import csv
import json
import math

import numpy as np
import pytest

import qropt
from qropt import cli
from qropt.examples import paper_mechanism

ARGS = ["analyze", "--omega2", "10", "--dynamics", "--density", "1.57", "--ram-mass", "20", "--force", "1000"]


def _library():
    m = paper_mechanism()
    masses, loads = qropt.Masses.bars(1.57, 20.0), qropt.Loads(1000.0)
    return m, masses, loads, m.dynamic_extremes(10.0, masses=masses, loads=loads)


def test_the_json_carries_the_librarys_peaks_and_flywheel(capsys):
    assert cli.main([*ARGS, "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    m, masses, loads, ex = _library()
    assert out["peak_torque"]["value"] == pytest.approx(ex.peak_torque.value, rel=1e-12)
    assert out["rms_torque"] == pytest.approx(ex.rms_torque, rel=1e-12)
    assert {k: v["value"] for k, v in out["peak_forces"].items()} == pytest.approx(
        {k: p.value for k, p in ex.peak_forces.items()}, rel=1e-12
    )
    fw = m.flywheel(10.0, 0.05, masses=masses, loads=loads)
    assert out["flywheel"]["inertia"] == pytest.approx(fw.inertia, rel=1e-12)
    assert out["flywheel"]["energy_per_turn"] == pytest.approx(300.0, rel=1e-9)  # 1000 N over the 0.3 m stroke


def test_text_plot_and_csv(tmp_path, capsys):
    png, table = tmp_path / "forces.png", tmp_path / "forces.csv"
    assert cli.main([*ARGS, "--plot", str(png), "--csv", str(table)]) == 0
    text = capsys.readouterr().out
    assert "peak torque" in text and "flywheel" in text and "peak force O4" in text
    assert png.stat().st_size > 20_000
    rows = list(csv.DictReader(table.open()))
    assert len(rows) == 360
    m, masses, loads, _ = _library()
    d = m.dynamics(np.radians([float(r["theta2_deg"]) for r in rows]), 10.0, masses=masses, loads=loads)
    assert [float(r["torque_Nm"]) for r in rows] == pytest.approx(d.torque, rel=1e-9, abs=1e-9)
    assert [float(r["O4_x_N"]) for r in rows] == pytest.approx(d.joint_forces["O4"][:, 0], rel=1e-9, abs=1e-9)


@pytest.mark.parametrize(
    "extra, words",
    [
        (["--density", "-1"], "density"),
        (["--force", "-5"], "cutting_force"),
        (["--cs", "3"], "cs"),
        (["--omega2", "0"], "omega2"),
        (["--counterweight", "5", "x", "180deg"], "not a number"),
        (["--counterweight", "-5", "0.1", "180deg"], "counterweight's mass"),
    ],
)
def test_bad_dynamics_input_is_one_line(extra, words, capsys):
    assert cli.main([*ARGS, *extra]) != 0
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and words in err and "Traceback" not in err


def _peak(capsys, args) -> float:
    assert cli.main([*args, "--json"]) == 0
    return json.loads(capsys.readouterr().out)["peak_torque"]["value"]


def test_gravity_as_a_vector_point_masses_and_a_loads_file(tmp_path, capsys):
    """--gravity GX GY (one number still means along -y), --point-mass JOINT KG and --loads FILE (JSON or TOML of
    Loads.to_dict): each the library's number; the cutting force stated as a general force in a file gives the
    shorthand's peak."""
    base = ["analyze", "--omega2", "10", "--dynamics", "--density", "1.57", "--ram-mass", "20"]
    m = paper_mechanism()
    assert _peak(capsys, [*base, "--gravity", "0", "-9.81"]) == _peak(capsys, [*base, "--gravity", "9.81"])
    side = _peak(capsys, [*base, "--gravity", "-9.81", "0", "--point-mass", "C", "2", "--point-mass", "B", "0.5"])
    masses = qropt.Masses.bars(1.57, 20.0, points={"C": 2.0, "B": 0.5})
    ex = m.dynamic_extremes(10.0, masses=masses, loads=qropt.Loads(gravity=(-9.81, 0.0)))
    assert side == pytest.approx(ex.peak_torque.value, rel=1e-12)
    loads = qropt.Loads(forces=[qropt.Force("D", 1000.0)], gravity=(0.0, -9.81))
    as_json, as_toml = tmp_path / "loads.json", tmp_path / "loads.toml"
    as_json.write_text(json.dumps(loads.to_dict()))
    import tomli_w

    as_toml.write_text(tomli_w.dumps(loads.to_dict()))
    shorthand = _peak(capsys, [*base, "--force", "1000", "--gravity", "9.81"])
    assert _peak(capsys, [*base, "--loads", str(as_json)]) == pytest.approx(shorthand, rel=1e-12)
    assert _peak(capsys, [*base, "--loads", str(as_toml)]) == pytest.approx(shorthand, rel=1e-12)
    for extra, words in (
        (["--loads", str(as_json), "--force", "5"], "not both"),
        (["--gravity", "1", "2", "3"], "one number"),
        (["--loads", str(tmp_path)], "not a regular file"),
        (["--point-mass", "Z", "1"], "Z"),
    ):
        assert cli.main([*base, *extra]) != 0
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and words in err and "Traceback" not in err, err


def test_the_report_states_its_assumptions_and_the_librarys_numbers():
    from qropt.io.report import FORCES, _forces

    m = paper_mechanism()
    text = _forces(m)
    ex = m.dynamic_extremes(
        FORCES["omega2"],
        masses=qropt.Masses.steel(FORCES["area"], FORCES["ram"]),
        loads=qropt.Loads(FORCES["force"], gravity=FORCES["gravity"]),
    )
    assert "20 mm x 10 mm" in text and "20 kg ram" in text and "1000 N" in text
    assert f"<td>{ex.peak_torque.value:.6g}</td>" in text
    assert f"<td>{math.degrees(ex.peak_torque.theta2):.6g}</td>" in text


def test_design_by_min_peak_torque_on_the_command_line(capsys):
    """The rows' peak torque is the library's exact value of the design each row returns."""
    argv = ["design", "--tr", "1.5", "--stroke", "0.3", "--types", "crank-shaper", "--objective", "min_peak_torque"]
    dyn = ["--density", "2", "--ram-mass", "5", "--force", "1000", "--gravity", "9.81", "--omega2", "10", "--json"]
    assert cli.main([*argv, *dyn]) == 0
    row = json.loads(capsys.readouterr().out)["rows"][0]
    m = qropt.CrankShaper(**{k: v for k, v in row["params"].items()})
    masses, loads = qropt.Masses.bars(2.0, 5.0), qropt.Loads(1000.0, gravity=9.81)
    assert row["peak_torque"] == pytest.approx(m.dynamic_extremes(10.0, masses=masses, loads=loads).peak_torque.value)
    assert cli.main(argv) != 0  # no masses and no loads: a one-line reason
    assert "needs masses or loads" in capsys.readouterr().err


def test_design_with_friction_on_the_command_line(capsys):
    """--friction reaches the solve: the row's peak torque is the library's exact value with the slide's friction,
    and differs from the frictionless row's."""
    argv = ["design", "--tr", "1.5", "--stroke", "0.3", "--types", "slider-crank", "--objective", "min_peak_torque"]
    dyn = ["--density", "1.57", "--ram-mass", "20", "--force", "1000", "--gravity", "9.81", "--omega2", "10", "--json"]
    assert cli.main([*argv, *dyn, "--friction", "0.2"]) == 0
    row = json.loads(capsys.readouterr().out)["rows"][0]
    assert cli.main([*argv, *dyn]) == 0
    plain = json.loads(capsys.readouterr().out)["rows"][0]
    m = qropt.SliderCrank(**row["params"])
    masses, loads = qropt.Masses.bars(1.57, 20.0), qropt.Loads(1000.0, friction=0.2, gravity=9.81)
    exact = m.dynamic_extremes(10.0, masses=masses, loads=loads).peak_torque.value
    assert row["peak_torque"] == pytest.approx(exact, rel=1e-9)
    assert row["peak_torque"] > plain["peak_torque"] * 1.05
    assert cli.main([*argv, *dyn, "--friction", "-1"]) != 0
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "friction" in err


def test_a_counterweight_on_the_command_line_is_the_librarys(capsys):
    assert cli.main([*ARGS, "--counterweight", "5", "0.1", "180deg", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    m = paper_mechanism()
    masses = qropt.Masses.bars(1.57, 20.0, counterweight=qropt.Counterweight(5.0, 0.1, math.pi))
    ex = m.dynamic_extremes(10.0, masses=masses, loads=qropt.Loads(1000.0))
    assert out["peak_forces"]["O2"]["value"] == pytest.approx(ex.peak_forces["O2"].value, rel=1e-12)
    assert out["peak_forces"]["O2"]["value"] != pytest.approx(_library()[3].peak_forces["O2"].value, rel=1e-3)


def test_design_balances_with_a_free_counterweight_on_the_command_line(capsys):
    """--balance leaves each row's counterweight to the solve; the row's shaking force is the library's with the
    counterweight its result chose, and lower than without one."""
    argv = ["design", "--tr", "1.5", "--stroke", "0.3", "--types", "slider-crank", "--objective", "min_shaking_force"]
    dyn = ["--density", "3.14", "--ram-mass", "20", "--force", "1000", "--omega2", "10", "--json"]
    assert cli.main([*argv, *dyn, "--balance", "0.1", "30"]) == 0
    row = json.loads(capsys.readouterr().out)["rows"][0]
    assert cli.main([*argv, *dyn]) == 0
    plain = json.loads(capsys.readouterr().out)["rows"][0]
    cw = qropt.Counterweight(**row["counterweight"])
    assert plain["counterweight"] is None
    m = qropt.SliderCrank(**row["params"])
    masses = qropt.Masses.bars(3.14, 20.0, counterweight=cw)
    exact = m.dynamic_extremes(10.0, masses=masses, loads=qropt.Loads(1000.0)).peak_shaking_force.value
    assert row["shaking_force"] == pytest.approx(exact, rel=1e-9)
    assert row["shaking_force"] < 0.8 * plain["shaking_force"]
