"""The model objects' pictures and notebook views, attached to their classes here: ``plot(path)`` (PNG, PDF or
SVG by the path's suffix, checked before anything is drawn) and ``_repr_html_()`` (what a notebook shows). The
layers that hold the data (mechanisms, synthesis, studies, convex) import nothing of io; ``import qropt``
imports this module, so every object has its views. matplotlib is imported on the first picture, not here."""

from __future__ import annotations

import math

import numpy as np

from qropt import validate
from qropt.convex.servo import SpeedProfile
from qropt.errors import ChartError
from qropt.io import notebook
from qropt.mechanisms import Mechanism
from qropt.mechanisms.relative_motion import RelativeMotion
from qropt.studies import Chart, Comparison, Family, Front
from qropt.synthesis.result import Result
from qropt.validate import picture_path


def _plot_mechanism(self, path, theta2: float = math.radians(60), omega2: float = 1.0) -> None:
    """The mechanism drawn at theta2 (rad), joints named, beside its output's position, velocity and acceleration
    over a turn at omega2 (rad/s), the working stroke shaded (``qropt.io.plots.cycle_figure``)."""
    from qropt.io import plots

    picture_path(path)
    theta2 = validate.number("theta2", theta2)
    omega2 = validate.number("omega2", omega2)
    plots.save(plots.cycle_figure(self, theta2, omega2), path)


def _plot_relative_motion(self, path, units: str = "m") -> None:
    """The velocity and acceleration polygons drawn to scale (``qropt.io.plots.polygon_figure``)."""
    from qropt.io import plots

    picture_path(path)
    plots.save(plots.polygon_figure(self, units), path)


def _plot_chart(self, path, dpi: int = 90) -> None:
    """Contour charts of the objective and the optimal free parameters beside how each cell was solved; cells
    without a design are crossed, branch changes ringed (``qropt.io.plots.chart_figure``)."""
    picture_path(path)
    if isinstance(dpi, bool) or not isinstance(dpi, (int, float, np.integer, np.floating)) or not 10 <= dpi <= 1200:
        raise ChartError(f"dpi must be a number from 10 to 1200, got {dpi!r}")
    from qropt.io import plots

    fig = plots.chart_figure(self)
    try:
        fig.savefig(path, dpi=dpi)
    except OSError as e:
        raise ChartError(f"cannot write the chart picture {path}: {e.strerror or e}") from None
    finally:
        plots.plt.close(fig)


def _plot_comparison(self, path) -> None:
    """The designs side by side at one scale, each with its numbers (and the fronts, if computed)."""
    from qropt.io import plots

    picture_path(path)
    plots.save(plots.comparison_figure(self), path)


def _plot_front(self, path) -> None:
    """The front in the two criteria, with the designs drawn at a few points."""
    from qropt.io import plots

    picture_path(path)
    plots.save(plots.front_figure(self), path)


def _plot_speed_profile(self, path) -> None:
    """omega2, slider v and a (and the torque when given) against time, limits dashed, working stroke shaded.

    path: a file ending .png, .pdf or .svg in an existing directory (InvalidParameter otherwise)."""
    from qropt.io import plots

    picture_path(path)
    plots.save(plots.servo_figure(self), path)


PLOTS = {
    Mechanism: _plot_mechanism,
    RelativeMotion: _plot_relative_motion,
    Chart: _plot_chart,
    Comparison: _plot_comparison,
    Front: _plot_front,
    SpeedProfile: _plot_speed_profile,
}
NOTEBOOK = {
    Mechanism: notebook.mechanism_html,
    Result: notebook.result_html,
    Comparison: notebook.comparison_html,
    Front: notebook.front_html,
    Family: notebook.family_html,
    Chart: notebook.chart_html,
}


for _cls, _f in PLOTS.items():
    _cls.plot = _f
for _cls, _f in NOTEBOOK.items():
    _cls._repr_html_ = _f

__all__ = ["PLOTS", "NOTEBOOK"]
