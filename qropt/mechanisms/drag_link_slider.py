"""Drag-link-driven slider: the paper's project mechanism (both r2 and r4 turn fully)."""

from __future__ import annotations

import dataclasses

from qropt.mechanisms import closed_forms
from qropt.mechanisms.four_bar import FourBarSlider


class DragLinkSlider(FourBarSlider):
    """Drag-link (r1 shortest, Grashof) driving C on O4->B at r5, rod r6 to D on y = h."""

    KIND = "drag-link-slider"
    CLASS = "drag-link"
    SHORTEST = "r1"
    SYNTHESIS = dataclasses.replace(
        FourBarSlider.SYNTHESIS,
        closed_forms=(closed_forms.drag_link_slider_starts, closed_forms.four_bar_slider_starts),
    )
    # the paper's design: TR 1.5, stroke 0.3 m, r3 from eqs. (7)-(13) (the root with the larger gamma_min)
    EXAMPLE = {
        **{"r1": 0.1, "r2": 0.225, "r3": closed_forms.drag_link_r3(1.5, 0.1, 0.225, 0.275)[-1].r3, "r4": 0.275},
        **{"r5": 0.15, "r6": 0.3, "h": 0.0, "sigma": -1.0, "sigma_slider": 1.0},
    }
