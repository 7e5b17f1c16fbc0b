"""Drag-link-driven slider: the paper's project mechanism (both r2 and r4 turn fully)."""

from __future__ import annotations

from qropt.mechanisms.four_bar import FourBarSlider


class DragLinkSlider(FourBarSlider):
    """Drag-link (r1 shortest, Grashof) driving C on O4->B at r5, rod r6 to D on y = h."""

    KIND = "drag-link-slider"
    CLASS = "drag-link"
    SHORTEST = "r1"
