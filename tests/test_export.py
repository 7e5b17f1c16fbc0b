"""Drawings and design files: DXF and SVG link lines at their true lengths on their layers, design round trips."""

from __future__ import annotations

import json
import math
import xml.etree.ElementTree as ET

import ezdxf
import numpy as np
import pytest

import qropt
from qropt import InvalidParameter, cli
from qropt.examples import paper_mechanism
from qropt.io import export

MECHANISMS = [
    paper_mechanism(),
    qropt.SliderCrank(r2=0.1, r3=0.35, e=0.06),
    qropt.CrankShaper(r1=160, r2=40, r4=240),
    qropt.Whitworth(r1=0.1, r2=0.2, r5=0.12, r6=0.3),
    qropt.CrankRockerSlider(r1=0.4, r2=0.1, r3=0.35, r4=0.3, r5=0.4, r6=0.5, h=0.1),
]


def _links(m, theta):
    """The lengths the drawing must show: every declared bar from its first joint to its farthest, and every slotted
    lever as far as its joints reach over a turn."""
    p = {k: v[0] for k, v in m.positions(theta).points.items()}
    turn = m.positions(np.linspace(0.0, 2 * math.pi, 361)).points
    out = []
    for b in m.bodies():
        if b.kind == "bar":
            out.append(max(math.dist(p[b.joints[0]], p[j]) for j in b.joints[1:]))
        elif b.kind == "slot-lever":
            out.append(max(float(np.hypot(*(turn[j] - turn[b.joints[0]]).T).max()) for j in b.joints[1:]))
    return sorted(out)


@pytest.mark.parametrize("m", MECHANISMS, ids=lambda m: m.KIND)
def test_dxf_lines_have_the_true_link_lengths(m, tmp_path):
    theta = math.radians(60)
    export.to_dxf(m, tmp_path / "m.dxf", theta)
    doc = ezdxf.readfile(tmp_path / "m.dxf")
    lines = [math.dist(e.dxf.start, e.dxf.end) for e in doc.modelspace().query("LINE[layer=='LINKS']")]
    assert np.allclose(sorted(lines), _links(m, theta), rtol=0, atol=1e-9)
    p = m.params
    crank = next(x for x in lines if abs(x - p["r2"]) < 1e-9)
    assert crank == pytest.approx(p["r2"], abs=1e-12)
    assert {layer.dxf.name for layer in doc.layers} >= set(export.LAYERS)
    path = doc.modelspace().query("LWPOLYLINE[layer=='SLIDER_PATH']")
    assert len(path) == 1 and len(path[0]) == 361


@pytest.mark.parametrize("m", MECHANISMS, ids=lambda m: m.KIND)
def test_svg_groups_and_lengths(m, tmp_path):
    export.to_svg(m, tmp_path / "m.svg", 0.3)
    root = ET.parse(tmp_path / "m.svg").getroot()
    ns = {"s": "http://www.w3.org/2000/svg"}
    groups = {g.get("id"): g for g in root.iter("{http://www.w3.org/2000/svg}g") if g.get("id")}
    assert set(groups) == set(export.LAYERS)
    lines = [
        math.dist((float(e.get("x1")), float(e.get("y1"))), (float(e.get("x2")), float(e.get("y2"))))
        for e in groups["LINKS"].findall("s:line", ns)
    ]
    assert np.allclose(sorted(lines), _links(m, 0.3), rtol=0, atol=1e-9)


def test_design_files_round_trip_through_the_command_line(tmp_path, capsys):
    f = tmp_path / "d.json"
    assert cli.main(["synth", "--save", str(f)]) == 0
    capsys.readouterr()
    m = export.load_design(f)
    assert m.params["r3"] == pytest.approx(0.2504281217548, abs=1e-12)
    assert cli.main(["analyze", "--from", str(f), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["params"] == dict(m.params) and out["time_ratio"] == pytest.approx(1.5, abs=1e-12)
    assert export.load_design(f) == m


@pytest.mark.parametrize(
    ("text", "words"),
    [
        (None, "no design file"),
        ("{", "not a JSON design"),
        ('{"type": "x"}', "'type' and 'params'"),
        ('{"type": "bogus", "params": {}}', "unknown mechanism"),
        ('{"type": "slider-crank", "params": {"r2": 1}}', "missing"),
    ],
)
def test_bad_design_files_are_typed_errors(text, words, tmp_path):
    f = tmp_path / "d.json"
    if text is not None:
        f.write_text(text)
    with pytest.raises(InvalidParameter, match=words):
        export.load_design(f)


def test_wrong_suffix_is_an_error(tmp_path):
    with pytest.raises(InvalidParameter, match=".dxf"):
        export.to_dxf(paper_mechanism(), tmp_path / "m.txt")


def test_animation_is_a_gif_of_one_turn(tmp_path):
    from PIL import Image

    from qropt.io.animation import animate

    f = tmp_path / "m.gif"
    animate(qropt.SliderCrank(r2=0.1, r3=0.35, e=0.06), f, omega2=-2.0)
    im = Image.open(f)
    assert im.format == "GIF" and im.n_frames == 72
    with pytest.raises(InvalidParameter, match="frames"):
        animate(paper_mechanism(), tmp_path / "x.gif", frames=10)
    with pytest.raises(InvalidParameter, match=".gif"):
        animate(paper_mechanism(), tmp_path / "x.png")
