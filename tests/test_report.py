"""The HTML report: self-contained, the paper's project computed by the same code as the CLI, rendered in Chromium
when it is installed."""

from __future__ import annotations

import re
import shutil
import subprocess

import numpy as np
import pytest

from qropt import InvalidParameter, cli
from qropt.examples import paper_problem
from qropt.io.report import render


@pytest.fixture(scope="module")
def paper_report(tmp_path_factory):
    path = tmp_path_factory.mktemp("report") / "report.html"
    assert cli.main(["report", "-o", str(path)]) == 0
    return path, path.read_text()


def test_the_report_is_self_contained(paper_report):
    _, text = paper_report
    sources = re.findall(r'(?:src|href)="([^"]*)"', text)
    assert sources and all(s.startswith(("data:", "#")) for s in sources)
    assert "http://" not in text.replace('xmlns="http://www.w3.org/2000/svg"', "") and "https://" not in text


def test_the_report_carries_the_numbers_of_the_library(paper_report):
    _, text = paper_report
    from qropt import solve

    r = solve(paper_problem())
    for number in (f"{r.params['r3']:.6g}", f"{r.local_optima[1].params['r3']:.6g}", "3.53812", "1.42985", "27.0082"):
        assert number in text
    for section in (
        "Design requirement 1",
        "Design requirement 2",
        "Discussion issues 3-4",
        "Analysis 1-2",
        "Analysis 3",
        "printed numbers differ",
    ):
        assert section in text
    assert "-21.67" in text and "5.538" in text  # the paper's printed values beside the exact ones


def test_the_report_sets_the_polygons_beside_the_papers_tables_2_and_3(paper_report):
    """Each printed magnitude of Tables 2-3 in a row beside qropt's term (computed here from the polygons of the
    Table-4 design, independently of the report's code), within 0.5 %, and the polygons drawn."""
    import math

    from qropt.examples import paper_mechanism
    from qropt.io.report import TABLE2, TABLE3

    _, text = paper_report
    assert "Tables 2-3, Fig. 7b-c" in text
    m = paper_mechanism()
    m = type(m)(**{**m.params, "r3": 0.2504})
    rm = m.relative_motion(math.radians(60), 10.0)
    t = rm.terms()
    own = {e.quantity: float(np.hypot(*e.exact)) for e in rm.equations if e.joint == "D"}
    for label, (printed, key) in {**TABLE2, **TABLE3}.items():
        v = own[key] if key in own else t[key].magnitude
        assert abs(printed - v) / v < 5e-3, label
        row = re.search(re.escape(f"<td>{label}</td><td>{printed:g}</td>") + r"<td>[^<]*</td><td>([^<]*)</td>", text)
        assert row and float(row.group(1)) == pytest.approx(v, rel=1e-5), label


def test_a_six_bar_report_names_an_angle_in_degrees(tmp_path):
    import math

    import qropt

    p = qropt.Problem(
        "coupler-slider",
        fixed={"r1": 0.4, "r2": 0.1, "r3": 0.35, "r4": 0.3, "r6": 0.6, "h": 0.0},
        free={"r5": (0.05, 0.6), "beta": (-math.pi, math.pi)},
        targets={"time_ratio": 1.5, "stroke": 0.3},
    )
    text = render(p)
    beta = qropt.solve(p).params["beta"]
    assert f"<td>beta [deg]</td><td>{math.degrees(beta):.6g}</td>" in text and "beta [m]" not in text


def test_a_problem_file_report(tmp_path):
    text = render(paper_problem().replace(objective="min_size", name="small"), tmp_path / "small.html")
    assert "small" in text and "0.154344" in text and (tmp_path / "small.html").is_file()
    with pytest.raises(InvalidParameter, match="html"):
        render(None, tmp_path / "x.txt")


@pytest.mark.skipif(shutil.which("chromium") is None, reason="Chromium is not installed")
def test_chromium_renders_the_report(paper_report, tmp_path):
    path, _ = paper_report
    png = tmp_path / "shot.png"
    cmd = [
        "chromium",
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        "--no-first-run",
        f"--user-data-dir={tmp_path / 'u'}",
        "--window-size=1200,3000",
        f"--screenshot={png}",
        path.as_uri(),
    ]
    subprocess.run(cmd, capture_output=True, timeout=120, check=False)
    from PIL import Image

    im = Image.open(png).convert("L")
    assert im.size == (1200, 3000) and len(np.unique(np.asarray(im))) > 50  # text and figures, not blank
