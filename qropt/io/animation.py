"""The mechanism over one crank turn as an animated GIF (matplotlib.animation with Pillow)."""

from __future__ import annotations

import math

import numpy as np

from qropt.errors import InvalidParameter
from qropt.io import drawing
from qropt.mechanisms import Mechanism
from qropt.validate import output_path

MAX_FPS = 100  # a GIF frame lasts a whole number of hundredths of a second


def animate(m: Mechanism, path, *, omega2: float = 1.0, frames: int = 72, fps: int = 24, progress: bool = False):
    """Write a GIF of m over one turn (``frames`` >= 72 crank angles, in the sense of omega2's sign, ``fps`` frames
    a second, 0 < fps <= 100): its declared bodies and joints, the slider's path and its ram green on the working
    (slow) stroke and red on the return, and the crank angle. progress: a tqdm bar on standard error (when it is a
    terminal). Every argument and the path are checked before anything is rendered."""
    if not isinstance(m, Mechanism):
        raise InvalidParameter(f"animate needs a qropt mechanism, got {type(m).__name__}")
    output_path(path, (".gif",), "animation")
    if isinstance(frames, bool) or not isinstance(frames, (int, np.integer)) or not 72 <= frames <= 3600:
        raise InvalidParameter(f"frames must be an integer from 72 to 3600, got {frames!r}")
    if isinstance(omega2, bool) or not isinstance(omega2, (int, float, np.integer, np.floating)):
        raise InvalidParameter(f"omega2 must be a nonzero finite number (rad/s), got {omega2!r}")
    if not (math.isfinite(omega2) and omega2 != 0):
        raise InvalidParameter(f"omega2 must be a nonzero finite number (rad/s), got {omega2!r}")
    if isinstance(fps, bool) or not isinstance(fps, (int, float, np.integer, np.floating)):
        raise InvalidParameter(f"fps (frames a second) must be a number in (0, {MAX_FPS}], got {fps!r}")
    if not (math.isfinite(fps) and 0 < fps <= MAX_FPS):
        raise InvalidParameter(f"fps (frames a second) must be a number in (0, {MAX_FPS}], got {fps!r}")
    sc = drawing.scene(m)  # the declared bodies, checked
    arc = m.working_arc(omega2) if sc.output is not None else None
    _render(m, sc, path, float(omega2), int(frames), float(fps), progress, arc)


def _render(m, sc, path, omega2, frames, fps, progress, arc):
    import sys

    import matplotlib.pyplot as plt
    from matplotlib.animation import FuncAnimation, PillowWriter
    from tqdm import tqdm

    from qropt.io.plots import draw_shapes

    sense = 1.0 if omega2 > 0 else -1.0
    theta = sense * np.linspace(0.0, 2 * math.pi, frames, endpoint=False)
    pos = m.positions(theta).points
    drawn = [
        [s for s in drawing.shapes(sc, {k: v[i] for k, v in pos.items()}) if s.part != "path"] for i in range(frames)
    ]
    x0, x1, y0, y1 = drawing.bounds([s for f in drawn for s in f] + drawing.at(sc, 0.0))
    pad = 0.05 * max(x1 - x0, y1 - y0)
    fig, ax = plt.subplots(figsize=(6, 4.3))
    ax.set_xlim(x0 - pad, x1 + pad)
    ax.set_ylim(y0 - pad, y1 + pad)
    ax.set_aspect("equal")
    ax.set_xlabel(f"x [{m.units}]")
    ax.set_ylabel(f"y [{m.units}]")
    ax.grid(alpha=0.3)
    working = None
    if arc is not None:
        working = ((theta - arc[0]) % (2 * math.pi)) <= arc[1]
        ax.plot(*sc.path.T, color="0.6", lw=3, alpha=0.5)
        ax.plot([], [], "s", color="tab:green", label="slider: working stroke")
        ax.plot([], [], "s", color="tab:red", label="slider: return stroke")
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=2, fontsize=8, frameon=False)
    label = ax.set_title(" ")
    fig.tight_layout()  # the legend below the axes, nothing over the mechanism
    artists = []

    def draw(i):
        for a in artists:
            a.remove()
        artists[:] = draw_shapes(ax, drawn[i], labels=False, joint_color="tab:blue")  # one artist a shape
        if working is not None:
            for a, s in zip(artists, drawn[i], strict=True):
                if s.part == "ram":
                    a.set_edgecolor("tab:green" if working[i] else "tab:red")
                    a.set_linewidth(2)
        angle = math.degrees(theta[i]) % 360
        label.set_text(f"{type(m).__name__}: theta2 = {angle:5.1f} deg, omega2 = {omega2:g} rad/s")
        return [*artists, label]

    anim = FuncAnimation(fig, draw, frames=frames, blit=False)
    try:
        with tqdm(total=frames, desc="frames", disable=not progress or not sys.stderr.isatty(), leave=False) as bar:
            anim.save(str(path), writer=PillowWriter(fps=fps), dpi=72, progress_callback=lambda i, n: bar.update())
    except OSError as e:
        raise InvalidParameter(f"{path}: cannot write the animation: {e.strerror or e}") from None
    finally:
        plt.close(fig)


__all__ = ["animate"]
