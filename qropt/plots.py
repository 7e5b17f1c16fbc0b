"""Pictures: a mechanism drawn at one crank angle beside its output over the cycle."""

from __future__ import annotations

import math

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from qropt.mechanisms import FourBar, Mechanism  # noqa: E402


def _segments(pts):
    segs = [("O2", "A")]
    if "B" in pts:
        segs += [("A", "B"), ("O4", "B"), ("O4", "C")]
    elif "O4" in pts:
        segs += [("O4", "C")]  # the slotted lever, through the block at A
    segs += [("C", "D")] if "D" in pts else [("A", "C")] if "O4" not in pts else []
    return [(a, b) for a, b in segs if a in pts and b in pts]


def draw_mechanism(ax, m: Mechanism, theta2: float, color="k", alpha=1.0):
    """Draw the links and joints of m at crank angle theta2 (rad), with the slider path, on an axis."""
    pts = {k: v[0] for k, v in m.positions(np.array([theta2])).points.items()}
    for a, b in _segments(pts):
        ax.plot(*zip(pts[a], pts[b], strict=True), color=color, lw=2, alpha=alpha)
    for k, (x, y) in pts.items():
        ground = k in ("O2", "O4")
        ax.plot(x, y, "s" if ground else "o", color=color, ms=7 if ground else 5, alpha=alpha)
        ax.annotate(k, (x, y), textcoords="offset points", xytext=(4, 4), fontsize=8, alpha=alpha)
    if not isinstance(m, FourBar):
        slider = "D" if "D" in pts else "C"
        path = m.positions(np.linspace(0, 2 * math.pi, 361))
        ax.plot(path.points[slider][:, 0], path.points[slider][:, 1], color="tab:blue", lw=3, alpha=0.4)
    ax.set_aspect("equal")


def cycle_figure(m: Mechanism, theta2: float = math.radians(60), omega2: float = 1.0, alpha2: float = 0.0, n=721):
    """Figure: mechanism at theta2 (left); x, v, a over a turn (right) with working/return strokes shaded."""
    fig = plt.figure(figsize=(12, 5.5))
    ax0 = fig.add_subplot(1, 2, 1)
    draw_mechanism(ax0, m, theta2)
    ax0.set_title(f"{type(m).__name__} at theta2 = {math.degrees(theta2):.1f} deg")
    th = np.linspace(0, 2 * math.pi, n)
    mo = m.motion(th, omega2, alpha2)
    d = m.dead_centres()
    a, b = m.stroke_angles()
    unit = "rad" if isinstance(m, FourBar) else ""
    rows = [("x", mo.x, unit), ("v", mo.v, "/s"), ("a", mo.a, "/s^2")]
    deg = np.degrees(th)
    for k, (name, y, u) in enumerate(rows):
        ax = fig.add_subplot(3, 2, 2 * k + 2)
        ax.plot(deg, y, color="tab:blue")
        ax.set_ylabel(f"{name} [{u}]" if u else name)
        _shade(ax, d.theta_max, d.theta_min, a, b, omega2)
        ax.grid(alpha=0.3)
        if k == 0:
            ax.plot(np.degrees([d.theta_max, d.theta_min]), [d.x_max, d.x_min], "kv", ms=6, label="dead centres")
            ax.legend(loc="upper right", fontsize=8)
    ax.set_xlabel("theta2 [deg]")
    fig.suptitle(
        f"TR = {m.time_ratio():.4f}, stroke = {m.stroke():.4g}, gamma_min = {math.degrees(m.gamma_min().value):.2f} deg"
    )
    fig.tight_layout()
    return fig


def _shade(ax, t_max, t_min, a, b, omega2):
    # with omega2 > 0 the crank runs t_max -> t_min (counter-clockwise) in a, else in b
    slow_from_max = (a > b) == (omega2 > 0)
    spans = [(t_max, t_max + a), (t_min, t_min + b)]
    for k, (lo, hi) in enumerate(spans):
        working = (k == 0) == slow_from_max
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


def save(fig, path):
    fig.savefig(path, dpi=110)
    plt.close(fig)
