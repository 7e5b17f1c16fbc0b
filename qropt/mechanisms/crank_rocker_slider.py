"""Crank-rocker-driven slider: a Grashof four-bar with the crank r2 shortest drives the slider."""

from __future__ import annotations

from qropt.mechanisms.four_bar import FourBarSlider


class CrankRockerSlider(FourBarSlider):
    """Crank-rocker (r2 shortest, Grashof) driving C on O4->B at r5, rod r6 to D on y = h."""

    KIND = "crank-rocker-slider"
    CLASS = "crank-rocker"
    SHORTEST = "r2"
