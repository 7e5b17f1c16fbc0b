"""The ``qropt analyze`` command: text, JSON, full-cycle table and picture."""

from __future__ import annotations

import csv
import json
import math

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


def test_angle_parsing():
    assert cli.angle("60") == pytest.approx(math.radians(60))
    assert cli.angle("60deg") == pytest.approx(math.radians(60))
    assert cli.angle("1.5rad") == 1.5
