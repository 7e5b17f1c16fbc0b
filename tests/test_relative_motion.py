"""Relative-motion analysis (the paper's polygons): every equation's terms sum to the joint's exact velocity and
acceleration from the jets (an independent route: each term's rate comes from its link's angle), for random
mechanisms of every type; the paper's Tables 2-3 (measured on drawn polygons) within 0.5 %."""

from __future__ import annotations

import math

import numpy as np
import pytest

import qropt
from qropt.examples import paper_mechanism
from qropt.mechanisms import TYPES
from tests import randmech


def _designs(cls, n=6):
    return [m for _, m in randmech.random_mechanisms(cls.KIND, n, seed=3)]


@pytest.mark.parametrize("cls", TYPES, ids=lambda c: c.KIND)
def test_the_terms_sum_to_the_exact_motion(cls):
    for m in _designs(cls):
        scale = max(abs(v) for k, v in m.params.items() if k in m.LENGTHS)
        for theta2 in (0.3, 2.0, 4.4):
            rm = m.relative_motion(theta2, omega2=7.0, alpha2=-3.0)
            assert rm.equations
            for e in rm.equations:
                size = scale * (7.0 if e.quantity == "velocity" else 49.0)
                assert e.residual <= 1e-11 * size, (cls.KIND, e.joint, e.quantity, e.residual)
                for t in e.terms:
                    if t.kind == "relative" and "/" in t.name and "'" not in t.name:  # normal to its link
                        j, o = t.name[2:].split("/")
                        r = np.array(m.positions(theta2).points[j][0]) - np.array(m.positions(theta2).points[o][0])
                        assert abs(float(np.dot(t.vector, r))) <= 1e-11 * size * scale


def test_a_block_in_a_turning_slot_has_its_sliding_and_coriolis_terms():
    m = qropt.CrankShaper(r1=0.3, r2=0.1, r4=0.6)
    terms = m.relative_motion(1.0, omega2=5.0).terms()
    slide, cor = terms["V_A/A' (slide)"], terms["A_A (Coriolis)"]
    lever = np.array(m.positions(1.0).points["A"][0]) - np.array(m.positions(1.0).points["O4"][0])
    along = slide.vector[0] * lever[1] - slide.vector[1] * lever[0]
    assert abs(along) <= 1e-12 * slide.magnitude * np.hypot(*lever)  # along the slot
    omega4 = m.motion(1.0, 5.0).omega["theta4"][0]
    assert cor.magnitude == pytest.approx(2 * abs(omega4) * slide.magnitude, rel=1e-12)


def test_the_paper_tables_2_and_3_within_half_a_percent():
    m = paper_mechanism()
    t = m.relative_motion(math.radians(60), omega2=10.0).terms()
    printed = {"V_B/A": 1.898, "V_C/O4": 1.756, "V_D/C": 1.631, "A_A/O2^n": 22.50, "A_B/A^n": 14.39, "A_D/C^n": 8.87}
    for name, v in printed.items():
        assert t[name].magnitude == pytest.approx(v, rel=5e-3), name
    exact = {e.joint: e.exact for e in m.relative_motion(math.radians(60), omega2=10.0).equations}
    assert np.hypot(*t["V_B/O4"].vector) == pytest.approx(3.219, rel=5e-3)
    assert t["A_B/O4^n"].magnitude == pytest.approx(37.68, rel=5e-3)
    assert np.hypot(*exact["D"]) == pytest.approx(21.7, rel=5e-3)
    rows = m.relative_motion(math.radians(60), omega2=10.0).table()
    assert {"joint", "term", "magnitude", "direction_deg", "solved"} <= set(rows[0])


def test_a_type_without_a_builder_linkage_has_no_polygons():
    class Hand(qropt.SliderCrank):
        KIND = "hand-slider-for-polygons"

        @staticmethod
        def loop(xp, theta2, p):
            return qropt.SliderCrank.loop(xp, theta2, p)

    with pytest.raises(qropt.InvalidParameter, match="not declared with the linkage builder"):
        Hand(r2=0.1, r3=0.4).relative_motion(0.5)


def test_the_command_line_prints_the_terms_and_draws_the_polygons(tmp_path, capsys):
    from qropt import cli

    path = tmp_path / "polygons.png"
    assert cli.main(["analyze", "--theta2", "60deg", "--omega2", "10", "--polygons", "--plot", str(path)]) == 0
    out = capsys.readouterr().out
    assert "V_B/A" in out and "solved" in out and path.stat().st_size > 10_000
    assert cli.main(["analyze", "--theta2", "60deg", "--omega2", "10", "--polygons", "--json"]) == 0
    import json

    rows = json.loads(capsys.readouterr().out)["terms"]
    assert next(r for r in rows if r["term"] == "V_B/A")["magnitude"] == pytest.approx(1.898, rel=5e-3)
