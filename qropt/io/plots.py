"""Pictures: a mechanism drawn at one crank angle beside its output over the cycle."""

from __future__ import annotations

import math
from typing import NamedTuple

import matplotlib

matplotlib.use("Agg")
import matplotlib.artist  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.colors import to_rgba  # noqa: E402
from matplotlib.patches import Polygon  # noqa: E402
from matplotlib.transforms import offset_copy  # noqa: E402

from qropt.errors import InvalidParameter  # noqa: E402
from qropt.io import drawing  # noqa: E402
from qropt.io._labels import LINE_WEIGHTS, SOLIDS, align, place_labels  # noqa: E402
from qropt.mechanisms import Mechanism  # noqa: E402
from qropt.synthesis import criteria  # noqa: E402
from qropt.validate import picture_path  # noqa: E402

PIVOT_SIZE, JOINT_SIZE, LABEL_SIZE = 7, 5, 8  # marker sizes and the joints' names, points
LABEL_GAPS = (1.5, 4.0, 8.0, 13.0)  # a label's box from its joint's marker, points: nearest first


def draw_shapes(ax, shapes, color="k", alpha=1.0, labels=True, joint_color=None) -> list:
    """Draw shapes of ``qropt.io.drawing`` on a matplotlib axis; the artists. With ``labels`` each pivot's and
    joint's name is set beside it where ``place_labels`` finds room when the figure is drawn (``JointLabels``)."""
    out = []
    joint_color = joint_color or color
    names = []
    for s in shapes:
        xy = np.array(s.points)
        if s.part == "link":
            out += ax.plot(xy[:, 0], xy[:, 1], color=color, lw=2, alpha=alpha, solid_capstyle="round", zorder=2)
        elif s.part == "plate":
            patch = Polygon(
                xy, closed=True, facecolor=to_rgba(color, 0.25 * alpha), edgecolor=to_rgba(color, alpha), lw=2, zorder=2
            )
            out.append(ax.add_patch(patch))
        elif s.part == "slot":
            out.append(
                ax.add_patch(
                    Polygon(xy, closed=True, fill=False, edgecolor=to_rgba(color, 0.8 * alpha), lw=1, zorder=2.5)
                )
            )
        elif s.part in ("block", "ram"):
            out.append(
                ax.add_patch(
                    Polygon(xy, closed=True, facecolor="white", edgecolor=to_rgba(color, alpha), lw=1.5, zorder=3)
                )
            )
        elif s.part == "slide":
            out += ax.plot(xy[:, 0], xy[:, 1], color="0.5", lw=1, ls="-.", zorder=1)
        elif s.part == "path":
            out += ax.plot(xy[:, 0], xy[:, 1], color="tab:blue", lw=3, alpha=0.4, zorder=1.5)
        else:  # a pivot or a joint
            pivot = s.part == "pivot"
            (x, y), c = s.points[0], color if pivot else joint_color
            ms = PIVOT_SIZE if pivot else JOINT_SIZE
            out += ax.plot(x, y, "s" if pivot else "o", color=c, ms=ms, alpha=alpha, zorder=4)
            names.append((s.name, (x, y), ms * (math.sqrt(2.0) if pivot else 1.0) / 2))  # the marker's radius
    if labels and names:
        texts = [
            ax.annotate(
                name,
                xy,
                textcoords="offset points",
                xytext=(4, 4),
                fontsize=LABEL_SIZE,
                alpha=alpha,
                zorder=6,
                bbox={"fc": "white", "ec": "none", "pad": 0.5, "alpha": 0.8 * alpha},
            )
            for name, xy, _ in names
        ]
        placer = JointLabels(texts, [xy for _, xy, _ in names], [r for _, _, r in names], shapes, out)
        out += [*texts, ax.add_artist(placer)]
    return out


class JointLabels(matplotlib.artist.Artist):
    """Places the joints' names (annotations offset in points) when the figure is drawn, by ``place_labels`` in
    display pixels, so that they stay apart at the axis' final limits and size; draws nothing itself. Besides the
    shapes' links, blocks and markers it keeps the names off what else the axis holds: its other lines, arrows
    (annotations from and to data points), texts and legend."""

    def __init__(self, texts, points, radii, shapes, own=()):
        super().__init__()
        self.texts, self.points, self.radii = list(texts), np.asarray(points, float).reshape(-1, 2), list(radii)
        self.own = {id(a) for a in [*own, *texts]}  # the shapes' artists, drawn as shapes
        self.lines = [(np.asarray(s.points, float), LINE_WEIGHTS[s.part]) for s in shapes if s.part in LINE_WEIGHTS]
        self.solids = [np.asarray(s.points, float) for s in shapes if s.part in SOLIDS]
        self.set_zorder(5.9)  # drawn before the labels (zorder 6)
        self.set_in_layout(False)

    def draw(self, renderer):
        if not self.get_visible() or not self.texts:
            return
        to_px = self.axes.transData.transform
        px = renderer.points_to_pixels(1.0)
        sizes = [(b.width, b.height) for b in (t.get_window_extent(renderer) for t in self.texts)]
        lines = [(to_px(p), w) for p, w in self.lines if len(p) > 1] + self._other_lines()
        bb = self.axes.bbox
        placed = place_labels(
            to_px(self.points),
            sizes,
            [r * px for r in self.radii],
            [g * px for g in LABEL_GAPS],
            lines,
            [to_px(p) for p in self.solids],
            (bb.x0, bb.y0, bb.x1, bb.y1),
            self._other_boxes(renderer),
        )
        for t, (u, r, _) in zip(self.texts, placed, strict=True):
            t.xyann = (r / px * u[0], r / px * u[1])
            ha, va = align(u)
            t.set_horizontalalignment(ha)
            t.set_verticalalignment(va)
        self.stale = False

    def _other_lines(self) -> list:
        """The axis' lines and arrows that are not the shapes', in pixels, each as a link."""
        out = []
        for line in self.axes.lines:
            if id(line) not in self.own and line.get_visible() and line.get_linestyle() not in ("None", " ", ""):
                xy = np.asarray(line.get_xydata(), float)
                if len(xy) > 1:
                    out.append((line.get_transform().transform(xy), 1.0))
        for t in self.axes.texts:
            arrow = getattr(t, "arrow_patch", None)
            if id(t) not in self.own and arrow is not None and t.xycoords == "data" and t.anncoords == "data":
                out.append((self.axes.transData.transform(np.array([t.xyann, t.xy], float)), 1.0))
        return out

    def _other_boxes(self, renderer) -> list:
        """The boxes (pixels) of the axis' texts that are not the shapes' names, and of its legend."""
        boxes = [
            t.get_window_extent(renderer)
            for t in self.axes.texts
            if id(t) not in self.own and t.get_visible() and t.get_text()
        ]
        legend = self.axes.get_legend()
        if legend is not None and legend.get_visible():
            boxes.append(legend.get_window_extent(renderer))
        return [(b.x0, b.y0, b.x1, b.y1) for b in boxes]


def draw_mechanism(ax, m: Mechanism, theta2: float, color="k", alpha=1.0):
    """Draw the declared bodies of m at crank angle theta2 (rad), its joints and the output's path, on an axis;
    the (x_min, x_max, y_min, y_max) of what was drawn."""
    shapes = drawing.at(drawing.scene(m), theta2)
    draw_shapes(ax, shapes, color, alpha)
    ax.margins(0.08)  # room for the joints' labels
    ax.set_aspect("equal")
    return drawing.bounds(shapes)


def _mechanism(m) -> Mechanism:
    if not isinstance(m, Mechanism):
        raise InvalidParameter(f"expected a qropt mechanism, got {type(m).__name__}")
    return m


def cycle_figure(m: Mechanism, theta2: float = math.radians(60), omega2: float = 1.0, alpha2: float = 0.0, n=721):
    """Figure: mechanism at theta2 (left); x, v, a over a turn (right) with working/return strokes shaded."""
    _mechanism(m)
    drawing.check(m)
    fig = plt.figure(figsize=(12, 5.5))
    ax0 = fig.add_subplot(1, 2, 1)
    draw_mechanism(ax0, m, theta2)
    ax0.set_title(f"{type(m).__name__} at theta2 = {math.degrees(theta2):.1f} deg")
    ax0.set_xlabel(f"x [{m.units}]")
    ax0.set_ylabel(f"y [{m.units}]")
    th = np.linspace(0, 2 * math.pi, n)
    mo = m.motion(th, omega2, alpha2)
    d = m.dead_centres()
    a, b = m.stroke_angles()
    follower = m.OUTPUT == "follower"
    unit = "rad" if follower else m.units
    names = ("theta4", "omega4", "alpha4") if follower else ("slider x", "slider v", "slider a")
    rows = [(names[0], mo.x, unit), (names[1], mo.v, f"{unit}/s"), (names[2], mo.a, f"{unit}/s^2")]
    deg = np.degrees(th)
    for k, (name, y, u) in enumerate(rows):
        ax = fig.add_subplot(3, 2, 2 * k + 2)
        ax.plot(deg, y, color="tab:blue")
        ax.set_ylabel(f"{name} [{u}]" if u else name)
        _shade(ax, d.theta_max, d.theta_min, a, b, omega2)
        ax.grid(alpha=0.3)
        if k == 0:
            ax.plot(np.degrees([d.theta_max, d.theta_min]), [d.x_max, d.x_min], "kv", ms=6, label="dead centres")
            ax.legend(loc="lower left", bbox_to_anchor=(0.0, 1.02), ncol=3, fontsize=8, frameon=False)
    ax.set_xlabel(f"theta2 [deg] (omega2 = {omega2:g} rad/s)")
    fig.suptitle(
        f"TR = {m.time_ratio():.4f}, {m.TRAVEL} = {m.stroke():.4g} {unit}, "
        f"gamma_min = {math.degrees(m.gamma_min().value):.2f} deg, omega2 = {omega2:g} rad/s"
    )
    fig.tight_layout()
    return fig


LOAD_COLOUR = "darkred"  # the applied loads' arrows and names; the joint forces take tab10's colours
SPOTS = (0.25, 0.5, 0.75)  # where a torque may be drawn between two joints of its body, from one to the other


class Drawn(NamedTuple):
    """One applied load at the figure's crank angle: its short name ("F1", "T1"), the load, the body it acts on,
    its point (the mechanism's unit; a torque's: on its body between two of its joints, clear of them and of the
    forces), the force (fx, fy) (N) or torque (N m) acting there, and whether its window is open (where it is
    shut, ``value`` is what it would be open)."""

    name: str
    load: object
    body: str
    point: tuple
    value: object
    on: bool


def applied_loads(m: Mechanism, theta2: float, omega2: float, masses=None, loads=None) -> list[Drawn]:
    """Every ``Force`` and ``Torque`` of ``loads`` at crank angle theta2 (rad) and omega2 (rad/s), as the exact
    dynamics apply them (``qropt.dynamics.inverse.loads_at``): forces F1, F2, ... and torques T1,
    T2, ... in the loads' order. A load whose window is shut there carries the value it would have open."""
    from qropt import units as units_
    from qropt.dynamics.inverse import linkage_of, loads_at
    from qropt.dynamics.model import Force

    if loads is None or not (loads.forces or loads.torques):
        return []
    t = np.array([float(theta2)])
    resolved, shown, working, x = loads_at(m, t, omega2, masses, loads)
    _, opened, _, _ = loads_at(m, t, omega2, masses, loads, opened=True)
    link = linkage_of(m)
    where = m.positions(t).points
    k = units_.to_metres(m.units)
    joints = {b.name: b.joints for b in link.bodies()}
    out, counts = [], {"F": 0, "T": 0}
    for (load, body), ap, open_ap in zip(resolved, shown, opened, strict=True):
        kind = "F" if isinstance(load, Force) else "T"
        counts[kind] += 1
        on = bool(load.window.active(t, working, x)[0])
        use = ap if on else open_ap
        if kind == "F":
            point = (float(use.point[0][0]) / k, float(use.point[1][0]) / k)
            value = np.array([float(np.ravel(use.force[0])[0]), float(np.ravel(use.force[1])[0])])
        else:
            xy = np.array([where[j][0] for j in joints[body]])
            # on the body between two of its joints, clear of its joints and of the forces' points
            spots = [xy[i] + f * (xy[j] - xy[i]) for i in range(len(xy)) for j in range(i, len(xy)) for f in SPOTS]
            busy = np.vstack([xy, *(np.array([o.point]) for o in out)])
            best = max(spots, key=lambda p: float(np.min(np.hypot(*(busy - p).T))))
            point = (float(best[0]), float(best[1]))
            value = float(np.ravel(use.torque)[0])
        out.append(Drawn(f"{kind}{counts[kind]}", load, body, point, value, on))
    return out


def _load_words(d: Drawn) -> str:
    """A drawn load for the legend: where, how and how much."""
    if isinstance(d.value, float):
        return f"{d.name} on the {d.body}: {d.value:.4g} N m" + ("" if d.on else " (off here)")
    how = d.load.direction if isinstance(d.load.direction, str) else "fixed direction"
    return f"{d.name} at {d.load.where}, {how}: {np.hypot(*d.value):.4g} N" + ("" if d.on else " (off here)")


def _load_label(ax, text: str, at, alpha: float):
    """A load's name beside the point ``at`` (data), where ``LoadLabels`` finds room when the figure is drawn."""
    return ax.annotate(
        text,
        at,
        textcoords="offset points",
        xytext=(4, 4),
        fontsize=8,
        color=LOAD_COLOUR,
        alpha=alpha,
        zorder=7,
        bbox={"fc": "white", "ec": "none", "pad": 0.5, "alpha": 0.8},
    )


def _draw_force(ax, d: Drawn, scale: float) -> tuple:
    """A force as an arrow from its point, to the joint forces' scale, named by its size beside its head; faded
    where its window is shut. (head (data), the name)."""
    at = np.asarray(d.point, float)
    head = at + scale * d.value
    alpha = 1.0 if d.on else 0.35
    ax.annotate(
        "",
        xy=head,
        xytext=at,
        arrowprops={"arrowstyle": "-|>", "color": LOAD_COLOUR, "lw": 2.4, "alpha": alpha, "shrinkA": 0, "shrinkB": 0},
        zorder=6,
    )
    text = f"{d.name} {float(np.hypot(*d.value)):.4g} N" + ("" if d.on else " (off)")
    return head, _load_label(ax, text, head, alpha)


def _draw_torque(ax, d: Drawn, radius: float) -> tuple:
    """A torque as a curved arrow (counter-clockwise for a positive one) around its point on its body, named by
    its size beside the arc's opening; faded where its window is shut. (the opening (data), the name)."""
    c = np.asarray(d.point, float)
    alpha = 1.0 if d.on else 0.35
    a = np.radians(np.linspace(40.0, 320.0, 60))
    arc = c + radius * np.column_stack([np.cos(a), np.sin(a)])
    ax.plot(arc[:, 0], arc[:, 1], color=LOAD_COLOUR, lw=2.0, alpha=alpha, zorder=6)
    head, before = (arc[-1], arc[-4]) if d.value >= 0 else (arc[0], arc[3])
    ax.annotate(
        "",
        xy=head,
        xytext=before,
        arrowprops={"arrowstyle": "-|>", "color": LOAD_COLOUR, "lw": 2.0, "alpha": alpha, "shrinkA": 0, "shrinkB": 0},
        zorder=6,
    )
    opening = c + (radius, 0.0)
    return opening, _load_label(ax, f"{d.name} {d.value:.4g} N m" + ("" if d.on else " (off)"), opening, alpha)


def _quiet_corner(ax, lines) -> tuple:
    """The corner of the axis (0 or 1 across, 0 or 1 up) whose box (a third across, a sixth up) the fewest points
    along ``lines`` (polylines, data) fall in; the upper left where they tie."""
    (xa, xb), (ya, yb) = ax.get_xlim(), ax.get_ylim()
    pts = [np.asarray(p, float).reshape(-1, 2) for p in lines]
    pts += [np.linspace(p[k], p[k + 1], 25) for p in pts for k in range(len(p) - 1)]
    xy = np.vstack(pts) if pts else np.zeros((0, 2))
    fx, fy = (xy[:, 0] - xa) / (xb - xa), (xy[:, 1] - ya) / (yb - ya)

    def crowd(c):
        across = fx <= 1 / 3 if c[0] == 0 else fx >= 2 / 3
        up = fy >= 5 / 6 if c[1] == 1 else fy <= 1 / 6
        return int(np.count_nonzero(across & up))

    return min([(0, 1), (1, 1), (0, 0), (1, 0)], key=crowd)


def _draw_gravity(ax, g: tuple, corner: tuple) -> None:
    """Gravity's direction as a small arrow "g" with its size in a corner of the drawing (``_quiet_corner``)."""
    from matplotlib.text import OffsetFrom

    size = math.hypot(*g)
    u = np.array(g) / size
    at = (0.06 if corner[0] == 0 else 0.94, 0.9 if corner[1] == 1 else 0.1)
    anchor = OffsetFrom(ax, at)
    ax.annotate(
        "",
        xy=tuple(14 * u),
        xycoords=anchor,
        xytext=tuple(-14 * u),
        textcoords=anchor,
        arrowprops={"arrowstyle": "-|>", "color": LOAD_COLOUR, "lw": 1.8},
        zorder=7,
    )
    ax.annotate(
        f"g {size:.3g} m/s^2",
        at,
        xycoords="axes fraction",
        textcoords="offset points",
        xytext=(20 if corner[0] == 0 else -20, 0),
        ha="left" if corner[0] == 0 else "right",
        va="center",
        fontsize=8,
        color=LOAD_COLOUR,
        zorder=7,
        bbox={"fc": "white", "ec": "none", "pad": 0.5, "alpha": 0.8},
    )


def _pin_friction_words(pf) -> str:
    r = f", pins r {pf.radius:g} m" if pf.radius is not None else ""
    at = f", at {', '.join(pf.joints)}" if pf.joints else ""
    return f"pin friction mu {pf.mu:g}{r}{at} (in the joint forces)"


def dynamics_figure(m: Mechanism, omega2: float, masses=None, loads=None, theta2: float = math.radians(60), n=721):
    """Figure: the mechanism at theta2 with the force each joint passes on (arrows to one scale, newtons), the
    applied forces (arrows to the same scale from their points, named F1, F2, ... with their size), the torques
    (curved arrows, T1, ...), gravity's direction ("g", in the emptiest corner) and, in the legend, what each load
    is (a load whose window is shut at theta2 faded, "off") (left); the crank torque and every joint force's
    magnitude over a turn (right), strokes shaded."""
    _mechanism(m)
    drawing.check(m)
    d = m.dynamics(np.array([theta2]), omega2, masses=masses, loads=loads)
    drawn = applied_loads(m, theta2, omega2, masses, loads)
    fig = plt.figure(figsize=(12, 6))
    ax0 = fig.add_subplot(1, 2, 1)
    x0, x1, y0, y1 = draw_mechanism(ax0, m, theta2, color="0.35")
    span = max(x1 - x0, y1 - y0)
    pos = m.positions(np.array([theta2])).points
    forces = {k: v[0] for k, v in d.joint_forces.items() if k in pos or k == "slide"}
    pushes = [dl for dl in drawn if not isinstance(dl.value, float)]
    biggest = max([float(np.hypot(*f)) for f in forces.values()] + [float(np.hypot(*p.value)) for p in pushes] + [0.0])
    scale = 0.25 * span / max(biggest, 1e-300)  # the largest force drawn a quarter of the drawing
    colours = plt.get_cmap("tab10")
    tips, names, anchors = [], [], []
    shapes = drawing.at(drawing.scene(m), theta2)
    lines = [s.points for s in shapes]  # what the drawing holds, for gravity's corner
    for i, (k, f) in enumerate(sorted(forces.items())):
        at = pos[m.output_joint()][0] if k == "slide" else pos[k][0]
        tips.append(at + scale * f)
        lines.append([at, at + scale * f])
        ax0.annotate(
            "",
            xy=at + scale * f,
            xytext=at,
            arrowprops={"arrowstyle": "-|>", "color": colours(i % 10), "lw": 1.8},
            zorder=6,
        )
        ax0.plot([], [], color=colours(i % 10), label=f"{k}: {np.hypot(*f):.4g} N")
    for dl in drawn:
        if isinstance(dl.value, float):
            r = 0.06 * span
            at, name = _draw_torque(ax0, dl, r)
            tips += [np.array(dl.point) + (-r, -r), np.array(dl.point) + (r, r)]
            lines.append([tips[-2], tips[-1]])
        else:
            at, name = _draw_force(ax0, dl, scale)
            tips.append(at)
            lines.append([dl.point, at])
        names.append(name)
        anchors.append(at)
        ax0.plot([], [], color=LOAD_COLOUR, lw=2.4, alpha=1.0 if dl.on else 0.35, label=_load_words(dl))
    if loads is not None and loads.pin_friction is not None and loads.pin_friction.active:
        ax0.plot([], [], color="none", label=_pin_friction_words(loads.pin_friction))
    tips = np.array(tips).reshape(-1, 2)
    pad = 0.05 * span
    ax0.set_xlim(min(x0, tips[:, 0].min(initial=x0)) - pad, max(x1, tips[:, 0].max(initial=x1)) + pad)
    ax0.set_ylim(min(y0, tips[:, 1].min(initial=y0)) - pad, max(y1, tips[:, 1].max(initial=y1)) + pad)
    g = (0.0, 0.0) if loads is None else loads.gravity_vector
    if g[0] or g[1]:
        _draw_gravity(ax0, g, _quiet_corner(ax0, lines))
    if names:  # the loads' names placed after the joints' (which keep clear of them as drawn first), clear of both
        placer = JointLabels(names, anchors, [0.0] * len(names), shapes)
        placer.set_zorder(5.95)
        ax0.add_artist(placer)
    below = offset_copy(ax0.transAxes, fig=fig, y=-36, units="points")  # under the tick labels and the x label
    ax0.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, 0.0), bbox_transform=below, ncol=2, framealpha=0.9)
    what = "joint forces on the driven body" + (" and the applied loads (dark red)" if drawn else "")
    ax0.set_title(
        f"{type(m).__name__} at theta2 = {math.degrees(theta2):.1f} deg, torque {d.torque[0]:.4g} N m\n"
        f"{what}, to one scale",
        fontsize=10,
    )
    ax0.set_xlabel(f"x [{m.units}]")
    ax0.set_ylabel(f"y [{m.units}]")
    th = np.linspace(0, 2 * math.pi, n)
    dc = m.dynamics(th, omega2, masses=masses, loads=loads)
    dead = m.dead_centres()
    a, b = m.stroke_angles()
    deg = np.degrees(th)
    ax1 = fig.add_subplot(2, 2, 2)
    ax1.plot(deg, dc.torque, color="k")
    ax1.axhline(float(np.mean(dc.torque[:-1])), color="k", ls=":", lw=1, label="mean")
    ax1.set_ylabel("crank torque [N m]")
    _shade(ax1, dead.theta_max, dead.theta_min, a, b, omega2)
    ax1.legend(loc="lower left", bbox_to_anchor=(0.0, 1.02), ncol=3, fontsize=8, frameon=False)
    ax1.grid(alpha=0.3)
    ax2 = fig.add_subplot(2, 2, 4)
    lines = [
        ax2.plot(deg, v, color=colours(i % 10), label=k)[0]
        for i, (k, v) in enumerate(sorted(dc.force_magnitudes().items()))
    ]
    ax2.set_ylabel("joint force [N]")
    ax2.set_xlabel(f"theta2 [deg] (omega2 = {omega2:g} rad/s)")
    _shade(ax2, dead.theta_max, dead.theta_min, a, b, omega2)
    ax2.legend(handles=lines, fontsize=7, ncol=4, loc="upper right", framealpha=0.9)
    ax2.grid(alpha=0.3)
    fig.tight_layout()
    fig.subplots_adjust(left=0.08)  # the drawing's y label clear of the edge
    return fig


def _shade(ax, t_max, t_min, a, b, omega2):
    # the crank arc t_max -> t_min (counter-clockwise) has length a and the other b; at constant |omega2| the
    # longer arc takes longer whichever way the crank turns, so it is the working stroke for either sign of omega2
    # (the sign only reverses which way the slider moves on it)
    spans = [(t_max, t_max + a), (t_min, t_min + b)]
    for k, (lo, hi) in enumerate(spans):
        working = (k == 0) == (a >= b)
        for shift in (-2 * math.pi, 0.0):
            label = ("working stroke" if working else "return stroke") if shift == 0.0 else None
            ax.axvspan(
                math.degrees(lo + shift),
                math.degrees(hi + shift),
                color="tab:green" if working else "tab:red",
                alpha=0.08,
                label=label,
            )
    ax.set_xlim(0, 360)


def save(fig, path, dpi: int = 110):
    """Write fig to path (the format by its extension, checked first) and close it."""
    try:
        picture_path(path)
        fig.savefig(path, dpi=dpi)
    except OSError as e:
        raise InvalidParameter(f"{path}: cannot write the picture: {e.strerror or e}") from None
    finally:
        plt.close(fig)


def reachable_figure(r, time_ratios=()):
    """TR against the free parameter over its feasible interval (the paper's Fig. 5, recomputed),
    with the TR extremes and, for each requested TR, its solutions and their count."""
    fig, ax = plt.subplots(figsize=(8, 5))
    ok = np.isfinite(r.tr)
    ax.plot(r.grid[ok], r.tr[ok], color="tab:blue", label="TR")
    for lo, hi in r.intervals:
        ax.axvspan(lo, hi, color="tab:green", alpha=0.07)
    tmin, xmin, tmax, xmax = r.time_ratio_range
    ax.plot([xmin, xmax], [tmin, tmax], "kv", ms=7, label=f"TR range {tmin:.4f}..{tmax:.4f}")
    for k, t in enumerate(time_ratios):
        xs = r.solutions(t)
        ax.axhline(t, color="tab:red", lw=0.8, ls="--")
        ax.plot(xs, [t] * len(xs), "o", color="tab:red")
        at, ha = (r.grid[0], "left") if k % 2 == 0 else (r.grid[-1], "right")
        ax.annotate(f"TR {t:g}: {len(xs)} solution(s)", (at, t), textcoords="offset points", xytext=(4, 4), ha=ha)
    ax.set_xlabel(f"{r.free} [{r.base.units}]")
    ax.set_ylabel("time ratio [-] (slow / fast)")
    ax.set_title(f"TR over the feasible {r.free} of {type(r.base).__name__} (shaded)")
    ax.grid(alpha=0.3)
    ax.legend(loc="upper center")
    fig.tight_layout()
    return fig


def family_figure(f, x=None, y=None, best=None, max_points=400):
    """A family in the plane of two free parameters, coloured by gamma_min, with folds, ends and the best."""
    free = list(f.problem.free)
    x = x or f.along
    y = y or next(k for k in free if k != x)
    fig, ax = plt.subplots(figsize=(8, 6))
    pts = f.points()
    step = max(1, len(pts) // max_points)
    for b in f.branches:
        ax.plot([p.params[x] for p in b], [p.params[y] for p in b], color="0.6", lw=1)
    shown = pts[::step]
    g = [math.degrees(p.quantities.get("gamma_min", float("nan"))) for p in shown]
    sc = ax.scatter([p.params[x] for p in shown], [p.params[y] for p in shown], c=g, cmap="viridis", s=12)
    fig.colorbar(sc, ax=ax, label="gamma_min [deg]")
    for k, fold in enumerate(f.folds):
        label = f"fold ({x} turns back): {x} = {fold[x]:.6g}" if k == 0 else None
        ax.plot(fold[x], fold[y], "rx", ms=10, mew=2, label=label)
    for k, e in enumerate(f.ends):
        ax.plot(e.params[x], e.params[y], "ks", ms=6)
        why = e.reason.split(":")[0].replace("singularity at a ", "").split(" (")[0]
        ax.annotate(
            f"end {k + 1}: {why}", (e.params[x], e.params[y]), textcoords="offset points", xytext=(6, -12), fontsize=8
        )
    if best is not None and best.success:
        g = math.degrees(best.objective) if best.objective is not None else float("nan")
        ax.plot(best.params[x], best.params[y], "*", color="tab:red", ms=16, label=f"best gamma_min {g:.2f} deg")
    ax.legend(loc="best", fontsize=8)  # matplotlib's least-overlap place
    ax.set_xlabel(f"{x} [{f.problem.units}]")  # free parameters are lengths and offsets
    ax.set_ylabel(f"{y} [{f.problem.units}]")
    n = sum(len(b) for b in f.branches)
    ax.set_title(f"{f.problem.mechanism.__name__} family ({n} points, {len(f.folds)} fold(s))")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    return fig


def family_mechanisms(f, count=4):
    """The mechanism drawn at ``count`` points spread along the family."""
    pts = f.points()
    picks = [pts[i] for i in np.linspace(0, len(pts) - 1, count).astype(int)]
    fig, axes = plt.subplots(1, count, figsize=(4 * count, 4))
    for ax, p in zip(np.atleast_1d(axes), picks, strict=True):
        try:
            draw_mechanism(ax, p.mechanism, 0.0)
        except Exception as e:  # noqa: BLE001 - a point that does not build is shown as such
            ax.text(0.5, 0.5, type(e).__name__, transform=ax.transAxes, ha="center")
        free = ", ".join(f"{k}={p.params[k]:.4g}" for k in f.problem.free)
        ax.set_title(free, fontsize=9)
    fig.tight_layout()
    return fig


def _criteria_text(c: dict, unit: str) -> str:
    return "\n".join(
        [
            f"gamma_min {math.degrees(c['gamma_min']):.1f} deg",
            f"footprint {c['footprint']:.3g} {unit}^2",
            f"peak accel {c['peak_accel']:.3g} {unit}/s^2",
            f"peak working v {c['peak_velocity']:.3g} {unit}/s",
        ]
    )


def comparison_figure(cmp):
    """The designs of a type comparison side by side at one scale, each with its criteria; with the fronts of
    every type in a last panel when they were computed."""
    rows = list(cmp.rows)
    extra = 1 if cmp.fronts else 0
    n = len(rows) + extra
    cols = min(n, 4)
    nrows = math.ceil(n / cols)
    fig, axes = plt.subplots(nrows, cols, figsize=(4.2 * cols, 4.6 * nrows), squeeze=False)
    axes = axes.ravel()
    boxes = {id(r): _extent(r.result.mechanism) for r in rows if r.success}
    span = max((max(x1 - x0, y1 - y0) for x0, x1, y0, y1 in boxes.values()), default=1.0) * 1.15
    for ax, r in zip(axes, rows, strict=False):
        if not r.success:
            ax.text(
                0.5,
                0.5,
                "no design:\n" + _wrap(r.reason, 40),
                transform=ax.transAxes,
                ha="center",
                va="center",
                fontsize=8,
            )
            ax.set_title(r.type)
            ax.set_axis_off()
            continue
        m = r.result.mechanism
        draw_mechanism(ax, m, _drawn_at(m))
        x0, x1, y0, y1 = boxes[id(r)]
        cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
        ax.set_xlim(cx - span / 2, cx + span / 2)
        ax.set_ylim(cy - span / 2, cy + span / 2)
        ax.set_title(r.type, fontsize=10)
        ax.text(
            0.02,
            0.02,
            _criteria_text(r.criteria, cmp.units),
            transform=ax.transAxes,
            fontsize=7.5,
            va="bottom",
            bbox={"facecolor": "white", "alpha": 0.8, "edgecolor": "0.8"},
        )
        ax.tick_params(labelsize=7)
        ax.set_xlabel(f"x [{cmp.units}]", fontsize=8)
        ax.set_ylabel(f"y [{cmp.units}]", fontsize=8)
    if cmp.fronts:
        ax = axes[len(rows)]
        drawn = {k: f for k, f in cmp.fronts.items() if not isinstance(f, str) and f.values}
        for k, front in drawn.items():
            va, vb = np.array(front.values).T
            ax.plot(*_front_xy(front, va, vb), "o-", ms=3, label=k)
        for k in cmp.fronts:
            if k not in drawn:
                ax.plot([], [], " ", label=f"{k}: no front")
        a, b = next(iter(drawn.values())).criteria if drawn else ("gamma_min", "peak_accel")
        ax.set_xlabel(_label(a, cmp.units))
        ax.set_ylabel(_label(b, cmp.units))
        ax.set_title("trade-off fronts")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    for ax in axes[n:]:
        ax.set_axis_off()
    fig.suptitle(
        f"TR {cmp.time_ratio:g}, stroke {cmp.stroke:g} {cmp.units}: best by {cmp.objective} first (one scale; "
        f"omega2 = {cmp.omega2:g} rad/s)"
    )
    fig.tight_layout()
    return fig


def _wrap(text, width):
    import textwrap

    return "\n".join(textwrap.wrap(text, width)[:8])


def _label(q, unit: str):
    from qropt.synthesis.criteria import units

    return f"{q} [{'deg' if q == 'gamma_min' else units(unit)[q]}]"


def _front_xy(front, va, vb):
    a, b = front.criteria
    x = np.degrees(va) if a == "gamma_min" else np.asarray(va)
    y = np.degrees(vb) if b == "gamma_min" else np.asarray(vb)
    return x, y


def front_figure(front, designs: int = 3):
    """The front in its two criteria (left) and the designs at ``designs`` points along it (right)."""
    fig = plt.figure(figsize=(5.5 + 3.2 * designs, 5))
    gs = fig.add_gridspec(1, 1 + designs, width_ratios=[1.7] + [1] * designs)
    ax = fig.add_subplot(gs[0])
    va, vb = np.array(front.values).T if front.values else (np.zeros(0), np.zeros(0))
    x, y = _front_xy(front, va, vb)
    ax.plot(x, y, "o-", color="tab:blue", ms=4, label=f"non-dominated ({len(front.points)} points)")
    picks = np.linspace(0, len(front.points) - 1, designs).round().astype(int) if front.points else []
    colors = plt.cm.viridis(np.linspace(0.0, 0.85, designs))
    for k, i in enumerate(picks):
        ax.plot(x[i], y[i], "s", color=colors[k], ms=9, mec="k")
        ax.annotate(f"{k + 1}", (x[i], y[i]), textcoords="offset points", xytext=(6, 6))
    ax.plot([], [], "x", color="tab:red", label=f"removed: {len(front.removed)} (dominated or none)")
    a, b = front.criteria
    ax.set_xlabel(_label(a, front.problem.units))
    ax.set_ylabel(_label(b, front.problem.units))
    ax.set_title(f"{front.problem.mechanism.__name__}: {front.objectives[0]} vs {front.objectives[1]}")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="best")
    boxes = [_extent(front.points[i].mechanism) for i in picks]
    span = max((max(x1 - x0, y1 - y0) for x0, x1, y0, y1 in boxes), default=1.0) * 1.15
    for k, i in enumerate(picks):
        axm = fig.add_subplot(gs[1 + k])
        m = front.points[i].mechanism
        draw_mechanism(axm, m, _drawn_at(m), color=colors[k])
        x0, x1, y0, y1 = boxes[k]
        cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
        axm.set_xlim(cx - span / 2, cx + span / 2)
        axm.set_ylim(cy - span / 2, cy + span / 2)
        axm.set_title(
            f"{k + 1}: {_short(a, va[i], front.problem.units)}, {_short(b, vb[i], front.problem.units)}", fontsize=9
        )
        axm.tick_params(labelsize=7)
        axm.set_xlabel(f"x [{front.problem.units}]", fontsize=8)
        axm.set_ylabel(f"y [{front.problem.units}]", fontsize=8)
    fig.tight_layout()
    return fig


def _short(q, v, unit: str):
    from qropt.synthesis.criteria import units

    return f"{q} {math.degrees(v):.1f} deg" if q == "gamma_min" else f"{q} {v:.3g} {units(unit).get(q, '')}".rstrip()


def _extent(m) -> tuple[float, float, float, float]:
    """(x_min, x_max, y_min, y_max) of every joint's path over a turn and of the drawing at ``_drawn_at``."""
    b = m.bounding_box()
    x0, x1, y0, y1 = drawing.bounds(drawing.at(drawing.scene(m), _drawn_at(m)))
    return min(b.x_min, x0), max(b.x_max, x1), min(b.y_min, y0), max(b.y_max, y1)


def _drawn_at(m) -> float:
    """A crank angle that shows a design's links apart: 30% into its working stroke (rad)."""
    start, length = m.working_arc()
    return start + 0.3 * length


def chart_figure(ch):
    """The chart's figure (matplotlib): one panel for the objective, one per free parameter, one for how each
    cell was solved; with a fixed parameter on y, the best y of each x is drawn as a dashed ridge."""
    names = ["objective", *ch.problem.free]
    xs, xlabel = ch.x.shown(ch.problem)
    note = ", ".join(
        [
            f"{k} = {v:g}"
            for k, v in ch.problem.fixed.items()
            if k != getattr(ch.y, "name", "") and k in ch.problem.mechanism.LENGTHS and k != ch.x.name
        ]
        + [
            f"{k} = {v:g}"
            for k, v in ch.problem.targets.items()
            if k not in (ch.x.name, getattr(ch.y, "name", "")) and k != "swing"
        ]
    )
    title = f"{ch.problem.name or ch.problem.mechanism.__name__}: {ch.problem.mechanism.KIND}" + (
        f", {note}" if note else ""
    )
    s = ch.stats
    how = (
        f"{s['cells']} cells: {s['continued']} continued, {s['full']} full solves ({s['needed']} needed), "
        f"{s['no_design']} without a design, {s['jumps'] + s['switched']} branch changes"
    )
    if ch.y is None:
        fig, axes = plt.subplots(len(names), 1, figsize=(7, 2.2 * len(names)), sharex=True, squeeze=False)
        for ax, name in zip(axes[:, 0], names, strict=True):
            z, label = ch.panel(name)
            ax.plot(xs, z[0], "o-", ms=3)
            ax.plot(xs[ch.mask("infeasible")[0]], np.zeros(ch.mask("infeasible").sum()), "x", color="0.5")
            ax.set_ylabel(label, fontsize=8)
            ax.grid(alpha=0.3)
        axes[-1, 0].set_xlabel(xlabel)
        fig.suptitle(f"{title}\n{how}", fontsize=9)
        fig.tight_layout()
        return fig
    ys, ylabel = ch.y.shown(ch.problem)
    n = len(names) + 1
    cols = 3 if n > 4 else 2
    rows = -(-n // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(5.2 * cols, 3.9 * rows), squeeze=False)
    bad, change = ch.mask("infeasible"), ch.mask("jump") | ch.mask("switched")
    gx, gy = np.meshgrid(xs, ys)
    ridge = None
    if ch.y.kind == "fixed":  # a design choice on y: its best value for each x
        z = ch.panel("objective")[0]
        sign = criteria.sense(ch.problem.objective)
        cols_ok = np.isfinite(z).any(axis=0)
        ridge = (xs[cols_ok], ys[np.nanargmax(sign * np.where(np.isfinite(z), z, -np.inf * sign), axis=0)][cols_ok])
    for ax, name in zip(axes.flat, names, strict=False):
        z, label = ch.panel(name)
        zm = np.ma.masked_invalid(z)
        if name == "objective":
            filled = ax.contourf(gx, gy, zm, levels=12, cmap="viridis")
            fig.colorbar(filled, ax=ax, shrink=0.9)
            lines = ax.contour(gx, gy, zm, levels=filled.levels[::2], colors="k", linewidths=0.6)
        else:
            lines = ax.contour(gx, gy, zm, levels=10, cmap="copper", linewidths=1.0)
        ax.clabel(lines, fontsize=7, fmt="%.3g")
        ax.set_title(label, fontsize=10)
    how_ax = axes.flat[len(names)]
    how_ax.set_title("how each cell was solved", fontsize=10)
    code = np.select([bad, ch.mask("needed"), ch.mask("full")], [3, 2, 1], 0)
    colours = matplotlib.colors.ListedColormap(["#dfe9f5", "#4c72b0", "#dd8452", "0.55"])
    how_ax.pcolormesh(gx, gy, code, cmap=colours, vmin=-0.5, vmax=3.5, shading="nearest")
    how_ax.set_xlim(xs.min(), xs.max())
    how_ax.set_ylim(ys.min(), ys.max())
    labels = ["continued", "full solve (tile start, check, closed form)", "full solve needed", "no design"]
    handles = [matplotlib.patches.Patch(color=colours(k), label=t) for k, t in enumerate(labels)]
    how_ax.legend(handles=handles, fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=2)
    for ax in axes.flat[:n]:
        ax.plot(gx[bad], gy[bad], "x", color="0.35", ms=4, mew=0.8, ls="none")
        ax.plot(gx[change], gy[change], "o", mfc="none", mec="red", ms=6, mew=1.0, ls="none")
        if ridge is not None:
            ax.plot(*ridge, "--", color="crimson", lw=1.2)
        ax.set_xlabel(xlabel, fontsize=8)
        ax.set_ylabel(ylabel, fontsize=8)
        ax.tick_params(labelsize=7)
    for ax in axes.flat[n:]:
        ax.set_visible(False)
    fig.suptitle(
        f"{title}\n{how}\nx: no design, red ring: branch change"
        + ("; dashed: best " + ch.y.name + " for each " + ch.x.name if ridge is not None else ""),
        fontsize=9,
    )
    fig.tight_layout()
    return fig


def polygon_figure(rm, units: str = "m"):
    """The velocity and acceleration polygons drawn to scale: each equation's terms head to tail from the pole o
    (a vector already drawn is not drawn again), the joint's exact vector dashed from o."""
    fig, axes = plt.subplots(1, 2, figsize=(12, 5.6))
    colours = {
        "absolute": "k",
        "relative": "tab:blue",
        "normal": "tab:green",
        "tangential": "tab:orange",
        "sliding": "tab:purple",
        "coriolis": "tab:red",
    }
    for ax, quantity, unit in ((axes[0], "velocity", f"{units}/s"), (axes[1], "acceleration", f"{units}/s^2")):
        drawn = set()
        eqs = [e for e in rm.equations if e.quantity == quantity]
        gap = 0.025 * max([float(np.hypot(*t.vector)) for e in eqs for t in e.terms] + [1e-300])
        segments: set = set()
        for e in eqs:
            head = np.zeros(2)
            for t in e.terms:
                tip = head + t.vector
                seg = tuple(np.round(np.r_[head, tip] / gap, 3))  # a vector drawn already (a known absolute term)
                if t.magnitude > 0 and seg not in segments:
                    segments.add(seg)
                    style = {"arrowstyle": "->", "color": colours[t.kind], "lw": 1.4}
                    ax.annotate("", xy=tip, xytext=head, arrowprops=style)
                    ax.plot([head[0], tip[0]], [head[1], tip[1]], alpha=0.0)  # (arrows do not set the limits)
                    normal = np.array([-t.vector[1], t.vector[0]]) / t.magnitude  # labels on the left of a term
                    mid = head + 0.5 * t.vector + gap * normal
                    ha = "right" if normal[0] < -0.3 else "left" if normal[0] > 0.3 else "center"
                    ax.text(*mid, t.name, fontsize=7, color=colours[t.kind], ha=ha, va="center")
                head = tip
            if e.joint not in drawn:  # the joint's exact vector from the pole, once
                ax.plot([0, e.exact[0]], [0, e.exact[1]], ls="--", color="0.5", lw=0.8)
                ax.text(*e.exact, f" {e.joint}", fontsize=8, color="0.3")
                drawn.add(e.joint)
        ax.plot(0, 0, "ko", ms=4)
        ax.text(0, 0, " o", fontsize=9)
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_xlabel(f"x [{unit}]")
        ax.set_ylabel(f"y [{unit}]")
        ax.set_title(f"{quantity} polygon")
        ax.grid(alpha=0.3)
    for kind, c in colours.items():
        axes[1].plot([], [], color=c, label=kind)
    axes[1].legend(fontsize=7, loc="best")
    title = f"theta2 = {math.degrees(rm.theta2):.1f} deg, omega2 = {rm.omega2:g} rad/s, alpha2 = {rm.alpha2:g} rad/s^2"
    fig.suptitle(title + "; dashed: each joint's exact vector from the pole o")
    fig.tight_layout()
    return fig


def servo_figure(profile):
    """A servo speed profile's figure: omega2, slider v and a (and the torque when given) against time, limits
    dashed, working stroke shaded."""
    s = profile.motion()
    rows = [
        ("crank omega2 [rad/s]", s.omega, ["omega_max"]),
        ("slider v [m/s]", s.v, ["v_max", "v_cut"]),
        ("slider a [m/s^2]", s.a, ["a_max"]),
    ]
    if profile.peak_torque is not None:
        rows.append(("motor torque [N m]", s.torque, ["torque_max"]))
    fig, axes = plt.subplots(len(rows), 1, figsize=(8, 2.2 * len(rows) + 0.6), sharex=True)
    tw = profile.working_time
    for ax, (label, y, names) in zip(axes, rows, strict=True):
        ax.plot(s.t, y, color="tab:blue", lw=1.5)
        ax.axvspan(0.0, tw, color="tab:orange", alpha=0.12, lw=0)
        for name in names:
            v = profile.limits.get(name)
            if v is not None:
                for i, sign in enumerate((1, -1) if name != "omega_max" else (1,)):
                    ax.axhline(
                        sign * v,
                        color="tab:red" if name != "v_cut" else "tab:green",
                        ls="--",
                        lw=1,
                        label=None if i else ("cutting speed" if name == "v_cut" else f"limit {name}"),
                    )
        if ax.get_legend_handles_labels()[0]:
            ax.legend(loc="best", fontsize=7, framealpha=0.9)
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel("time [s]")
    axes[0].set_title(
        f"{type(profile.mechanism).__name__} servo profile: cycle {profile.cycle_time:.4g} s, "
        f"time ratio {profile.time_ratio:.3f} (working stroke shaded)",
        fontsize=10,
    )
    fig.tight_layout()
    return fig
