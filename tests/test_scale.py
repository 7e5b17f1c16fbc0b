"""Results do not depend on the length scale: a problem in micrometres or kilometres is solved to the same
relative accuracy as in metres (the solver works at unit scale and scales its Result back)."""

from __future__ import annotations

import math

import pytest

import qropt
from qropt import Problem


def paper(s: float) -> Problem:
    """The paper's design task with every length times s."""
    return Problem(
        mechanism="DragLinkSlider",
        fixed={k: v * s for k, v in {"r1": 0.1, "r2": 0.225, "r4": 0.275, "r6": 0.3}.items()},
        free={"r3": (0.05 * s, 1.0 * s), "r5": (0.01 * s, 0.5 * s)},
        targets={"time_ratio": 1.5, "stroke": 0.3 * s},
        conditions={"grashof": "drag-link"},
        objective="max_gamma_min",
    )


@pytest.mark.parametrize("s", [1e-6, 1e-5, 1e-4, 1e3, 1e6])
def test_the_paper_task_at_any_scale(s):
    base, r = qropt.solve(paper(1.0)), qropt.solve(paper(s))
    assert r.status == "optimal" and r.objective == pytest.approx(base.objective, rel=1e-12)
    assert [o.params["r3"] / s for o in r.local_optima] == pytest.approx(
        [o.params["r3"] for o in base.local_optima], rel=1e-12
    )
    assert r.mechanism.params["r3"] == pytest.approx(base.params["r3"] * s, rel=1e-12)
    assert r.quantities["stroke"] == pytest.approx(0.3 * s, rel=1e-12)  # exact, in the problem's own lengths
    assert r.quantities["peak_accel"] == pytest.approx(base.quantities["peak_accel"] * s, rel=1e-9)


def test_an_infeasible_target_at_a_small_scale_keeps_its_ranges_in_the_problems_lengths():
    r = qropt.solve(paper(1e-5).replace(targets={"time_ratio": 9.0, "stroke": 0.3e-5}))
    assert r.status == "infeasible"
    assert r.reachable["time_ratio"] == pytest.approx((1.4298489, 3.5381161), rel=1e-6)
    lo, hi = r.reachable["stroke"]
    assert 0 < lo < 0.3e-5 < hi < 1e-5


def test_design_at_a_micrometre_stroke_matches_the_unit_one():
    small = {row.type: row for row in qropt.design(1.5, 3e-6, types=["drag-link-slider", "slider-crank"]).rows}
    large = {row.type: row for row in qropt.design(1.5, 1.0, types=["drag-link-slider", "slider-crank"]).rows}
    for kind in small:
        assert small[kind].result.status == "optimal", small[kind].result.message
        assert math.degrees(small[kind].criteria["gamma_min"]) == pytest.approx(
            math.degrees(large[kind].criteria["gamma_min"]), abs=1e-6
        )
