"""The mechanism over one crank turn as an animated GIF (matplotlib.animation with Pillow)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from qropt.errors import InvalidParameter
from qropt.io.export import link_segments
from qropt.mechanisms import FourBar, Mechanism


def animate(m: Mechanism, path, *, omega2: float = 1.0, frames: int = 72, fps: int = 24, progress: bool = False):
    """Write a GIF of m over one turn (``frames`` >= 72 crank angles, in the sense of omega2's sign): links and
    joints, the slider's path with the working (slow) stroke green and the return red, and the crank angle.
    progress: a tqdm bar on standard error (when it is a terminal)."""
    import matplotlib.pyplot as plt
    from matplotlib.animation import FuncAnimation, PillowWriter

    if Path(path).suffix.lower() != ".gif":
        raise InvalidParameter(f"{path}: the animation is a .gif file")
    if isinstance(frames, bool) or not isinstance(frames, int) or not 72 <= frames <= 3600:
        raise InvalidParameter(f"frames must be an integer from 72 to 3600, got {frames!r}")
    if not (isinstance(omega2, (int, float)) and math.isfinite(omega2) and omega2 != 0):
        raise InvalidParameter(f"omega2 must be a nonzero finite number (rad/s), got {omega2!r}")
    sense = 1.0 if omega2 > 0 else -1.0
    theta = sense * np.linspace(0.0, 2 * math.pi, frames, endpoint=False)
    pos = m.positions(theta).points
    box = m.bounding_box()
    span = max(box.x_max - box.x_min, box.y_max - box.y_min)
    pad = 0.08 * span
    fig, ax = plt.subplots(figsize=(6, 4.3))
    ax.set_xlim(box.x_min - pad, box.x_max + pad)
    ax.set_ylim(box.y_min - pad, box.y_max + pad)
    ax.set_aspect("equal")
    ax.set_xlabel("x [length]")
    ax.set_ylabel("y [length]")
    ax.grid(alpha=0.3)
    out = None
    if not isinstance(m, FourBar):
        out = "D" if "D" in pos else "C"
        start, length = m.working_arc(omega2)
        working = ((theta - start) % (2 * math.pi)) <= length
        ax.plot(*m.positions(np.linspace(0.0, 2 * math.pi, 721)).points[out].T, color="0.6", lw=3, alpha=0.5)
        ax.plot([], [], "s", color="tab:green", label="slider: working stroke")
        ax.plot([], [], "s", color="tab:red", label="slider: return stroke")
        ax.legend(loc="upper right", fontsize=8)
        slider = ax.plot([], [], "s", ms=11, mfc="white", mew=2)[0]
    lines = [ax.plot([], [], color="k", lw=2)[0] for _ in range(6)]
    joints = ax.plot([], [], "o", color="tab:blue", ms=5)[0]
    label = ax.set_title("")

    def draw(i):
        p = {k: v[i] for k, v in pos.items()}
        segs = link_segments(p)  # a slotted lever's drawn length follows its block
        for k, line in enumerate(lines):
            line.set_data(*([[p[segs[k][0]][0], p[segs[k][1]][0]], [p[segs[k][0]][1], p[segs[k][1]][1]]]
                            if k < len(segs) else [[], []]))  # fmt: skip
        joints.set_data([q[0] for q in p.values()], [q[1] for q in p.values()])
        angle = math.degrees(theta[i]) % 360
        label.set_text(f"{type(m).__name__}: theta2 = {angle:5.1f} deg, omega2 = {omega2:g} rad/s")
        if out is None:
            return [*lines, joints, label]
        slider.set_data([p[out][0]], [p[out][1]])
        slider.set_mec("tab:green" if working[i] else "tab:red")
        return [*lines, joints, label, slider]

    anim = FuncAnimation(fig, draw, frames=frames, blit=False)
    import sys

    from tqdm import tqdm

    with tqdm(total=frames, desc="frames", disable=not progress or not sys.stderr.isatty(), leave=False) as bar:
        anim.save(str(path), writer=PillowWriter(fps=fps), dpi=72, progress_callback=lambda i, n: bar.update())
    plt.close(fig)


__all__ = ["animate"]
