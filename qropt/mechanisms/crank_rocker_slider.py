"""Crank-rocker-driven slider: a Grashof four-bar with the crank r2 shortest drives the slider."""

from __future__ import annotations

import dataclasses

from qropt.mechanisms import closed_forms
from qropt.mechanisms.four_bar import FourBarSlider


class CrankRockerSlider(FourBarSlider):
    """Crank-rocker (r2 shortest, Grashof) driving C on O4->B at r5, rod r6 to D on y = h."""

    KIND = "crank-rocker-slider"
    CLASS = "crank-rocker"
    SHORTEST = "r2"
    SYNTHESIS = dataclasses.replace(
        FourBarSlider.SYNTHESIS,
        closed_forms=(closed_forms.crank_rocker_slider_starts, closed_forms.four_bar_slider_starts),
    )
    EXAMPLE = {
        **{"r1": 1.1124, "r2": 0.3438, "r3": 0.7075, "r4": 1.2727, "r5": 0.8676, "r6": 0.9507, "h": 0.4627},
        **{"sigma": -1.0, "sigma_slider": 1.0},
    }
