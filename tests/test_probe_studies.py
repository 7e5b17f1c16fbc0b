"""Bad input to charts and reachable ranges, found by a hostile probe: each case is a typed qropt error naming the
problem (never a bare Python exception, a silent wrong answer or a runaway), on the API and on the command line."""

from __future__ import annotations

import importlib
import json
import math
import subprocess
import sys

import numpy as np
import pytest

from qropt import FourBar, SliderCrank
from qropt.errors import ChartError, InvalidParameter
from qropt.examples import paper_mechanism
from qropt.studies._chart import Chart
from qropt.studies._chart_run import chart
from qropt.studies._reachable import reachable

ROOT = __import__("pathlib").Path(__file__).resolve().parents[1]
TR, CRANK = (1.2, 1.45, 1.7), (0.2, 0.32)


@pytest.fixture(scope="module")
def small():
    """A 3 x 2 slider-crank chart (closed forms: fast), its last cell without a design."""
    p = importlib.import_module("problems.chart_slider_crank").build()
    return chart(p, ("time_ratio", TR), ("r2", CRANK), progress=False)


@pytest.fixture(scope="module")
def written(small, tmp_path_factory):
    path = tmp_path_factory.mktemp("chart") / "c.json"
    small.to_json(path)
    return json.loads(path.read_text())


@pytest.fixture(scope="module")
def paper():
    return reachable(paper_mechanism(), "r3")


def _cli(*args):
    """qropt in a fresh process: (exit code, standard error lines)."""
    code = "import sys; from qropt.cli import main; sys.exit(main(sys.argv[1:]))"
    p = subprocess.run(
        [sys.executable, "-c", code, "--quiet", *args], capture_output=True, text=True, timeout=300, cwd=ROOT
    )
    return p.returncode, p.stdout, p.stderr.strip().splitlines()


# ---- chart lookups and arrays ------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "call, words",
    [
        (lambda ch: ch.result(math.nan, CRANK[0]), "time_ratio value must be a finite number"),
        (lambda ch: ch.result(TR[0], math.inf), "r2 value must be a finite number"),
        (lambda ch: ch.result("x", CRANK[0]), "time_ratio value must be a number"),
        (lambda ch: ch.cell(5, 0), r"cell index i = 5 is out of range: 0\.\.2"),
        (lambda ch: ch.cell(-1), r"cell index i = -1 is out of range"),
        (lambda ch: ch.cell(100), r"cell index i = 100 is out of range"),
        (lambda ch: ch.cell(0, 2), r"cell index j = 2 is out of range: 0\.\.1"),
        (lambda ch: ch.cell(0, -1), r"cell index j = -1 is out of range"),
        (lambda ch: ch.cell(1.0), "cell index i must be an integer"),
        (lambda ch: ch.cell(True), "cell index i must be an integer"),
        (lambda ch: ch.grid(None), "a chart quantity is a name or a ratio"),
        (lambda ch: ch.grid(3), "a chart quantity is a name or a ratio"),
        (lambda ch: ch.mask(["jump"]), "unknown chart flag"),
        (lambda ch: ch.mask(None), "unknown chart flag"),
        (lambda ch: ch.to_json(None), "the chart JSON file must be a path"),
        (lambda ch: ch.to_csv(None), "the chart CSV file must be a path"),
        (lambda ch: ch.to_json(ROOT / "no such dir" / "c.json"), "cannot write the chart JSON file"),
        (lambda ch: ch.plot("c.png", dpi=0), "dpi must be a number"),
    ],
)
def test_chart_lookups_refuse_bad_input(small, call, words):
    with pytest.raises(ChartError, match=words):
        call(small)


def test_chart_lookups_still_answer(small):
    assert small.shape == (2, 3) and small.cell(2, 1) is small.cells[5] and small.cell(np.int64(1)) is small.cells[1]
    assert small.result(TR[1], CRANK[1]).params == small.cell(1, 1).params


@pytest.mark.parametrize(
    ("path", "words"),
    [
        (None, "the picture path must be a str or path-like"),
        ("no such dir/c.png", "cannot write the picture: its directory"),
    ],
)
def test_plot_refuses_a_path_it_cannot_write(small, path, words):
    with pytest.raises(InvalidParameter, match=words):
        small.plot(path)


@pytest.mark.parametrize("name", ["noext", "c.xyz", "c.jpg"])
def test_plot_refuses_an_unknown_picture_format_and_writes_nothing(small, tmp_path, name):
    with pytest.raises(InvalidParameter, match=r"the picture formats are \.png, \.pdf, \.svg"):
        small.plot(tmp_path / name)
    assert list(tmp_path.iterdir()) == []


def test_plot_writes_a_known_format(small, tmp_path):
    small.plot(tmp_path / "c.SVG")
    assert (tmp_path / "c.SVG").read_text().lstrip().startswith("<?xml")


# ---- chart files ---------------------------------------------------------------------------------------------
def _broken(d, how):
    d = json.loads(json.dumps(d))
    how(d)
    return d


@pytest.mark.parametrize(
    "how, words",
    [
        (lambda d: d.update(stats=None), "chart 'stats' is null, not an object"),
        (lambda d: d.update(x=None), "chart 'x' is null, not an object"),
        (lambda d: d.pop("y"), "chart has no 'y'"),
        (lambda d: d["stats"].pop("certified"), "stats has no 'certified'"),
        (lambda d: d["stats"].update(seconds="fast"), "stats 'seconds' is \"fast\", not a finite number"),
        (lambda d: d.update(cells=d["cells"][:4]), "4 cells for 3 x 2 axis values: the file is incomplete"),
        (lambda d: d["cells"].reverse(), r"cell 0 is \(2, 1\), not \(0, 0\)"),
        (lambda d: d["cells"][2].pop("method"), "cell has no 'method'"),
        (
            lambda d: d["cells"][2]["result"].update(status="great"),
            r"cell \(2, 0\) result 'status' is \"great\", not a Result status",
        ),
        (
            lambda d: d["cells"][1]["result"].update(params={"r3": None}),
            r"cell \(1, 0\) result 'params' is dict, not an object of finite numbers",
        ),
        (lambda d: d["x"].update(values=[1.2]), "axis x 'values' is list, not 2 or more finite numbers"),
        (lambda d: d["x"].update(values=[1.2, 1.7, 1.45]), "not distinct and in order"),
        (lambda d: d["x"].update(name="bogus"), "'bogus' is no target or fixed parameter"),
        (lambda d: d["y"].update(kind="target"), "'r2' is a fixed, not a target"),
        (lambda d: d.update(problem={"mechanism": "Nope"}), "not a qropt chart file"),
    ],
)
def test_a_damaged_chart_file_is_refused_on_load(written, tmp_path, how, words):
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(_broken(written, how)))
    with pytest.raises(ChartError, match=words):
        Chart.from_json(path)


def test_a_truncated_or_missing_chart_file_is_refused(written, tmp_path):
    text = json.dumps(written)
    (tmp_path / "cut.json").write_text(text[: len(text) // 2])
    for path, words in (
        (tmp_path / "cut.json", "not a qropt chart file"),
        (tmp_path / "none.json", "No such file"),
        (None, "must be a path"),
    ):
        with pytest.raises(ChartError, match=words):
            Chart.from_json(path)
    (tmp_path / "whole.json").write_text(text)
    back = Chart.from_json(tmp_path / "whole.json")  # the undamaged file still loads, every cell in place
    assert back.shape == (2, 3) and back.cell(1, 1).result.params == back.cell(1, 1).params


# ---- workers -------------------------------------------------------------------------------------------------
def test_a_million_workers_is_refused_before_any_process_starts():
    p = importlib.import_module("problems.chart_slider_crank").build()
    with pytest.raises(ChartError, match=r"worker processes in \[1, \d+\] .* got 1000000; use a Dask cluster"):
        chart(p, ("time_ratio", TR), workers=10**6, progress=False)


def test_a_local_cluster_that_cannot_start_is_a_chart_error(monkeypatch):
    import distributed

    def refuse(*args, **kwargs):
        raise OSError("[Errno 24] Too many open files")

    monkeypatch.setattr(distributed, "LocalCluster", refuse)
    p = importlib.import_module("problems.chart_slider_crank").build()
    with pytest.raises(ChartError, match=r"cannot start a local Dask cluster of 2 worker processes \(OSError: .*open"):
        chart(p, ("time_ratio", TR), workers=2, progress=False)


# ---- reachable ranges ----------------------------------------------------------------------------------------
def _scanned(base, free, values) -> np.ndarray:
    """The mechanism's exact time_ratio along a dense scan of one parameter (nan where it does not build)."""
    out = []
    for v in values:
        try:
            out.append(type(base)(**{**base.params, free: v}).time_ratio())
        except Exception:  # noqa: BLE001 - does not build: no design there
            out.append(math.nan)
    return np.array(out)


def _brute_count(scanned, time_ratio):
    """Designs of this TR on a scan (``_scanned``): sign changes of TR - target."""
    d = scanned - time_ratio
    ok = np.isfinite(d[:-1]) & np.isfinite(d[1:])
    return int(np.sum(ok & (np.sign(d[:-1]) != np.sign(d[1:]))))


def test_negative_offsets_are_in_the_reachable_range():
    m = SliderCrank(r2=0.1, r3=0.4, e=-0.05)
    r = reachable(m, "e")
    assert len(r.intervals) == 1
    lo, hi = r.intervals[0]
    assert lo == pytest.approx(-0.3, abs=1e-12) and hi == pytest.approx(0.3, abs=1e-12)  # r3 >= r2 + |e|
    assert lo <= m.params["e"] <= hi  # the mechanism's own offset is reachable
    scanned = _scanned(m, "e", np.linspace(-0.3, 0.3, 60001))
    for tr in (1.05, 1.2, 1.5, 1.8):
        assert r.count(tr) == _brute_count(scanned, tr) == 2, tr  # e and its mirror -e
    assert sorted(abs(x) for x in r.solutions(1.2)) == pytest.approx([0.18505139459444] * 2, abs=1e-12)
    for x in r.solutions(1.2):
        assert SliderCrank(r2=0.1, r3=0.4, e=x).time_ratio() == pytest.approx(1.2, abs=1e-10)
    assert r.count(1.0) == 1 and r.time_ratio_range.low_at == pytest.approx(0.0, abs=1e-9)


def test_an_offset_without_rules_needs_bounds_on_both_sides():
    from qropt import Whitworth

    with pytest.raises(InvalidParameter, match="do not bound it below and above"):
        reachable(Whitworth(r1=0.1, r2=0.2, r5=0.4, r6=0.6, h=-0.05), "h")


@pytest.mark.parametrize(
    "call, words",
    [
        (lambda: reachable(paper_mechanism(), "r3", bounds=(0.15, 1e300)), r"out of range: \|bound\| <= 1e\+100"),
        (lambda: reachable(paper_mechanism(), "r3", bounds=(-1.0, 0.1)), "satisfies DragLinkSlider's rules"),
        (lambda: reachable(FourBar(r1=1, r2=0.3, r3=1.1, r4=0.8), "r3", bounds=(0.5, 1e6)), "span more than 1000"),
        (lambda: reachable(paper_mechanism(), "r3", bounds=(0.3, 0.2)), "empty interval"),
    ],
)
def test_reachable_refuses_unusable_bounds(call, words):
    with pytest.raises(InvalidParameter, match=words):
        call()


def test_huge_bounds_within_the_rules_give_the_rules_interval(paper):
    wide = reachable(paper_mechanism(), "r3", bounds=(0.15, 1e50))  # nothing works beyond the Grashof interval
    assert np.array(wide.intervals) == pytest.approx(np.array(paper.intervals), abs=1e-9)
    (lo, lo_at, hi, hi_at), want = wide.time_ratio_range, paper.time_ratio_range
    assert (lo, hi) == pytest.approx((want.low, want.high), abs=1e-12)
    assert (lo_at, hi_at) == pytest.approx((want.low_at, want.high_at), abs=1e-6)  # a flat minimum: ~sqrt(eps)


@pytest.mark.parametrize(
    "call, words",
    [
        (lambda r: r.adjustable(2.5, 1.5), "2.5..1.5 runs backwards: give the lower time ratio first"),
        (lambda r: r.adjustable("x"), "tr_low must be a finite number, got 'x'"),
        (lambda r: r.adjustable(1.5, math.nan), "tr_high must be a finite number"),
        (lambda r: r.count("x"), "time ratio must be a finite number, got 'x'"),
        (lambda r: r.count(None), "time ratio must be a finite number, got None"),
        (lambda r: r.count(math.nan), "time ratio must be a finite number"),
        (lambda r: r.solutions(True), "time ratio must be a finite number"),
    ],
)
def test_reachable_queries_refuse_bad_input(paper, call, words):
    with pytest.raises(InvalidParameter, match=words):
        call(paper)


def test_reachable_queries_still_answer(paper):
    assert paper.count(1.5) == 2 and paper.count(np.float64(2.0)) == 1 and paper.count(1) == 0
    assert paper.adjustable(1.5, 2.5).interval[0] == pytest.approx(0.2504281217548, abs=1e-9)


# ---- the command line: one line, a non-zero exit -------------------------------------------------------------
@pytest.mark.parametrize(
    "args, code, words",
    [
        (["reachable", "--adjust", "2.5", "1.5"], 2, "--adjust 2.5 1.5: TR_LOW is above TR_HIGH"),
        (["reachable", "--bounds", "0.15", "1e300"], 1, "InvalidParameter: bounds of r3 (0.15, 1e+300) are out of"),
        (
            [
                "chart",
                "problems/chart_crank_rocker.py",
                "--x",
                "time_ratio",
                "1.2:1.5:3",
                "--y",
                "none",
                "--workers",
                "1000000",
            ],
            1,
            "ChartError: workers is a number of worker processes in [1,",
        ),
        (["chart", "problems/chart_crank_rocker.py", "--plot", "noext"], 2, "the picture formats are .png"),
    ],
)
def test_bad_input_is_one_line_on_the_command_line(args, code, words):
    rc, out, err = _cli(*args)
    assert rc == code and len(err) == 1 and err[0].startswith("qropt:") and words in err[0], (rc, err)
    assert "Traceback" not in out


def test_negative_offsets_on_the_command_line():
    rc, out, err = _cli(
        "reachable", "slider-crank", "--r2", "0.1", "--r3", "0.4", "--e", "-0.05", "--free", "e", "--tr", "1.2"
    )
    assert rc == 0 and not err
    assert "feasible e in [-0.3, 0.3]" in out and "TR 1.2: 2 design(s): -0.1850513946, 0.1850513946" in out
