"""Bodies declared on the type: every picture (plot, DXF, SVG, GIF) draws them, for a user type with its own joint
names and a ternary plate too; a body naming a joint the positions lack is a typed error, never an omission."""

from __future__ import annotations

import math
import re
import xml.etree.ElementTree as ET
from collections import Counter
from pathlib import Path

import ezdxf
import numpy as np
import pytest

import qropt
from qropt.errors import BodyError
from qropt.examples import paper_mechanism
from qropt.io import drawing, export, plots
from qropt.io.animation import animate
from qropt.kinematics.closures import rod_lines, rod_to_line
from qropt.mechanisms import REQUIRED, TYPES, Body, Loop, Mechanism, Rule

SVG = "{http://www.w3.org/2000/svg}"


class PlateSlider(Mechanism):
    """A user type (no KIND: not registered): crank P-Q, a ternary rod-plate (Q, S, T) driving the ram S on y = e;
    T sits off the line QS by k."""

    PARAMS = {"r2": REQUIRED, "r3": REQUIRED, "e": 0.0, "k": 0.05, "sigma_slider": 1.0}
    LENGTHS = ("r2", "r3")
    BODIES = (Body("crank", ("P", "Q"), "bar"), Body("plate", ("Q", "S", "T"), "plate"), Body("ram", ("S",), "ram"))
    GROUND = ("P",)
    OUTPUT_JOINT = "S"

    @classmethod
    def rules(cls, xp, p, grashof=None):
        return [Rule("r3 >= r2 + |e|", p["r3"] - p["r2"] - abs(p["e"]))]

    @staticmethod
    def loop(xp, theta2, p):
        q = (p["r2"] * xp.cos(theta2), p["r2"] * xp.sin(theta2))
        s, margin = rod_to_line(xp, q, p["r3"], p["e"], p["sigma_slider"])
        t3 = xp.atan2(s[1] - q[1], s[0] - q[0])
        t = ((q[0] + s[0]) / 2 - p["k"] * xp.sin(t3), (q[1] + s[1]) / 2 + p["k"] * xp.cos(t3))
        return Loop(
            {"P": (0.0, 0.0), "Q": q, "S": s, "T": t},
            {"theta2": theta2, "theta3": t3},
            s[0],
            {"S": rod_lines(q, s)},
            [("rod QS reaching the slide line", margin)],
        )


class MissingJoint(PlateSlider):
    """Its rod names a joint 'C' that its loop does not give."""

    BODIES = (Body("crank", ("P", "Q"), "bar"), Body("rod", ("Q", "C"), "bar"), Body("ram", ("S",), "ram"))


def _toy():
    return PlateSlider(r2=0.1, r3=0.35, e=0.04, k=0.06)


def test_a_user_type_draws_every_declared_body(tmp_path):
    m = _toy()
    theta = math.radians(50)
    export.to_dxf(m, tmp_path / "t.dxf", theta)
    entities = Counter((e.dxftype(), e.dxf.layer) for e in ezdxf.readfile(tmp_path / "t.dxf").modelspace())
    assert entities[("LINE", "LINKS")] == 1  # the crank
    assert entities[("LWPOLYLINE", "LINKS")] == 1 and entities[("HATCH", "LINKS")] == 1  # the plate, filled
    assert entities[("LWPOLYLINE", "BLOCKS")] == 1 and entities[("LINE", "SLIDE_LINE")] == 1  # the ram on its line
    assert entities[("CIRCLE", "PIVOTS")] == 1 and entities[("CIRCLE", "JOINTS")] == 3
    assert entities[("LWPOLYLINE", "SLIDER_PATH")] == 1
    plate = next(e for e in ezdxf.readfile(tmp_path / "t.dxf").modelspace().query("LWPOLYLINE[layer=='LINKS']"))
    p = {k: v[0] for k, v in m.positions(np.array([theta])).points.items()}
    assert plate.closed and np.allclose([v[:2] for v in plate.get_points()], [p["Q"], p["S"], p["T"]], atol=1e-12)

    export.to_svg(m, tmp_path / "t.svg", theta)
    groups = {g.get("id"): g for g in ET.parse(tmp_path / "t.svg").getroot().iter(f"{SVG}g") if g.get("id")}
    assert len(groups["LINKS"].findall(f"{SVG}line")) == 1 and len(groups["LINKS"].findall(f"{SVG}polygon")) == 1
    assert groups["LINKS"].find(f"{SVG}polygon").get("fill") != "none"
    assert len(groups["BLOCKS"].findall(f"{SVG}polygon")) == 1 and len(groups["SLIDE_LINE"]) == 1

    fig = plots.cycle_figure(m, theta)
    ax = fig.axes[0]
    assert len(ax.patches) == 2  # the plate and the ram block
    assert {t.get_text() for t in ax.texts} == {"P", "Q", "S", "T"}
    plots.save(fig, tmp_path / "t.png")
    assert (tmp_path / "t.png").stat().st_size > 0

    from PIL import Image

    animate(m, tmp_path / "t.gif")
    assert Image.open(tmp_path / "t.gif").n_frames == 72


@pytest.mark.parametrize(
    "draw",
    [
        lambda m, d: export.to_dxf(m, d / "x.dxf"),
        lambda m, d: export.to_svg(m, d / "x.svg"),
        lambda m, d: plots.cycle_figure(m),
        lambda m, d: animate(m, d / "x.gif"),
        lambda m, d: plots.draw_mechanism(plots.plt.figure().add_subplot(), m, 0.0),
    ],
    ids=["dxf", "svg", "plot", "gif", "draw"],
)
def test_a_body_naming_a_missing_joint_is_a_typed_error(draw, tmp_path):
    with pytest.raises(BodyError, match=r"body 'rod' names joint 'C'"):
        draw(MissingJoint(r2=0.1, r3=0.35), tmp_path)
    assert not list(tmp_path.iterdir())  # nothing written


@pytest.mark.parametrize(
    ("attrs", "words"),
    [
        ({"BODIES": ()}, "declares no bodies"),
        ({"GROUND": ("O2",)}, "ground pivot 'O2'"),
        ({"OUTPUT_JOINT": "D"}, "output joint 'D'"),
        ({"OUTPUT_JOINT": None}, "needs its output joint"),
        ({"BODIES": (Body("crank", ("P", "Q"), "spring"),)}, "kind 'spring'"),
        ({"BODIES": (Body("ram", ("S", "Q"), "ram"),)}, "carries 1 joint"),
    ],
)
def test_bad_declarations_are_typed_errors(attrs, words):
    bad = type("Bad", (PlateSlider,), attrs)
    with pytest.raises(BodyError, match=words):
        drawing.check(bad(r2=0.1, r3=0.35))


def _every_type():
    return [
        paper_mechanism(),
        qropt.SliderCrank(r2=0.1, r3=0.35, e=0.06),
        qropt.CrankShaper(r1=160, r2=40, r4=240),
        qropt.CrankShaper(r1=160, r2=40, r4=240, r6=150, h=220),
        qropt.Whitworth(r1=0.1, r2=0.2, r5=0.12, r6=0.3),
        qropt.CrankRockerSlider(r1=0.4, r2=0.1, r3=0.35, r4=0.3, r5=0.4, r6=0.5, h=0.1),
        qropt.FourBar(r1=0.4, r2=0.1, r3=0.35, r4=0.3),
        qropt.CouplerSlider(r1=0.4, r2=0.1, r3=0.35, r4=0.3, r5=0.15, beta=0.5, r6=0.6, h=0.1),
        qropt.SlotRamShaper(r1=0.3, r2=0.1, h=0.5),
    ]


def test_every_shipped_type_declares_bodies_that_fit_its_joints():
    ms = _every_type()
    assert {type(m) for m in ms} == set(TYPES)
    for m in ms:
        bodies, ground, out = drawing.check(m)
        assert bodies[0] == Body("crank", ("O2", "A"), "bar") and "O2" in ground
        assert (out is None) == (m.OUTPUT == "follower")
    shaper, rod = ms[2], ms[3]
    assert [b.kind for b in shaper.bodies()] == ["bar", "block", "slot-lever", "yoke"] and shaper.output_joint() == "C"
    assert [b.name for b in rod.bodies()] == ["crank", "block", "lever", "rod", "ram"] and rod.output_joint() == "D"


@pytest.mark.parametrize(
    ("m", "length"),
    [
        (qropt.CrankShaper(r1=160, r2=40, r4=240), 240.0),
        (qropt.CrankShaper(r1=160, r2=40, r4=150, r6=150, h=150), 200.0),
        (qropt.Whitworth(r1=0.1, r2=0.2, r5=0.12, r6=0.3), 0.3),
    ],
)
def test_a_slotted_lever_is_drawn_at_its_true_length(m, length):
    """CONVENTIONS, Dynamics: the lever runs from O4 along O4->A for max(r4 or r5, r1 + r2), at every angle."""
    sc = drawing.scene(m)
    for theta in (0.3, 2.0, 4.5):
        lever = [s for s in drawing.at(sc, theta) if s.name == "lever" and s.part == "link"]
        assert len(lever) == 1 and math.dist(*lever[0].points) == pytest.approx(length, abs=1e-9)


def test_io_asks_the_type_not_its_class_or_joint_names():
    for f in Path(drawing.__file__).parent.glob("*.py"):
        text = f.read_text()
        assert "FourBar" not in text, f.name
        assert not re.search(r"""["'](?:A|B|C|D|O4)["']""", text), f.name
