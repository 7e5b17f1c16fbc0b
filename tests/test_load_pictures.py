"""The dynamics figure under general loads: one arrow per force from its point, to the joint forces' scale, named
with its size; a curved arrow per torque; gravity's direction in a corner; a load off at the figure's angle faded
and said to be off; pin friction named; the joints' names clear of the loads' names."""

from __future__ import annotations

import math
import re

import matplotlib.pyplot as plt
import numpy as np
import pytest

import qropt
from qropt.io import plots
from qropt.mechanisms import TYPES

THETA2 = math.radians(60)
SHAPER = qropt.CrankShaper(r1=0.2, r2=0.08, r4=0.5)
MASSES = qropt.Masses.steel(4e-4, ram=20.0, points={"A": 1.5})
LOADS = qropt.Loads(
    forces=[
        qropt.Force("C", 600.0, "against", "working"),  # the cut
        qropt.Force(("lever", 0.35, 0.0), 300.0, (0.0, -1.0), "always"),  # down, at a point of the lever
        qropt.Force("C", 150.0, "slide", qropt.Window(x=(0.0, 0.05), stroke="return")),  # off at 60 deg
    ],
    torques=[qropt.Torque("lever", -20.0)],
    gravity=(-3.0, -9.3),
)


@pytest.fixture(scope="module")
def figure():
    fig = plots.dynamics_figure(SHAPER, 10.0, MASSES, LOADS, THETA2)
    fig.canvas.draw()
    yield fig
    plt.close(fig)


def _arrows(ax) -> list:
    """The axis' arrows: (tail, head, colour) in data."""
    out = []
    for t in ax.texts:
        if getattr(t, "arrow_patch", None) is not None and t.xycoords == "data":
            out.append((np.asarray(t.xyann, float), np.asarray(t.xy, float), t.arrow_patch.get_edgecolor()))
    return out


def _load_arrows(ax) -> list:
    red = plt.matplotlib.colors.to_rgba(plots.LOAD_COLOUR)
    return [(a, b) for a, b, c in _arrows(ax) if np.allclose(c[:3], red[:3])]


def test_the_loads_at_the_figures_angle_are_the_dynamics_own():
    """Their points and forces: the joint's position, the lever's point, the window's state, and what they do to
    the torque: the crank torque of the figure's angle is the dynamics' with the loads."""
    drawn = plots.applied_loads(SHAPER, THETA2, 10.0, MASSES, LOADS)
    assert [d.name for d in drawn] == ["F1", "F2", "F3", "T1"]
    c = SHAPER.positions(np.array([THETA2])).points["C"][0]
    assert drawn[0].point == pytest.approx(tuple(c)) and drawn[0].on
    v = SHAPER.motion(np.array([THETA2]), 10.0).v[0]
    assert drawn[0].value == pytest.approx([-600.0 * math.copysign(1.0, v), 0.0])  # against the ram's motion
    o4 = SHAPER.positions(np.array([THETA2])).points["O4"][0]
    u = (c - o4) / np.hypot(*(c - o4))
    assert drawn[1].point == pytest.approx(tuple(o4 + 0.35 * u))  # 0.35 m from O4 along the lever
    assert drawn[1].value == pytest.approx([0.0, -300.0]) and drawn[1].on
    assert not drawn[2].on and drawn[2].value == pytest.approx([150.0, 0.0])  # what it would be, were it on
    assert drawn[3].value == -20.0 and drawn[3].on


def test_one_arrow_per_force_from_its_point_to_the_joint_forces_scale(figure):
    ax = figure.axes[0]
    everything = plots.applied_loads(SHAPER, THETA2, 10.0, MASSES, LOADS)
    drawn = [d for d in everything if d.name.startswith("F")]
    (t1,) = [d for d in everything if d.name == "T1"]
    (arc,) = [ln.get_xydata() for ln in ax.lines if len(ln.get_xydata()) > 10 and ln.get_color() == plots.LOAD_COLOUR]
    radius = np.hypot(*(arc[0] - t1.point))
    on_arc = [abs(np.hypot(*(a - t1.point)) - radius) < 1e-9 for a, _ in _load_arrows(ax)]  # the torque's head
    straight = [(a, b) for (a, b), arc in zip(_load_arrows(ax), on_arc, strict=True) if not arc]
    assert len(straight) == len(drawn) == 3 and sum(on_arc) == 1
    d = SHAPER.dynamics(np.array([THETA2]), 10.0, masses=MASSES, loads=LOADS)
    scales = []
    for tail, head, _ in _arrows(ax):
        for f in d.joint_forces.values():
            ratio = np.hypot(*(head - tail)) / np.hypot(*f[0])
            if ratio > 0 and np.allclose(head - tail, ratio * f[0]):
                scales.append(ratio)
    scale = scales[0]
    assert len(scales) >= 4 and scales == pytest.approx([scale] * len(scales))
    for dl in drawn:
        found = [a for a, b in straight if np.allclose(a, dl.point) and np.allclose(b - a, scale * dl.value)]
        assert len(found) == 1, dl.name  # from its point, to the joint forces' scale


def test_the_names_say_the_sizes_and_what_is_off(figure):
    ax = figure.axes[0]
    texts = {t.get_text(): t for t in ax.texts if t.get_text()}
    assert {"F1 600 N", "F2 300 N", "F3 150 N (off)", "T1 -20 N m", "g 9.77 m/s^2"} <= set(texts)
    assert texts["F3 150 N (off)"].get_alpha() < 0.5 and texts["F1 600 N"].get_alpha() == 1.0
    legend = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "F1 at C, against: 600 N" in legend and "F3 at C, slide: 150 N (off here)" in legend
    assert "T1 on the lever: -20 N m" in legend
    assert "dark red" in ax.get_title()


def test_the_torque_is_a_curved_arrow_on_its_body_and_gravity_points_its_way(figure):
    ax = figure.axes[0]
    red = plt.matplotlib.colors.to_rgba(plots.LOAD_COLOUR)
    colour = plt.matplotlib.colors.to_rgba
    arcs = [ln for ln in ax.lines if len(ln.get_xydata()) > 10 and np.allclose(colour(ln.get_color()), red)]
    assert len(arcs) == 1
    xy = arcs[0].get_xydata()
    centre = xy.mean(axis=0)
    (t1,) = [d for d in plots.applied_loads(SHAPER, THETA2, 10.0, MASSES, LOADS) if d.name == "T1"]
    radius = np.hypot(*(xy - t1.point).T)
    assert radius == pytest.approx(np.full(len(xy), radius[0]))  # a circle's arc about the torque's point
    pos = SHAPER.positions(np.array([THETA2])).points
    o4, c = pos["O4"][0], pos["C"][0]
    cross = (c - o4)[0] * (np.array(t1.point) - o4)[1] - (c - o4)[1] * (np.array(t1.point) - o4)[0]
    assert abs(cross) < 1e-9 and np.hypot(*(centre - t1.point)) < radius[0]  # on the lever's line
    # the clockwise torque's head at the arc's start, pointing clockwise
    ((tail, head),) = [(a, b) for a, b in _load_arrows(ax) if 0 < np.hypot(*(b - a)) < 1e-2]
    assert head == pytest.approx(xy[0])
    r0, r1 = tail - t1.point, head - t1.point
    assert r0[0] * r1[1] - r0[1] * r1[0] < 0  # turning clockwise
    g = [t for t in ax.texts if getattr(t, "arrow_patch", None) is not None and t.xycoords != "data"]
    assert len(g) == 1
    u = np.subtract(g[0].xy, g[0].xyann)
    assert u / np.hypot(*u) == pytest.approx(np.array([-3.0, -9.3]) / math.hypot(3.0, 9.3))


def test_the_joints_names_are_clear_of_the_loads_names(figure):
    ax = figure.axes[0]
    r = figure.canvas.get_renderer()
    names = {"O2", "A", "O4", "C"}
    loads = [t for t in ax.texts if re.match(r"^(F|T)\d|^g ", t.get_text())]
    joints = [t for t in ax.texts if t.get_text() in names]
    assert len(loads) == 5 and len(joints) == 4
    for j in joints:
        jb = j.get_window_extent(r)
        for t in loads:
            assert not jb.overlaps(t.get_window_extent(r)), (j.get_text(), t.get_text())


def test_the_legend_is_under_the_drawing(figure):
    ax = figure.axes[0]
    r = figure.canvas.get_renderer()
    assert ax.get_legend().get_window_extent(r).y1 < ax.get_window_extent(r).y0


def test_pin_friction_is_named_and_the_shorthands_drawn_as_before():
    m = qropt.CrankShaper(r1=0.2, r2=0.08, r4=0.5)
    loads = qropt.Loads(600.0, gravity=9.81, pin_friction=qropt.PinFriction(0.1, 0.01))
    fig = plots.dynamics_figure(m, 10.0, qropt.Masses.steel(4e-4, ram=20.0), loads, THETA2)
    try:
        ax = fig.axes[0]
        legend = [t.get_text() for t in ax.get_legend().get_texts()]
        assert "pin friction mu 0.1, pins r 0.01 m (in the joint forces)" in legend
        assert not [t for t in ax.texts if re.match(r"^[FT]\d", t.get_text())]  # no force or torque to draw
        assert "g 9.81 m/s^2" in [t.get_text() for t in ax.texts]
    finally:
        plt.close(fig)


def test_a_force_at_an_unknown_joint_is_refused_by_name():
    with pytest.raises(qropt.InvalidParameter, match="no joint 'Q'"):
        plots.dynamics_figure(SHAPER, 10.0, MASSES, qropt.Loads(forces=[qropt.Force("Q", 1.0)]), THETA2)


def test_the_svg_holds_the_loads(tmp_path):
    path = tmp_path / "loads.svg"
    plots.save(plots.dynamics_figure(SHAPER, 10.0, MASSES, LOADS, THETA2), path)
    text = path.read_text()
    for name in ("F1 600 N", "F2 300 N", "F3 150 N (off)", "T1 -20 N m"):
        assert name in text or name.replace(" ", "") in re.sub(r"<[^>]*>|\s", "", text), name


@pytest.mark.parametrize("kind", TYPES, ids=lambda t: t.__name__)
def test_every_type_draws_its_loads(kind):
    """A force at every joint (a fixed direction, always on) and a torque on every body that turns: one arrow from
    each force's point, one arc per torque, each named, gravity in a corner."""
    from qropt.dynamics.inverse import linkage_of

    m = kind(**kind.EXAMPLE)
    link = linkage_of(m)
    joints = sorted({j for b in link.bodies() for j in b.joints})
    turning = [b.name for b in link.bodies() if b.kind not in ("ram", "block")]
    loads = qropt.Loads(
        forces=[qropt.Force(j, 50.0 + 10 * i, (1.0, 0.5), "always") for i, j in enumerate(joints)],
        torques=[qropt.Torque(b, 3.0 * (-1) ** i) for i, b in enumerate(turning)],
        gravity=(1.0, -9.0),
    )
    masses = qropt.Masses.bars(2.0, 5.0, block=1.0)
    drawn = plots.applied_loads(m, THETA2, 10.0, masses, loads)
    fig = plots.dynamics_figure(m, 10.0, masses, loads, THETA2)
    try:
        fig.canvas.draw()
        ax = fig.axes[0]
        texts = [t.get_text() for t in ax.texts]
        assert [t for t in texts if re.match(r"^F\d+ ", t)] == [
            f"F{i + 1} {50 + 10 * i:g} N" for i in range(len(joints))
        ]
        assert len([t for t in texts if re.match(r"^T\d+ ", t)]) == len(turning)
        for d in drawn[: len(joints)]:
            assert any(np.allclose(a, d.point) for a, _ in _load_arrows(ax)), d.name
        assert "g 9.06 m/s^2" in texts
        r = fig.canvas.get_renderer()
        boxes = [(t.get_text(), t.get_window_extent(r)) for t in ax.texts if t.get_text()]
        loads_ = [(n, b) for n, b in boxes if re.match(r"^(F|T)\d+ |^g ", n)]
        for n, b in loads_:
            for n2, b2 in boxes:
                if n2 != n:
                    assert not b.overlaps(b2), (kind.__name__, n, n2)
    finally:
        plt.close(fig)
