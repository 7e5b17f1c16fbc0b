"""Closed forms: the paper's relations under their own names and the synthesis formulas that exist, and the warm
starts of a synthesis problem from the closed forms its type names (``Mechanism.SYNTHESIS.closed_forms``).

The relations, formulas and every shipped type's closed forms are defined in ``qropt.mechanisms.closed_forms`` (below
synthesis, so that each type can name its own) and re-exported here. They are independent of the general numerical
machinery: they serve as warm starts and as test oracles. Angles in radians, lengths in any consistent unit.
Equation numbers refer to Podhorodeski, Nokleby and Wittchen, "Quick-return mechanism design and analysis projects"
(2004).
"""

from __future__ import annotations

from qropt.mechanisms.closed_forms import (
    FAMILY_POINTS,
    WINDOW_STEPS,
    Context,
    CrankRockerDesign,
    DragLinkR3,
    RockerExtremes,
    SliderCrankCentres,
    SliderCrankDesign,
    Walk,
    WarmStarts,
    crank_rocker_design,
    crank_rocker_extremes,
    crank_rocker_r3,
    crank_rocker_slider_starts,
    crank_shaper_ratio,
    crank_shaper_starts,
    crank_shaper_stroke,
    crank_shaper_time_ratio,
    drag_link_discriminant,
    drag_link_r3,
    drag_link_slider_starts,
    drag_link_tr_range,
    four_bar_slider_starts,
    four_bar_starts,
    paper_dead_centre_angles,
    paper_time_ratio,
    paper_transmission_at_dead_centres,
    rocker_slider_r5,
    slider_crank_dead_centres,
    slider_crank_design,
    slider_crank_starts,
    slider_crank_window,
    slot_ram_shaper_gamma_min,
    slot_ram_shaper_starts,
    slot_ram_shaper_stroke,
    time_ratio_from_centres,
    tr_deviation,
    whitworth_ratio,
    whitworth_starts,
    whitworth_time_ratio,
)


def warm_starts(problem) -> WarmStarts:
    """Starts from every closed form that applies to a problem (other free parameters at mid-bounds): the type's
    own ``warm_starts`` hook where it has one, else the first of the closed forms the type names
    (``Mechanism.SYNTHESIS.closed_forms``, tried in order) that applies.

    Each start is verified later by the solver; a start that does not build is dropped there.
    """
    own = problem.mechanism.warm_starts(problem)
    if own is not None:
        return own
    c = Context(problem)
    for closed_form in problem.mechanism.SYNTHESIS.closed_forms:
        w = closed_form(c)
        if w is not None:
            return w
    return c.result("none", "")


__all__ = [
    "Context",
    "crank_rocker_design",
    "crank_rocker_extremes",
    "crank_rocker_r3",
    "crank_rocker_slider_starts",
    "crank_shaper_ratio",
    "crank_shaper_starts",
    "crank_shaper_stroke",
    "crank_shaper_time_ratio",
    "CrankRockerDesign",
    "drag_link_discriminant",
    "drag_link_r3",
    "drag_link_slider_starts",
    "drag_link_tr_range",
    "DragLinkR3",
    "FAMILY_POINTS",
    "four_bar_slider_starts",
    "four_bar_starts",
    "paper_dead_centre_angles",
    "paper_time_ratio",
    "paper_transmission_at_dead_centres",
    "rocker_slider_r5",
    "RockerExtremes",
    "slider_crank_dead_centres",
    "slider_crank_design",
    "slider_crank_starts",
    "slider_crank_window",
    "SliderCrankCentres",
    "SliderCrankDesign",
    "slot_ram_shaper_gamma_min",
    "slot_ram_shaper_starts",
    "slot_ram_shaper_stroke",
    "time_ratio_from_centres",
    "tr_deviation",
    "Walk",
    "warm_starts",
    "WarmStarts",
    "whitworth_ratio",
    "whitworth_starts",
    "whitworth_time_ratio",
    "WINDOW_STEPS",
]
