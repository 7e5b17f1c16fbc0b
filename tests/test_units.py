"""A stated length unit: a problem or mechanism states it once (``units="mm"``), lengths stay plain numbers in
it, and every printout, axis, table and export names it; files keep it and read it back."""

from __future__ import annotations

import csv
import json

import matplotlib
import pytest

matplotlib.use("Agg")

import qropt
from qropt import cli as qropt_cli
from qropt.errors import InvalidParameter, ProblemError
from qropt.examples import paper_problem
from qropt.io import export, plots
from qropt.studies._design import design

MM = 1000.0  # millimetres per metre


def _scaled(p: qropt.Problem, k: float, units: str) -> qropt.Problem:
    """The problem with every length times k (rounded to 12 digits: 0.1 * 1000 is 100, not 100.00000000000001),
    stated in ``units``."""

    def x(v):
        return float(f"{v * k:.12g}")

    return p.replace(
        fixed={n: x(v) for n, v in p.fixed.items() if n not in p.mechanism.BRANCHES},
        free={n: (x(lo), x(hi)) for n, (lo, hi) in p.free.items()},
        targets={n: x(v) if n == "stroke" else v for n, v in p.targets.items()},
        units=units,
    )


@pytest.fixture(scope="module")
def solved():
    p_m = paper_problem()
    p_mm = _scaled(p_m, MM, "mm")
    return p_m, p_mm, qropt.solve(p_m), qropt.solve(p_mm)


# ---- the mechanism ------------------------------------------------------------------------------------
def test_a_mechanism_states_its_unit_which_is_not_a_parameter():
    m = qropt.SliderCrank(r2=100, r3=350, e=60, units="mm")
    assert m.units == "mm" and "units" not in m.params and list(m.params) == list(qropt.SliderCrank.PARAMS)
    assert qropt.SliderCrank(r2=0.1, r3=0.35, e=0.06).units == qropt.units.DEFAULT == "m"
    assert repr(m).endswith("units='mm')") and "units" not in repr(qropt.SliderCrank(r2=0.1, r3=0.35))
    same = qropt.SliderCrank(r2=100, r3=350, e=60)
    assert m != same and hash(m) != hash(same) and m == qropt.SliderCrank(r2=100, r3=350, e=60, units="mm")
    with pytest.raises(InvalidParameter, match="length unit is one of"):
        qropt.SliderCrank(r2=100, r3=350, units="furlong")


# ---- the problem --------------------------------------------------------------------------------------
def test_a_problem_states_its_unit_and_keeps_it_through_files():
    p = _scaled(paper_problem(), MM, "mm")
    assert p.units == "mm" and paper_problem().units == "m"
    assert qropt.Problem.from_json(p.to_json()) == p and qropt.Problem.from_toml(p.to_toml()) == p
    assert p.replace(omega2=2.0).units == "mm" and p != p.replace(units="m")
    assert p.build({"r3": 250.4281217548, "r5": 150.0}, {"sigma": -1.0, "sigma_slider": 1.0}).units == "mm"
    d = p.to_dict()
    del d["units"]
    assert qropt.Problem.from_dict(d).units == "m"  # a table without units: the default
    with pytest.raises(ProblemError, match="length unit is one of"):
        p.replace(units="parsec")


def test_lengths_times_1000_in_mm_give_the_design_times_1000(solved):
    p_m, p_mm, r_m, r_mm = solved
    assert r_m.status == r_mm.status == "optimal" and r_mm.units == "mm" and r_mm.mechanism.units == "mm"
    for k, v in r_m.params.items():
        want = v if k.startswith("sigma") else v * MM
        assert r_mm.params[k] == pytest.approx(want, rel=1e-7, abs=1e-9)
    assert r_mm.objective == pytest.approx(r_m.objective, rel=1e-9)  # gamma_min: an angle
    assert r_mm.quantities["stroke"] == pytest.approx(300.0, rel=1e-10)
    assert r_mm.quantities["peak_accel"] == pytest.approx(r_m.quantities["peak_accel"] * MM, rel=1e-7)
    text = repr(r_mm) + "\n" + r_mm.summary()
    assert "stroke=300 mm" in text and "stroke 300 mm" in text and "mm/s^2" in text and "length" not in text
    assert "(mm" in text and "m/s^2" in repr(r_m) and "length" not in repr(r_m)


def test_result_dictionaries_keep_the_unit(solved):
    *_, r_m, r_mm = solved
    d = json.loads(json.dumps(r_mm.to_dict()))
    assert d["units"]["length"] == "mm" and d["units"]["peak_accel"].startswith("mm/s^2")
    assert d["units"]["footprint"] == "mm^2"
    back = qropt.Result.from_dict(d)
    assert back.to_dict() == d and back.units == "mm" and back.mechanism.units == "mm"
    assert all(o.units == "mm" for o in back.local_optima)
    assert qropt.Result.from_dict(r_m.to_dict()).units == "m"
    old = r_m.to_dict() | {"units": {"angles": "rad"}}  # a file from before units were stated
    assert qropt.Result.from_dict(old).units == "m"
    bare = qropt.Result("infeasible", "no design", units="mm")
    assert qropt.Result.from_dict(bare.to_dict()).units == "mm"
    with pytest.raises(ProblemError, match="in mm has a mechanism in m"):
        qropt.Result("optimal", "x", params=dict(r_m.params), mechanism=r_m.mechanism, units="mm")


# ---- io: files, drawings, plots -----------------------------------------------------------------------
def test_design_files_keep_the_unit(tmp_path, solved):
    m = solved[3].mechanism
    export.save_design(m, tmp_path / "d.json")
    assert json.loads((tmp_path / "d.json").read_text())["units"] == "mm"
    back = export.load_design(tmp_path / "d.json")
    assert back == m and back.units == "mm"
    legacy = {"type": m.KIND, "params": dict(m.params), "units": export.LEGACY_UNITS}
    (tmp_path / "old.json").write_text(json.dumps(legacy))
    assert export.load_design(tmp_path / "old.json").units == "m"  # a file without a stated unit: the default
    (tmp_path / "none.json").write_text(json.dumps({"type": m.KIND, "params": dict(m.params)}))
    assert export.load_design(tmp_path / "none.json").units == "m"
    (tmp_path / "bad.json").write_text(json.dumps({**legacy, "units": "furlong"}))
    with pytest.raises(InvalidParameter, match="length unit is one of"):
        export.load_design(tmp_path / "bad.json")
    (tmp_path / "result.json").write_text(json.dumps(solved[3].to_dict()))  # synth --json output
    assert export.load_design(tmp_path / "result.json").units == "mm"


@pytest.mark.parametrize("unit, code", [("mm", 4), ("m", 6), ("cm", 5), ("in", 1), ("ft", 2), ("um", 13)])
def test_dxf_states_its_unit(tmp_path, unit, code):
    import ezdxf

    m = qropt.SliderCrank(r2=100, r3=350, e=60, units=unit)
    export.to_dxf(m, tmp_path / "m.dxf")
    doc = ezdxf.readfile(tmp_path / "m.dxf")
    assert doc.header["$INSUNITS"] == code and doc.units == code


def test_svg_notes_its_unit(tmp_path):
    export.to_svg(qropt.SliderCrank(r2=100, r3=350, e=60, units="mm"), tmp_path / "m.svg")
    text = (tmp_path / "m.svg").read_text()
    assert 'data-units="mm"' in text and "lengths in mm" in text


def test_plot_axes_name_the_unit(solved):
    import matplotlib.pyplot as plt

    m = solved[3].mechanism
    fig = plots.cycle_figure(m)
    labels = [ax.get_xlabel() for ax in fig.axes] + [ax.get_ylabel() for ax in fig.axes]
    plt.close(fig)
    assert "x [mm]" in labels and "y [mm]" in labels and "slider v [mm/s]" in labels
    assert "slider a [mm/s^2]" in labels and not any("length" in s for s in labels)
    r = qropt.reachable(m, "r3")
    fig = plots.reachable_figure(r)
    assert fig.axes[0].get_xlabel() == "r3 [mm]"
    plt.close(fig)


# ---- studies: the comparison and the family --------------------------------------------------------------
def test_design_in_mm(tmp_path):
    c = design(1.5, 300.0, types=["slider-crank"], units="mm")
    assert c.units == "mm" and c.rows[0].result.mechanism.units == "mm"
    assert c.rows[0].result.quantities["stroke"] == pytest.approx(300.0, rel=1e-9)
    text = repr(c)
    assert "stroke 300 mm" in text and "mm^2" in text and "mm/s^2" in text and "length" not in text
    d = json.loads(c.to_json())
    assert d["units"]["length"] == "mm" and d["units"]["peak_velocity"] == "mm/s"
    assert c.table()[0]["units"] == "mm"
    c.to_csv(tmp_path / "c.csv")
    with open(tmp_path / "c.csv") as fh:
        assert next(csv.DictReader(fh))["units"] == "mm"
    m_row = design(1.5, 0.3, types=["slider-crank"]).rows[0]
    assert c.rows[0].criteria["footprint"] == pytest.approx(m_row.criteria["footprint"] * MM**2, rel=1e-6)
    import matplotlib.pyplot as plt

    fig = plots.comparison_figure(c)
    assert "300 mm" in fig._suptitle.get_text()
    plt.close(fig)


def test_family_points_and_axes_in_the_problem_unit():
    import importlib

    import matplotlib.pyplot as plt

    p = _scaled(importlib.import_module("problems.paper_family_r1_r3").build(), MM, "mm")
    f = qropt.family(p, max_points=60)
    assert f.points()[0].mechanism.units == "mm"
    fig = plots.family_figure(f)
    assert fig.axes[0].get_xlabel() == "r1 [mm]" and fig.axes[0].get_ylabel() == "r3 [mm]"
    plt.close(fig)


# ---- the command line -------------------------------------------------------------------------------------
RIG = ["crank-shaper", "--r1", "160", "--r2", "40", "--r4", "240"]


def test_cli_analyze_names_the_unit(tmp_path, capsys):
    assert qropt_cli.main(["analyze", *RIG, "--units", "mm", "--save", str(tmp_path / "d.json")]) == 0
    out = capsys.readouterr().out
    assert "stroke            " in out and " mm\n" in out and "mm/s^2" in out and "length" not in out
    assert json.loads((tmp_path / "d.json").read_text())["units"] == "mm"
    assert qropt_cli.main(["analyze", *RIG, "--units", "mm", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["units"] == "mm"
    assert qropt_cli.main(["analyze", "--from", str(tmp_path / "d.json")]) == 0  # the file's own unit
    assert "(mm)" in capsys.readouterr().out
    assert qropt_cli.main(["analyze", "--from", str(tmp_path / "d.json"), "--units", "mm"]) == 0
    capsys.readouterr()
    assert qropt_cli.main(["analyze", "--from", str(tmp_path / "d.json"), "--units", "m"]) == 2
    assert "contradicts" in capsys.readouterr().err
    assert qropt_cli.main(["analyze", "--units", "mm"]) == 2  # the paper's design is stated in m
    assert "contradicts the built-in paper design, which is in m" in capsys.readouterr().err
    f = tmp_path / "t.csv"
    assert qropt_cli.main(["analyze", *RIG, "--units", "mm", "--table", "30", "--csv", str(f)]) == 0
    rows = list(csv.DictReader(f.open()))
    assert rows[0]["units"] == "mm" and float(rows[0]["x"]) != 0


def test_cli_design_names_the_unit(capsys):
    assert qropt_cli.main(["design", "--tr", "1.5", "--stroke", "300", "--units", "mm", "--types", "slider-crank"]) == 0
    out = capsys.readouterr().out
    assert "stroke 300 mm" in out and "[mm^2]" in out and "[mm/s^2]" in out and "length" not in out


def test_cli_tolerance_reads_the_design_unit(tmp_path, capsys):
    mm = qropt.SliderCrank(r2=100, r3=350, e=60, units="mm")
    export.save_design(mm, tmp_path / "d.json")
    path = str(tmp_path / "d.json")
    assert qropt_cli.main(["tolerance", path, "--limit", "stroke=1mm", "--json"]) == 0  # the file states mm
    got = json.loads(capsys.readouterr().out)
    assert got["limits"]["stroke"] == pytest.approx(1.0) and got["units"] == "mm"
    assert qropt_cli.main(["tolerance", path, "--units", "mm", "--limit", "stroke=10um", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["limits"]["stroke"] == pytest.approx(0.01)
    assert qropt_cli.main(["tolerance", path, "--units", "m", "--limit", "stroke=1mm"]) == 2
    err = capsys.readouterr().err
    assert "contradicts" in err and err.count("\n") == 1
    assert qropt_cli.main(["tolerance", "--units", "mm", "--limit", "stroke=1mm"]) == 2  # the paper's: m
    assert "contradicts" in capsys.readouterr().err
    rig = ["slider-crank", "--r2", "100", "--r3", "350", "--e", "60"]
    assert qropt_cli.main(["tolerance", *rig, "--units", "mm", "--limit", "stroke=1mm", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["limits"]["stroke"] == pytest.approx(1.0)
