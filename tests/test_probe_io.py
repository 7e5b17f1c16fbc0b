"""Bad inputs to qropt.io: each a typed qropt error naming the problem, raised before anything is rendered."""

from __future__ import annotations

import json
import math
import re
import time

import pytest

import qropt
from qropt import InvalidParameter, cli
from qropt.errors import QroptError
from qropt.io import export, plots
from qropt.io.animation import animate

FAST = 3.0  # seconds: a bad input fails before the 13-16 s of rendering


def _m():
    return qropt.SliderCrank(r2=0.1, r3=0.35, e=0.06)


def _fails_fast(call, error, words):
    t = time.perf_counter()
    with pytest.raises(error, match=words):
        call()
    assert time.perf_counter() - t < FAST


@pytest.mark.parametrize("fps", [0, -1, "x", math.nan, math.inf, True, 1000])
def test_animate_rejects_a_bad_fps_first(fps, tmp_path):
    _fails_fast(lambda: animate(_m(), tmp_path / "x.gif", fps=fps), InvalidParameter, "fps")
    assert not (tmp_path / "x.gif").exists()


def test_animate_to_a_directory_fails_first(tmp_path):
    (tmp_path / "d.gif").mkdir()
    _fails_fast(lambda: animate(_m(), tmp_path / "d.gif"), InvalidParameter, "is a directory")


def test_animate_to_an_unwritable_path_fails_first(tmp_path):
    _fails_fast(lambda: animate(_m(), tmp_path / "no" / "x.gif"), InvalidParameter, "does not exist")
    (tmp_path / "f").write_text("a file")
    _fails_fast(lambda: animate(_m(), tmp_path / "f" / "x.gif"), InvalidParameter, "is not a directory")


@pytest.mark.parametrize(("out", "words"), [("r.txt", r"\.html"), ("no/r.html", "does not exist")])
def test_report_checks_its_output_path_first(out, words, tmp_path, capsys):
    t = time.perf_counter()
    assert cli.main(["report", "-o", str(tmp_path / out)]) != 0
    assert time.perf_counter() - t < FAST
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and re.search(words, err)
    from qropt.io.report import render

    _fails_fast(lambda: render(None, tmp_path / out), InvalidParameter, words)


@pytest.mark.parametrize(
    ("extra", "words"),
    [({"note": math.nan}, "'note'.*nan"), ({"note": object()}, "'note'"), ({"type": "x"}, "own field")],
)
def test_save_design_rejects_extras_that_are_not_strict_json(extra, words, tmp_path):
    with pytest.raises(InvalidParameter, match=words):
        export.save_design(_m(), tmp_path / "d.json", **extra)
    assert not (tmp_path / "d.json").exists()


@pytest.mark.parametrize(
    "text",
    ["[" * 100_000 + "]" * 100_000, '{"type": "slider-crank", "params": {"r2": ' + "[" * 99_999 + "]" * 99_999 + "}}"],
    ids=["document", "parameter"],
)
def test_load_design_of_deeply_nested_json_is_a_typed_error(text, tmp_path):
    f = tmp_path / "deep.json"
    f.write_text(text)
    with pytest.raises(InvalidParameter, match="nested too deeply"):
        export.load_design(f)


def test_analyze_from_a_deeply_nested_design_prints_one_line(tmp_path, capsys):
    f = tmp_path / "deep.json"
    f.write_text("[" * 100_000 + "]" * 100_000)
    assert cli.main(["analyze", "--from", str(f)]) != 0
    out = capsys.readouterr()
    assert len(out.err.strip().splitlines()) == 1 and "nested too deeply" in out.err and len(out.err) < 300


@pytest.mark.parametrize("write", [export.to_dxf, export.to_svg, export.save_design, animate])
def test_drawing_nothing_is_a_typed_error(write, tmp_path):
    suffix = {"to_dxf": ".dxf", "to_svg": ".svg", "save_design": ".json", "animate": ".gif"}[write.__name__]
    with pytest.raises(InvalidParameter, match="mechanism, got NoneType"):
        write(None, tmp_path / f"x{suffix}")


def test_load_design_of_a_non_path_is_a_typed_error():
    with pytest.raises(InvalidParameter, match="path"):
        export.load_design(None)


@pytest.mark.parametrize(
    ("name", "words"), [("x.xyz", "'.xyz'"), ("x", "no extension"), ("no/x.png", "does not exist"), (".", "directory")]
)
def test_every_plot_checks_its_path_before_writing(name, words, tmp_path):
    cmp = qropt.design(1.5, 0.3, types=["slider-crank"])
    with pytest.raises(InvalidParameter, match=words):
        cmp.plot(tmp_path / name)
    fig = plots.plt.figure()
    with pytest.raises(InvalidParameter, match=words):
        plots.save(fig, tmp_path / name)
    assert not plots.plt.fignum_exists(fig.number)  # closed all the same
    cmp.plot(tmp_path / "ok.svg")
    assert (tmp_path / "ok.svg").read_text().startswith("<?xml")


def test_a_good_design_file_still_round_trips(tmp_path):
    export.save_design(_m(), tmp_path / "d.json", note="fine", tags=["a", 1])
    d = json.loads((tmp_path / "d.json").read_text())
    assert d["note"] == "fine" and export.load_design(tmp_path / "d.json") == _m()
    assert issubclass(InvalidParameter, QroptError)


@pytest.mark.parametrize(
    ("kw", "words"),
    [
        ({"path": "x.xyz"}, "'.xyz'"),
        ({"path": "no/x.png"}, "does not exist"),
        ({"theta2": math.nan}, "theta2"),
        ({"omega2": "fast"}, "omega2"),
    ],
)
def test_a_mechanism_plot_checks_its_inputs_first(kw, words, tmp_path):
    kw = {"path": "m.png", **kw}
    path = tmp_path / kw.pop("path")
    _fails_fast(lambda: _m().plot(path, **kw), InvalidParameter, words)
    assert not path.exists()


def test_a_mechanism_plot_draws_it_at_its_crank_angle(tmp_path):
    _m().plot(tmp_path / "m.svg", theta2=math.radians(30), omega2=2.0)
    labels = re.findall(r"<!-- (.*?) -->", (tmp_path / "m.svg").read_text())  # matplotlib's SVG names each text
    assert "SliderCrank at theta2 = 30.0 deg" in labels and {"O2", "A", "C"} <= set(labels)
    assert "x [m]" in labels and "theta2 [deg] (omega2 = 2 rad/s)" in labels
