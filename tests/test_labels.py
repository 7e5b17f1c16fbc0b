"""The joints' names on every picture of a mechanism (``qropt.io.plots.draw_shapes``, placed by
``qropt.io._labels.place_labels``): measured as matplotlib draws them (Agg, window extents in pixels), no name over
another, none over a joint's marker other than its own, each beside its joint; and the notebook's SVG alike."""

from __future__ import annotations

import math

import numpy as np
import pytest

from qropt.io import _labels as labels
from qropt.io import plots
from qropt.mechanisms import TYPES

ANGLES = (0, 60, 135, 210, 300)  # deg
NEAR = 32.0  # pixels at 110 dpi: from a joint's centre to its name's box, at most


def measured(fig, ax):
    """Each name's text, its box and its joint (pixels), and every joint marker's box, as drawn."""
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    names = [t for t in ax.texts if hasattr(t, "xyann") and t.get_text()]  # not the arrows
    markers = [
        (ax.transData.transform((line.get_xdata()[0], line.get_ydata()[0])), line.get_window_extent(renderer))
        for line in ax.lines
        if line.get_marker() not in (None, "None", "") and len(line.get_xdata()) == 1
    ]
    return [(t.get_text(), t.get_window_extent(renderer), ax.transData.transform(t.xy)) for t in names], markers


def assert_apart(fig, ax, expected):
    names, markers = measured(fig, ax)
    assert sorted(n for n, _, _ in names) == sorted(expected)
    for i, (a, box_a, _) in enumerate(names):
        for b, box_b, _ in names[i + 1 :]:
            assert not box_a.overlaps(box_b), f"{a} over {b}"
    for name, box, at in names:
        for centre, marker in markers:
            if np.hypot(*(centre - at)) > 1e-6:
                assert not box.overlaps(marker), f"{name} over the joint at {centre}"
        gap = np.hypot(max(box.x0 - at[0], 0.0, at[0] - box.x1), max(box.y0 - at[1], 0.0, at[1] - box.y1))
        assert 0.0 < gap <= NEAR, f"{name} {gap:.1f} px from its joint"


@pytest.mark.parametrize("kind", TYPES, ids=lambda t: t.__name__)
def test_names_apart_on_each_type_example(kind):
    """The type's example at a few crank angles, in the drawing panel of ``cycle_figure`` (``m.plot``, the CLI's
    and the report's pictures) and in a small panel as a comparison's or a front's."""
    m = kind(**kind.EXAMPLE)
    joints = list(m.positions(np.zeros(1)).points)
    for figsize, panel in (((12, 5.5), (1, 2, 1)), ((4.2, 4.6), (1, 1, 1))):
        for deg in ANGLES:
            fig = plots.plt.figure(figsize=figsize, dpi=110)  # as plots.save writes
            try:
                ax = fig.add_subplot(*panel)
                plots.draw_mechanism(ax, m, math.radians(deg))
                ax.set_xlabel(f"x [{m.units}]")
                ax.set_ylabel(f"y [{m.units}]")
                fig.tight_layout()
                assert_apart(fig, ax, joints)
            finally:
                plots.plt.close(fig)


def test_names_are_placed_at_the_final_limits():
    """Limits set after drawing (as a comparison's one scale or the classroom's frame) move the names with them."""
    m = TYPES[0](**TYPES[0].EXAMPLE)
    fig, ax = plots.plt.subplots(figsize=(4, 4))
    try:
        plots.draw_mechanism(ax, m, 1.0)
        b = m.bounding_box()
        span = 1.5 * max(b.x_max - b.x_min, b.y_max - b.y_min)
        ax.set_xlim(b.x_min, b.x_min + span)
        ax.set_ylim(b.y_min, b.y_min + span)
        assert_apart(fig, ax, list(m.positions(np.zeros(1)).points))
    finally:
        plots.plt.close(fig)


def test_place_labels_keeps_crowded_names_apart_and_is_deterministic():
    points = [(0.0, 0.0), (12.0, 0.0), (6.0, 9.0), (200.0, 0.0)]
    sizes = [(14.0, 11.0)] * 4
    args = (points, sizes, [5.0] * 4, [2.0, 5.0, 10.0, 16.0], [(np.array(points[:3]), 1.0)])
    placed = labels.place_labels(*args, frame=(-100.0, -100.0, 300.0, 100.0))
    assert placed == labels.place_labels(*args, frame=(-100.0, -100.0, 300.0, 100.0))
    boxes = np.array([box for *_, box in placed])
    for i, a in enumerate(boxes):
        for b in boxes[i + 1 :]:
            assert labels._overlap(a[None], b)[0] == 0.0
        for j, p in enumerate(points):
            if j != i:  # no box within another joint's marker
                gx = max(a[0] - p[0], 0.0, p[0] - a[2])
                gy = max(a[1] - p[1], 0.0, p[1] - a[3])
                assert math.hypot(gx, gy) >= 5.0
    assert placed[3][0] == labels.LABEL_DIRECTIONS[0]  # a joint alone: the first direction, the nearest gap
    assert placed[3][1] == 5.0 + 2.0


def test_a_joint_inside_a_block_is_named_outside_it():
    block = np.array([(-20.0, -20.0), (20.0, -20.0), (20.0, 20.0), (-20.0, 20.0)])
    (u, r, box), *_ = labels.place_labels([(0.0, 0.0)], [(10.0, 11.0)], [4.0], [2.0], solids=[block])
    x0, y0, x1, y1 = box
    assert x0 >= 20.0 or x1 <= -20.0 or y0 >= 20.0 or y1 <= -20.0
    assert r <= 20.0 * math.sqrt(2.0) + 2.0 + 1e-9


def test_names_keep_off_what_else_is_written_and_drawn():
    """A taken box (another text, a legend) and a line (an arrow) where a name would go move it elsewhere."""
    alone = labels.place_labels([(0.0, 0.0)], [(10.0, 11.0)], [4.0], [2.0])
    (u, _, box), *_ = alone
    assert u == labels.LABEL_DIRECTIONS[0]
    (u_taken, _, box_taken), *_ = labels.place_labels([(0.0, 0.0)], [(10.0, 11.0)], [4.0], [2.0], taken=[box])
    assert u_taken != u and labels._overlap(np.array([box_taken]), box)[0] == 0.0
    arrow = (np.array([(0.0, 0.0), (30.0, 30.0)]), 1.0)
    (u_arrow, _, _), *_ = labels.place_labels([(0.0, 0.0)], [(10.0, 11.0)], [4.0], [2.0], lines=[arrow])
    assert u_arrow != u


def test_the_forces_figure_names_clear_of_its_legend_and_arrows():
    from qropt.examples import paper_mechanism

    fig = plots.dynamics_figure(paper_mechanism(), 10.0, theta2=math.radians(60))
    try:
        fig.set_dpi(110)
        ax = fig.axes[0]
        assert_apart(fig, ax, ["O2", "A", "B", "O4", "C", "D"])
        names, _ = measured(fig, ax)
        legend = ax.get_legend().get_window_extent(fig.canvas.get_renderer())
        assert not any(box.overlaps(legend) for _, box, _ in names)
    finally:
        plots.plt.close(fig)


@pytest.mark.parametrize("kind", TYPES, ids=lambda t: t.__name__)
def test_the_notebook_picture_names_apart(kind):
    """``notebook.mechanism_svg`` places its names with the same rule: their boxes (as estimated for 12 px text)
    apart, over no joint's marker, each within NEAR px of one."""
    import xml.etree.ElementTree as ET

    from qropt.io import notebook

    svg = "{http://www.w3.org/2000/svg}"
    m = kind(**kind.EXAMPLE)
    for deg in ANGLES:
        root = ET.fromstring(notebook.mechanism_svg(m, math.radians(deg)))
        marks = [(float(r.get("x")) + 4, float(r.get("y")) + 4, 4.0) for r in root.iter(f"{svg}rect")]
        marks += [(float(c.get("cx")), float(c.get("cy")), 3.2) for c in root.iter(f"{svg}circle")]
        names = [t for t in root.iter(f"{svg}text") if t.get("stroke") == "#fff"]
        assert sorted(t.text for t in names) == sorted(m.positions(np.zeros(1)).points)
        boxes = []
        for t in names:
            x, y = float(t.get("x")) - 1.0, float(t.get("y")) + 1.0
            boxes.append((x, y - notebook.NAME_HEIGHT, x + notebook.NAME_CHAR * len(t.text) + 2.0, y))
        for i, a in enumerate(boxes):
            for b in boxes[i + 1 :]:
                assert labels._overlap(np.array([a]), b)[0] == 0.0, deg
            gaps = [math.hypot(max(a[0] - x, 0.0, x - a[2]), max(a[1] - y, 0.0, y - a[3])) for x, y, _ in marks]
            assert all(g >= r for g, (*_, r) in zip(gaps, marks, strict=True)), deg  # over no marker, its own neither
            assert min(gaps) <= NEAR, deg
