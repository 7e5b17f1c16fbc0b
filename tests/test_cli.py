"""The ``qropt analyze`` command: text, JSON, full-cycle table and picture."""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np
import pytest

from qropt import cli
from tests import brute


def test_builtin_example_text(capsys):
    assert cli.main(["analyze", "--omega2", "10"]) == 0
    out = capsys.readouterr().out
    assert "drag-link-slider" in out and "time ratio        1.50000000" in out
    assert "gamma_min         27.008205 deg at theta2 = 0.000000 deg, joint B" in out
    assert "216.000000 deg working / 144.000000 deg return" in out
    assert "v = -1.0734" in out and "a = -21.6749" in out


def test_json_matches_api(capsys):
    assert (
        cli.main(
            [
                "analyze",
                "crank-shaper",
                "--r1",
                "160",
                "--r2",
                "40",
                "--r4",
                "240",
                "--json",
                "--theta2",
                "90deg",
                "--omega2",
                "-1",
            ]
        )
        == 0
    )
    r = json.loads(capsys.readouterr().out)
    assert r["stroke"] == pytest.approx(120.0, abs=1e-10)
    assert r["time_ratio"] == pytest.approx(1.3833960613578, abs=1e-12)
    assert r["working_direction"] == "+x"
    assert r["state"]["x"] == pytest.approx(0.0, abs=1e-12)  # crank along +y: lever vertical


def test_table_csv_matches_brute_force(tmp_path, capsys):
    f = tmp_path / "t.csv"
    assert (
        cli.main(
            [
                "analyze",
                "whitworth",
                "--r1",
                "0.1",
                "--r2",
                "0.2",
                "--r5",
                "0.12",
                "--r6",
                "0.3",
                "--h",
                "0.02",
                "--table",
                "5",
                "--csv",
                str(f),
                "--omega2",
                "3",
            ]
        )
        == 0
    )
    rows = list(csv.DictReader(f.open()))
    assert len(rows) == 73
    th = np.radians([float(r["theta2_deg"]) for r in rows])
    p = {"r1": 0.1, "r2": 0.2, "r5": 0.12, "r6": 0.3, "h": 0.02, "sigma_slider": 1.0}
    x = np.real(brute.output("whitworth", p, th))
    np.testing.assert_allclose([float(r["x"]) for r in rows], x, atol=1e-11)
    v = np.imag(brute.output("whitworth", p, th + 1e-30j)) / 1e-30 * 3.0
    np.testing.assert_allclose([float(r["v"]) for r in rows], v, atol=1e-10)
    assert {"A_x", "C_y", "D_x", "theta4_deg", "omega_theta4", "gamma_D_deg"} <= set(rows[0])


def test_plot_written(tmp_path, capsys):
    f = tmp_path / "m.png"
    assert cli.main(["analyze", "slider-crank", "--r2", "0.1", "--r3", "0.35", "--e", "0.06", "--plot", str(f)]) == 0
    assert f.stat().st_size > 10_000 and f.read_bytes()[:4] == b"\x89PNG"


def test_version_is_the_packages(capsys):
    import qropt

    with pytest.raises(SystemExit) as e:
        cli.main(["--version"])
    assert e.value.code == 0 and capsys.readouterr().out == f"qropt {qropt.__version__}\n"


def test_angle_parsing():
    assert cli.angle("60") == pytest.approx(math.radians(60))
    assert cli.angle("60deg") == pytest.approx(math.radians(60))
    assert cli.angle("1.5rad") == 1.5


@pytest.mark.parametrize(
    ("argv", "code", "words"),
    [
        (["analyze", "--table", "1e-6", "--csv", "x.csv"], 2, "0.01 to 360"),
        (["analyze", "--table", "0"], 2, "0.01 to 360"),
        (["analyze", "--table", "400"], 2, "0.01 to 360"),
        (["analyze", "--plot", "out.txt"], 2, "picture formats"),
        (["analyze", "--json", "--table", "90"], 2, "--csv FILE"),
        (["analyze", "--theta2", "nan"], 2, "finite angle"),
        (["analyze", "--theta2", "1e400"], 2, "finite angle"),
        (["analyze", "--omega2", "0"], 2, "nonzero"),
        (["analyze", "--omega2", "nan"], 2, "finite number"),
        (["reachable", "--tr", "nan"], 2, "finite number"),
        (["synth", "--starts", "-3"], 2, "--starts"),
        (["synth", "--size", "footprint"], 2, "min_size"),
        (["design", "--tr", "1.5", "--stroke", "0.3", "--workers", "0"], 1, "worker processes in [1,"),
        (["analyze", "whitworth", "--r1", "0.1", "--r2", "0.2", "--r5", "0.12", "--r6", "0.05"], 1, "fails for theta2"),
    ],
)
def test_bad_command_lines_print_one_line(argv, code, words, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert cli.main(argv) == code
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and words in err, err
    assert not (tmp_path / "x.csv").exists()


def test_ctrl_c_is_one_line(capsys, monkeypatch):
    from qropt.studies import _design

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(_design, "design", interrupted)
    assert cli.main(["design", "--tr", "1.5", "--stroke", "0.3"]) == 130
    err = capsys.readouterr().err
    assert err.strip() == "qropt: interrupted"


@pytest.mark.parametrize(
    ("text", "words"),
    [
        ("def build(:\n", "does not load: SyntaxError"),
        ("def build():\n    return 42\n", "must return a qropt.Problem, got int"),
        ("def build():\n    return None\n", "got NoneType"),
        ("x = 1\n", "no build()"),
    ],
)
def test_bad_problem_files_print_one_line(text, words, capsys, tmp_path):
    f = tmp_path / "bad.py"
    f.write_text(text)
    assert cli.main(["synth", str(f)]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and words in err, err


def test_toml_and_json_problem_files_solve_like_the_python_one(capsys, tmp_path):
    from qropt.examples import paper_problem

    (tmp_path / "task.json").write_text(paper_problem().to_json())
    (tmp_path / "bad.toml").write_text("mechanism = \n")
    root = Path(__file__).resolve().parent.parent
    for f in (str(root / "problems" / "paper_task.toml"), str(tmp_path / "task.json")):
        assert cli.main(["synth", f, "--json"]) == 0
        out = json.loads(capsys.readouterr().out)
        assert out["params"]["r3"] == pytest.approx(0.2504281217548, abs=1e-12)
    assert cli.main(["synth", str(tmp_path / "bad.toml")]) == 1
    assert "TOML" in capsys.readouterr().err


def test_infeasible_synth_json_is_strict(capsys, tmp_path):
    from qropt.examples import paper_problem

    (tmp_path / "far.json").write_text(paper_problem().replace(targets={"time_ratio": 9.0, "stroke": 0.3}).to_json())
    assert cli.main(["synth", str(tmp_path / "far.json"), "--json"]) == 1
    out = capsys.readouterr().out
    assert "NaN" not in out and json.loads(out)["status"] == "infeasible"


def test_working_stroke_shading_is_the_slow_arc_for_either_sense_of_rotation():
    import matplotlib.pyplot as plt

    from qropt.examples import paper_mechanism
    from qropt.io.plots import _shade

    m = paper_mechanism()
    d, (a, b) = m.dead_centres(), m.stroke_angles()
    for omega2 in (1.0, -1.0):
        fig, ax = plt.subplots()
        _shade(ax, d.theta_max, d.theta_min, a, b, omega2)
        spans = [p for p in ax.patches if p.get_label() == "working stroke"]
        assert spans[0].get_width() == pytest.approx(math.degrees(max(a, b)))
        plt.close(fig)


def test_a_slotted_lever_is_drawn_through_its_crank_pin_block():
    import matplotlib.pyplot as plt

    from qropt import Whitworth
    from qropt.io.plots import draw_mechanism

    m = Whitworth(r1=0.1, r2=0.2, r5=0.12, r6=0.3)
    for theta in np.linspace(0, 2 * math.pi, 13):
        fig, ax = plt.subplots()
        draw_mechanism(ax, m, theta)
        p = {k: v[0] for k, v in m.positions(theta).points.items()}
        lever = [line.get_xydata() for line in ax.lines if tuple(line.get_xydata()[0]) == tuple(p["O4"])]
        reach = max(np.hypot(*(seg[-1] - seg[0])) for seg in lever)
        assert reach >= np.hypot(*np.subtract(p["A"], p["O4"])) - 1e-12  # the lever reaches the block at A
        plt.close(fig)


def test_reachable_sizes_the_adjustable_link_for_a_given_range(capsys):
    assert cli.main(["reachable", "--adjust", "1.5", "2.5", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    lo, hi = out["adjustable"]["interval"]
    assert lo == pytest.approx(0.2504281217548, abs=1e-9) and out["adjustable"]["worst_gamma_min_deg"] > 8
    from qropt import DragLinkSlider

    for r3, tr in ((lo, 1.5), (hi, 2.5)):
        m = DragLinkSlider(r1=0.1, r2=0.225, r3=r3, r4=0.275, r5=0.15, r6=0.3)
        assert m.time_ratio() == pytest.approx(tr, abs=1e-8)
    assert cli.main(["reachable", "--adjust", "1.2", "2"]) == 2


def _help(sub, capsys) -> str:
    with pytest.raises(SystemExit) as e:
        cli.main([sub, "--help"])
    assert e.value.code == 0
    return capsys.readouterr().out


def _subcommands() -> list[str]:
    p = cli.parser()
    return [s for s in p._subparsers._group_actions[0].choices if s != "bench"]  # bench: the suite's own --help


def _examples(sub, capsys) -> list[list[str]]:
    import shlex

    text = _help(sub, capsys)
    lines = text[text.rindex("\nexamples") + 1 :].splitlines()[1:]
    return [shlex.split(line) for line in lines if line.strip()]


@pytest.mark.parametrize("sub", _subcommands())
def test_every_help_ends_with_examples_of_its_command(sub, capsys):
    found = _examples(sub, capsys)
    assert 1 <= len(found) <= 2 and all(argv[:2] == ["qropt", sub] for argv in found)


@pytest.mark.parametrize("sub", ["synth", "analyze", "reachable"])
def test_the_examples_of_cheap_commands_run(sub, capsys, tmp_path, monkeypatch):
    (tmp_path / "problems").symlink_to(Path(__file__).resolve().parent.parent / "problems")
    monkeypatch.chdir(tmp_path)
    for argv in _examples(sub, capsys):
        assert cli.main(argv[1:]) == 0, argv
        capsys.readouterr()


@pytest.mark.parametrize("sub", ["analyze", "reachable", "servo", "tolerance"])
def test_parameter_flags_name_the_types_that_take_them(sub, capsys):
    from qropt.mechanisms import REGISTRY

    p = cli.parser()
    flags = {a.dest: a.help for a in p._subparsers._group_actions[0].choices[sub]._actions}
    for k in cli.PARAM_NAMES:
        takers = sorted(t for t, cls in REGISTRY.items() if k in cls.PARAMS)
        assert takers and flags[k].partition(" of the types ")[2].split(", ") == takers, k
    if sub == "analyze":  # the type argument's help (argparse wraps the printed help at hyphens too)
        helps = " ".join(a.help or "" for a in p._subparsers._group_actions[0].choices[sub]._actions)
        assert "default: the paper's mechanism, a drag-link-slider" in helps
        assert _help(sub, capsys).startswith("usage: qropt analyze")


@pytest.mark.parametrize("sub", ["synth", "design", "servo"])
def test_objective_has_help(sub):
    p = cli.parser()
    (flag,) = [a for a in p._subparsers._group_actions[0].choices[sub]._actions if a.dest == "objective"]
    assert flag.help and all(o in flag.help for o in flag.choices if o != "none")


def test_synth_dxf_help_names_no_theta2_flag(capsys):
    assert "--theta2" not in _help("synth", capsys)


def test_pareto_json_is_strict(capsys):
    problem = str(Path(__file__).resolve().parent.parent / "problems" / "slider_crank_size.py")
    argv = ["pareto", problem, "--objectives", "max_gamma_min", "min_peak_accel", "--n", "3", "--json"]
    assert cli.main(argv) == 0
    out = json.loads(capsys.readouterr().out, parse_constant=lambda c: pytest.fail(f"not strict JSON: {c}"))
    assert out["objectives"] == ["max_gamma_min", "min_peak_accel"] and len(out["points"]) >= 2
    assert out["units"]["length"] == "m" and {"gamma_min", "peak_accel", "r2"} <= set(out["points"][0])
