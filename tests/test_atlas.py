"""The atlas (``qropt.synthesis.atlas``): its key is the problem's shape, its designs are certified designs of their
nodes' problems, and a solve that starts from them is as good as the multi-start it replaces."""

from __future__ import annotations

import json

import numpy as np
import pytest

from benchmarks.tasks import LOADS, MASSES, OMEGA2
from qropt import Solver
from qropt.studies._design import TYPES, type_problem
from qropt.synthesis import atlas, criteria, starts
from qropt.synthesis.certificate import Designs
from qropt.synthesis.result import SOLUTION_PRESENT
from qropt.synthesis.search import results
from tests import brute

DATA = json.loads(atlas.PATH.read_text())
# the search's reference for the coupler slider's least peak torque at TR 2.479, 0.2952 m in its first run with
# evolutions (results/search_torque_evolve.json of 2026-11-28 before the multi-start counted per two parameters)
FIRST_REFERENCE = 103.14587537194157


def test_the_key_is_the_shape_of_the_problem():
    key = atlas.signature(type_problem("coupler-slider", 1.7, 0.3))
    assert key is not None
    # the stroke, omega2, the unit and the TR do not change the shape
    assert atlas.signature(type_problem("coupler-slider", 1.7, 3e-3, omega2=7.0)) == key
    assert atlas.signature(type_problem("coupler-slider", 2.4, 300.0, units="mm")) == key
    # the objective, the bounds and the conditions do
    assert atlas.signature(type_problem("coupler-slider", 1.7, 0.3, objective="min_peak_accel")) != key
    assert atlas.signature(type_problem("coupler-slider", 1.7, 0.3, bounds={"r1": (0.1, 1.0)})) != key
    assert atlas.signature(type_problem("coupler-slider", 1.7, 0.3, conditions={"gamma_min": 0.5})) != key
    # optima that do not scale with the stroke have no key
    assert atlas.signature(type_problem("coupler-slider", 1.7, 0.3, conditions={"max_sum": 2.0})) is None
    assert atlas.signature(type_problem("coupler-slider", 1.7, 0.3, objective=None)) is None


def test_the_file_holds_every_row_as_design_builds_it():
    """Each entry's key is that of its row's problem today (a changed row must rebuild the atlas)."""
    rows = {(e["row"], e["objective"]): e for e in DATA["entries"]}
    assert set(rows) == {(k, o) for k in TYPES for o in ("max_gamma_min", "min_peak_accel")}
    for (kind, objective), e in rows.items():
        assert e["signature"] == atlas.signature(type_problem(kind, 2.0, 1.0, objective=objective))
        assert e["nodes"] == sorted(e["nodes"]) and len(e["designs"]) == len(e["nodes"])
        # most nodes hold designs (a solve between two nodes without any runs the multi-start)
        assert sum(map(bool, e["designs"])) >= len(e["nodes"]) // 2, kind


@pytest.mark.parametrize("objective", ["max_gamma_min", "min_peak_accel"])
def test_every_design_of_the_atlas_meets_its_node_exactly(objective):
    """Rebuilt at stroke 1, each design meets its node's TR and stroke to 1e-8, keeps its row's rules and bounds,
    and has the objective the atlas records; TR, stroke and gamma_min checked by the tests' own simulation too."""
    for e in (e for e in DATA["entries"] if e["objective"] == objective):
        for tr, designs in zip(e["nodes"], e["designs"], strict=True):
            p = type_problem(e["row"], tr, 1.0, objective=objective)
            for d in designs:
                assert all(lo - 1e-12 <= d["params"][k] <= hi + 1e-12 for k, (lo, hi) in p.free.items())
                m = p.build(d["params"], d["branch"])
                assert m.time_ratio() == pytest.approx(tr, abs=1e-8)
                assert m.stroke() == pytest.approx(1.0, abs=1e-8)
                assert not any(v > 1e-8 for v in criteria.violations(p, m).values())
                assert criteria.objective_of(p, m) == pytest.approx(d["value"], rel=1e-9)
        if objective == "max_gamma_min":  # the tests' own simulation, at every fifth node
            for tr, designs in list(zip(e["nodes"], e["designs"], strict=True))[::5]:
                if designs:
                    m = type_problem(e["row"], tr, 1.0).build(designs[0]["params"], designs[0]["branch"])
                    b_tr, b_stroke, b_gamma = brute.task_values(TYPES[e["row"]][0], dict(m.params))
                    assert (b_tr, b_stroke) == pytest.approx((tr, 1.0), abs=1e-8), e["row"]
                    assert b_gamma == pytest.approx(designs[0]["value"], abs=1e-7), e["row"]


def test_a_solve_between_nodes_starts_from_the_atlas_and_is_as_good_as_the_multi_start():
    """The coupler slider (no closed form) at a TR between nodes and a stroke the atlas was not built at: from
    the atlas in a few runs, and no worse than the default multi-start without it."""
    p = type_problem("coupler-slider", 1.83, 0.42)
    with_atlas, without = Solver().solve(p), Solver(atlas=False).solve(p)
    assert with_atlas.status == "optimal", with_atlas.message
    assert "atlas" in with_atlas.certificate.global_claim
    assert with_atlas.stats["atlas_starts"] >= 2
    assert with_atlas.stats["ipopt_runs"] < without.stats["ipopt_runs"] / 2
    assert without.status in SOLUTION_PRESENT
    assert with_atlas.objective >= without.objective - 1e-9
    m = with_atlas.mechanism
    assert (m.time_ratio(), m.stroke()) == pytest.approx((1.83, 0.42), abs=1e-8)


def test_a_bounded_problem_starts_from_the_atlas_optima_without_its_bound():
    """The coupler slider by the peak acceleration under a transmission bound, which the atlas does not hold: its
    starts are the atlas's optima without the bound. Under 10 deg the unbounded optimum (23.55 deg) meets the bound,
    so it is the bounded one's (the bound cannot make it better), without the multi-start; under 60 deg the
    atlas's designs fall short of their nodes and the multi-start runs as well."""
    p = type_problem("coupler-slider", 1.83, 0.42, objective="min_peak_accel", conditions={"gamma_min": 0.1745})
    found = atlas.starts(p)
    assert found.unbounded == ("gamma_min",) and found.designs
    assert found.designs == atlas.starts(p.replace(conditions={})).designs
    r = Solver().solve(p)
    assert r.status == "optimal", r.message
    assert "by min_peak_accel without its bound gamma_min" in r.certificate.global_claim
    assert "Sobol multi-start" not in r.stats["strategies"]
    assert r.mechanism.gamma_min().value >= 0.1745 - 1e-9
    assert r.objective == pytest.approx(Solver().solve(p.replace(conditions={})).objective, rel=1e-9)
    steep = Solver(starts_n=1).solve(p.replace(conditions={"gamma_min": 1.0472}))
    assert steep.status == "optimal" and "Sobol multi-start" in steep.stats["strategies"], steep.message
    assert steep.mechanism.gamma_min().value >= 1.0472 - 1e-9
    assert "without its bound" not in steep.certificate.global_claim


def test_problems_outside_the_atlas_run_the_multi_start():
    for p in (
        type_problem("coupler-slider", 1.83, 0.42, bounds={"r1": (0.05, 1.0)}),  # its own bounds
        type_problem("coupler-slider", 3.9, 0.42),  # beyond the nodes
    ):
        assert not atlas.starts(p).designs
    assert atlas.starts(type_problem("coupler-slider", 1.83, 0.42)).designs


def test_a_start_is_scaled_to_the_stroke_and_clipped_to_the_bounds():
    p = type_problem("drag-link-slider", 2.0, 0.25)
    found = atlas.starts(p)
    e = next(e for e in DATA["entries"] if e["signature"] == atlas.signature(p))
    i = e["nodes"].index(min(e["nodes"], key=lambda t: abs(t - 2.0) if t <= 2.0 else 9))
    v0, _ = found.designs[0]
    assert v0 == pytest.approx({k: x * 0.25 for k, x in e["designs"][i][0]["params"].items()}, rel=1e-12)
    assert all(lo <= v[k] <= hi for v, _ in found.designs for k, (lo, hi) in p.free.items())
    assert np.isfinite([x for v, _ in found.designs for x in v.values()]).all()


def test_a_dynamic_objective_starts_from_the_atlas_designs_of_its_shape_by_the_kinematic_objectives():
    """The peak torque's optima do not scale with the stroke (no key), but its problem shares mechanism, bounds and
    branches with the atlas's entries by max_gamma_min and min_peak_accel: ``related`` gives their designs at the
    nodes around the TR, scaled to the stroke, as ``starts`` gives each objective's problem its own."""
    kw = {"masses": MASSES, "loads": LOADS, "omega2": OMEGA2}
    p = type_problem("coupler-slider", 2.479, 0.2952, objective="min_peak_torque", **kw)
    assert atlas.signature(p) is None and not atlas.starts(p).designs
    found = atlas.related(p)
    own = [
        atlas.starts(type_problem("coupler-slider", 2.479, 0.2952, objective=o))
        for o in ("max_gamma_min", "min_peak_accel")
    ]
    assert [d for s in own for d in s.designs] == list(found.designs) and len(found.designs) == 8
    assert found.trs == (2.45, 2.55) and "by max_gamma_min and min_peak_accel" in found.how
    assert all(lo <= v[k] <= hi for v, _ in found.designs for k, (lo, hi) in p.free.items())
    # its own bounds, a TR beyond the nodes, a kinematic objective (its own starts) or no objective: none
    for q in (
        type_problem("coupler-slider", 2.479, 0.2952, objective="min_peak_torque", bounds={"r1": (0.05, 1.0)}, **kw),
        type_problem("coupler-slider", 3.9, 0.2952, objective="min_peak_torque", **kw),
        type_problem("coupler-slider", 2.479, 0.2952),
        type_problem("coupler-slider", 2.479, 0.2952, objective=None),
    ):
        assert not atlas.related(q).designs
    assert not starts.plan(p, True, False).related.designs  # Solver(atlas=False)
    assert starts.plan(p, True, True).related.designs == found.designs


def test_the_atlas_designs_of_its_shape_reach_the_peak_torque_that_the_multi_start_missed():
    """The coupler slider's least peak torque at TR 2.479, 0.2952 m (a task of ``benchmarks.search``): 36
    space-filling starts reached 115.43 N m at best; from the 8 designs of the atlas by the kinematic objectives,
    the default barrier reaches 103.146 N m, the independent search's reference in its first run with evolutions
    (10^6 shapes, 32 starts, two evolutions; its later runs' multi-starts found 102.8895, another shape, and a
    solve from seed 3 96.690, docs/benchmarks.md). Its TR and stroke by brute force, its peak against a dense
    Newton-Euler grid."""
    p = type_problem(
        "coupler-slider", 2.479, 0.2952, objective="min_peak_torque", masses=MASSES, loads=LOADS, omega2=OMEGA2
    )
    solver = Solver()
    plan = starts.plan(p, True, solver.atlas)
    runs = [("related", v, b) for v, b in plan.related.designs]
    found = solver.multistart.run(p, runs, p.targets, solver.max_rounds, Designs(), False)
    r = results.best(solver, p, found, "", plan, 0.0)
    assert r.status == "optimal", r.message
    assert "from 8 starts (8 the atlas's optima of this shape by kinematic objectives)" in r.certificate.global_claim
    assert r.objective <= FIRST_REFERENCE * (1 + 1e-9)
    b_tr, b_stroke, _ = brute.task_values("coupler-slider", dict(r.mechanism.params))
    assert b_tr == pytest.approx(2.479, rel=1e-9) and b_stroke == pytest.approx(0.2952, rel=1e-9)
    grid = np.abs(r.mechanism.dynamics(np.linspace(0, 2 * np.pi, 40_001), OMEGA2, masses=MASSES, loads=LOADS).torque)
    assert grid.max() <= r.objective * (1 + 1e-12) and grid.max() == pytest.approx(r.objective, rel=1e-6)


# a coupler slider at TR 2.65 (stroke 1), the least peak acceleration found there: a valid start for max_gamma_min
START_265 = {
    "r1": 0.6648245579796193,
    "r2": 0.15671227005783603,
    "r3": 3.831640947533235,
    "r4": 3.858296582703623,
    "r5": 4.999999999889551,
    "r6": 4.337804459608482,
    "h": 4.999999999379198,
    "beta": -1.0746614020625493,
}


def test_a_solve_keeps_one_reversal_a_turn():
    """From a valid design far from any optimum (gamma_min 0.13 rad), max_gamma_min once ended at a design whose
    output reverses twice a turn (its dead centres local extremes): no design at all. The NLP keeps each stroke's
    velocity of one sign at the turn-backs the certifier sees, and the solve ends at a design the tests' own
    simulation confirms."""
    p = type_problem("coupler-slider", 2.65, 1.0)
    branch = {"sigma": -1.0, "sigma_slider": 1.0}
    start = p.build(START_265, branch)
    assert start.dead_centres().reversals == 1 and start.time_ratio() == pytest.approx(2.65, abs=1e-8)
    r = Solver(atlas=False).solve(p, starts_n=0, use_analytic=False, extra_starts=[START_265])
    assert r.status == "optimal", r.message
    m = r.mechanism
    assert m.dead_centres().reversals == 1
    assert m.gamma_min().value > start.gamma_min().value + 0.3  # 0.13 rad at the start
    b_tr, b_stroke, b_gamma = brute.task_values("coupler-slider", dict(m.params))
    assert (b_tr, b_stroke) == pytest.approx((2.65, 1.0), abs=1e-8)
    assert b_gamma == pytest.approx(m.gamma_min().value, abs=1e-7)


def test_the_certifier_names_where_the_output_turns_back():
    """A design whose output reverses twice a turn: ``wrong_way`` names, per stroke, a point where the velocity
    has the wrong sign (checked by the exact motion there)."""
    from qropt.mechanisms import CouplerSlider
    from qropt.synthesis.certificate import TWO_PI, wrong_way

    m = CouplerSlider(
        r1=3.9767748182558744, r2=0.642575026063248, r3=4.314873925498792, r4=1.2206065015834444,
        r5=4.999999999910129, r6=4.999999999760366, h=1.2320049288704513, beta=-0.8426513658110741,
        sigma=-1.0, sigma_slider=1.0,
    )  # fmt: skip
    d = m.dead_centres()
    assert d.reversals == 2
    spots = wrong_way(m, d.theta_max, d.theta_min)
    assert spots
    fall = (d.theta_min - d.theta_max) % TWO_PI
    for stroke, f in spots:
        assert 0 < f < 1
        t = d.theta_max + f * fall if stroke == 0 else d.theta_min + f * (TWO_PI - fall)
        v = float(np.ravel(m.slider(t).v)[0])
        assert (v > 0) if stroke == 0 else (v < 0)


def test_the_solver_option():
    from qropt.errors import ProblemError

    with pytest.raises(ProblemError, match="atlas"):
        Solver(atlas="yes")
    off = Solver(atlas=False)
    assert Solver(**off.options()).atlas is False  # the options rebuild an equal Solver (a Dask worker's)
    p = type_problem("drag-link-slider", 1.83, 0.42)
    r = off.solve(p)
    assert r.stats["atlas_starts"] == 0 and "atlas" not in r.certificate.global_claim


def test_a_solve_short_of_its_nodes_runs_the_atlas_starts_without_a_design_again_with_more_iterations():
    """At TR 2.295, 0.7816 m the coupler slider's atlas nodes hold 1.1752 rad (TR 2.25) and 1.1193 rad (TR 2.35).
    With IPOPT's iteration limit at 5, every start from them ends without a design: short of both nodes. The
    starts without a design run again with a larger iteration limit (4 times) and reach the design of the
    default solve (1.1520 rad, 66.0 deg), checked by the tests' own simulation."""
    from qropt.synthesis import multistart
    from qropt.synthesis.local import Designs

    p = type_problem("coupler-slider", 2.295, 0.7816)
    found = atlas.starts(p)
    between, floor = multistart.expected(p, found, Designs())
    assert floor == pytest.approx(1.1193, abs=1e-3)  # the worse node (TR 2.35)
    assert between == pytest.approx(1.1752 + 0.45 * (1.1193 - 1.1752), abs=1e-3)
    default = Solver().solve(p)
    assert "larger iteration limit" not in default.certificate.global_claim
    r = Solver(ipopt_options={"ipopt.max_iter": 5}).solve(p)
    assert r.status == "optimal", r.message
    assert "larger iteration limit" in r.certificate.global_claim
    assert r.stats["ipopt_runs"] > default.stats["ipopt_runs"]
    assert r.objective == pytest.approx(default.objective, abs=1e-9)
    assert r.objective > floor  # and above the nodes' values interpolated to the TR (1.1500 rad)
    b_tr, b_stroke, b_gamma = brute.task_values("coupler-slider", dict(r.mechanism.params))
    assert (b_tr, b_stroke) == pytest.approx((2.295, 0.7816), abs=1e-8)
    assert b_gamma == pytest.approx(r.objective, abs=1e-7)
    assert b_gamma > 1.15


def test_no_value_is_expected_where_one_node_has_no_design():
    """The slider-crank reaches TR 2.967 but not the node above it (3.05): no value is expected from one node."""
    from qropt.synthesis import multistart
    from qropt.synthesis.local import Designs

    p = type_problem("slider-crank", 2.967, 0.0908)
    found = atlas.starts(p)
    assert found.designs and set(found.nodes) == {0}
    assert multistart.expected(p, found, Designs()) == (None, None)
    assert not multistart.short(p, [], None, Solver().settings.atlas_short)


def test_a_solve_still_short_after_the_rerun_runs_the_multi_start_as_well(monkeypatch):
    """Where the atlas's starts end short of both nodes' values, also after the rerun, the multi-start runs as
    well, its candidates and the atlas's together, and the claim counts every start (here with the nodes' values
    raised beyond any design's; the test below is a task that falls that short)."""
    from qropt.synthesis import multistart

    p = type_problem("crank-rocker-slider", 1.898, 0.1077, objective="min_peak_accel")
    plain = Solver().solve(p)
    assert "atlas" in plain.certificate.global_claim and "distinct local optima" not in plain.certificate.global_claim
    monkeypatch.setattr(multistart, "expected", lambda problem, found, designs: (0.0, 0.0))  # signed: minimised
    r = Solver().solve(p)
    assert r.status == "optimal", r.message
    assert "distinct local optima" in r.certificate.global_claim
    assert r.stats["starts"] > r.stats["atlas_starts"] == 2  # each node's two designs are one start (atlas.SAME)
    assert r.objective <= plain.objective * (1 + 1e-9)  # the atlas's candidates kept
    alone = Solver(atlas=False).solve(p)
    assert r.objective <= alone.objective * (1 + 1e-9)
    b_tr, b_stroke, _ = brute.task_values("crank-rocker-slider", dict(r.mechanism.params))
    assert (b_tr, b_stroke) == pytest.approx((1.898, 0.1077), abs=1e-8)


def test_a_solve_between_nodes_of_another_shape_reaches_the_better_design():
    """At TR 2.155, 0.3808 m the coupler slider's atlas nodes (TR 2.15, 1.2187 rad, and 2.25, 1.1752 rad) hold
    designs of other shapes. The solve reaches 1.2168 rad (69.7 deg; 1.1116 rad before the node at TR 2.25 held
    1.1752): from the atlas's starts, or, where they end more than 2 % short of both nodes, by the multi-start
    that then runs as well. Checked by the tests' own simulation."""
    from qropt.synthesis import multistart
    from qropt.synthesis.local import Designs

    p = type_problem("coupler-slider", 2.155, 0.3808)
    _, floor = multistart.expected(p, atlas.starts(p), Designs())
    assert floor == pytest.approx(1.1752, abs=1e-3)
    r = Solver().solve(p)
    assert r.status == "optimal", r.message
    assert "atlas" in r.certificate.global_claim and r.stats["atlas_starts"] == 4
    assert r.objective > 1.2
    b_tr, b_stroke, b_gamma = brute.task_values("coupler-slider", dict(r.mechanism.params))
    assert (b_tr, b_stroke) == pytest.approx((2.155, 0.3808), abs=1e-8)
    assert b_gamma == pytest.approx(r.objective, abs=1e-7)


# the coupler slider's best gamma_min at TR 2.056, 0.2236 m (m, rad; 1.2491 rad), from a 256-start multi-start
COUPLER_OPTIMUM = {
    "r1": 0.6043291853944245,
    "r2": 0.08155147011660599,
    "r3": 0.29081619165484857,
    "r4": 0.5359947287699416,
    "r5": 1.117999999996619,
    "beta": -0.5880881687113135,
    "r6": 0.78434292877084,
    "h": 0.5169896740835271,
}


def test_a_start_at_an_optimum_stays_there():
    """A start at the coupler slider's optimum at TR 2.056, whose velocity touches zero inside a stroke: the lifted
    turn-back holds it there, from IPOPT's default, adaptive barrier and from the small, monotone barrier of a
    given start (``Ipopt.near``) alike, in one run of a few iterations. The solve comes back to the optimum
    (1.24908 rad, a certified optimum 2e-5 rad from the start's 1.24910, whose turn back by 1e-7 of the stroke
    is a dwell), checked by the tests' own simulation."""
    from qropt.synthesis.backends import Ipopt

    class Adaptive:  # IPOPT without its near() variant: every run from the default barrier
        name = "ipopt"

        def __init__(self):
            self.ipopt = Ipopt()

        def run(self, *args, **kw):
            return self.ipopt.run(*args, **kw)

    p = type_problem("coupler-slider", 2.056, 0.2236)
    branch = {"sigma": -1.0, "sigma_slider": 1.0}
    m = p.mechanism(**COUPLER_OPTIMUM, **branch)
    assert m.gamma_min().value == pytest.approx(1.2491, abs=1e-4)
    adaptive = Solver(atlas=False, backend=Adaptive()).local_solve.run(p, COUPLER_OPTIMUM, branch, dict(p.targets))
    c = Solver(atlas=False).local_solve.run(p, COUPLER_OPTIMUM, branch, dict(p.targets), near=True)
    for run in (adaptive, c):
        assert run.ok and run.info["certified"] > 1.2490
        assert len(run.statuses) == 1 and run.iterations <= 15
    r = Solver(atlas=False).solve(p, starts_n=0, use_analytic=False, extra_starts=[COUPLER_OPTIMUM])
    assert r.status == "optimal", r.message
    assert r.objective > 1.2490
    b_tr, b_stroke, b_gamma = brute.task_values("coupler-slider", dict(r.mechanism.params))
    assert (b_tr, b_stroke) == pytest.approx((2.056, 0.2236), abs=1e-8)
    assert b_gamma == pytest.approx(r.objective, abs=1e-7)


def test_the_small_barrier_keeps_the_callers_options():
    """``Ipopt.near`` is IPOPT's monotone barrier from mu_init 1e-6, except where the caller named a barrier option;
    the patient variant keeps both the caller's options and the small barrier."""
    near = Solver().backend.near().options
    assert (near["ipopt.mu_strategy"], near["ipopt.mu_init"]) == ("monotone", 1e-6)
    own = Solver(ipopt_options={"ipopt.mu_strategy": "adaptive", "ipopt.max_iter": 100}).backend
    assert own.near().options["ipopt.mu_strategy"] == "adaptive"
    patient = own.patient()
    assert patient.options["ipopt.max_iter"] == 400 and patient.options["ipopt.mu_strategy"] == "adaptive"
    assert Solver().backend.patient().near().options["ipopt.max_iter"] == 240


def test_a_nodes_designs_that_are_one_shape_are_one_start(monkeypatch):
    """The atlas keeps two designs a node; where they are within atlas.SAME in every parameter (the coupler
    slider's at TR 2.05: 1.25046 and 1.25045 rad, 1.8 % of a stroke apart at most) they are one start. With both,
    the solve at TR 2.135, 0.1797 m runs the second to the same design as the first."""
    p = type_problem("coupler-slider", 2.135, 0.1797)
    e = next(e for e in DATA["entries"] if e["signature"] == atlas.signature(p))
    pair = e["designs"][e["nodes"].index(2.05)]
    apart = max(abs(x - pair[1]["params"][k]) for k, x in pair[0]["params"].items())
    assert 0.01 < apart < atlas.SAME
    assert atlas.starts(p).nodes == (0, 1, 1)  # TR 2.05's one, TR 2.15's two (3.8 % of a stroke apart)
    one = Solver().solve(p)
    monkeypatch.setattr(atlas, "SAME", 0.0)
    assert atlas.starts(p).nodes == (0, 0, 1, 1)
    both = Solver().solve(p)
    assert one.objective == pytest.approx(both.objective, abs=1e-12) == pytest.approx(1.2246376238, abs=1e-9)
    assert one.stats["ipopt_runs"] < both.stats["ipopt_runs"]


def test_an_exchange_loop_that_goes_round_without_moving_stops():
    """Three rounds in a row that end alike (verdict, reason, NLP value to 1e-9, the same angles to add) stop the
    loop; one that differs in any of them does not."""
    from qropt.synthesis.local import _stuck

    same = (False, "the NLP's dead centres are local", -0.5484, np.array([3.1267]), np.zeros(0))
    assert _stuck([same] * 3, 3) and not _stuck([same] * 2, 3)
    moved = (False, same[1], -0.5484 + 1e-6, same[3], same[4])
    other = (False, same[1], same[2], np.array([3.1267 + 1e-6]), same[4])
    why = (False, "the output reverses 2 times a turn", *same[2:])
    for odd in (moved, other, why):
        assert not _stuck([same, odd, same], 3) and not _stuck([odd, same, same], 3)


def _touching(par, t_max, t_min):
    """The output velocity's largest local maximum inside the falling stroke (theta_max to theta_min, ccw), by the
    tests' own finite differences refined by a bounded search, relative to the peak speed."""
    from scipy.optimize import minimize_scalar

    th = np.linspace(0.0, 2 * np.pi, 20001)
    _, v, _ = brute.sixbar_motion("coupler-slider", par, th)
    inside = ((th - t_max) % (2 * np.pi)) < ((t_min - t_max) % (2 * np.pi))
    k = [i for i in np.flatnonzero((v[1:-1] > v[:-2]) & (v[1:-1] >= v[2:])) + 1 if inside[i]]
    assert k, "no turn back inside the falling stroke"

    def minus_v(t):
        return -float(brute.sixbar_motion("coupler-slider", par, np.array([t]))[1][0])

    top = max(
        -minimize_scalar(minus_v, bounds=(th[i - 2], th[i + 2]), method="bounded", options={"xatol": 1e-10}).fun
        for i in k
    )
    return top / np.max(np.abs(v))


def test_an_optimum_whose_velocity_touches_zero_mid_stroke_is_reached():
    """The coupler slider's best gamma_min at TR 2.185, 0.567 m holds its output velocity at zero at one point
    inside the falling stroke: a turn-back of the velocity that touches zero, held there by a lifted crank angle
    (stationary velocity, of the stroke's sign). The solve reaches it from the atlas (1.2042 rad, 69.0 deg; with
    the velocity's sign held at fixed angles of each stroke it reached 1.1035 rad in 8 s). By the tests' own
    simulation: the target values, gamma_min, one maximum a turn, and a velocity that touches zero (to 1e-9 of
    the peak speed) without crossing it."""
    p = type_problem("coupler-slider", 2.185, 0.567)
    r = Solver().solve(p)
    assert r.status == "optimal", r.message
    assert "atlas" in r.certificate.global_claim and r.objective > 1.2042
    par = dict(r.mechanism.params)
    t_max, t_min, _, _, b_tr, b_stroke, b_gamma = brute.sixbar_cycle("coupler-slider", par)
    assert (b_tr, b_stroke) == pytest.approx((2.185, 0.567), abs=1e-8)
    assert b_gamma == pytest.approx(r.objective, abs=1e-7)
    assert brute.sixbar_reversals("coupler-slider", par) == 1
    assert -1e-9 < _touching(par, t_max, t_min) <= 1e-9


def test_a_lifted_turn_back_follows_the_optimum_to_the_next_time_ratio():
    """From the atlas's design at TR 2.15 (whose velocity touches zero mid-stroke), the optimum at TR 2.16 is one
    IPOPT run away: the lifted turn-back angle moves with the design (fixed angles of each stroke went round 11
    rounds and ended at no design). Its design meets TR and stroke by the tests' own simulation."""
    from qropt.synthesis.local import Designs

    p0 = type_problem("coupler-slider", 2.15, 1.0)
    e = next(e for e in DATA["entries"] if e["signature"] == atlas.signature(p0))
    d = e["designs"][e["nodes"].index(2.15)][0]
    p = type_problem("coupler-slider", 2.16, 1.0)
    c = Solver(atlas=False).local(p, d["params"], d["branch"], dict(p.targets), designs=Designs())
    assert c.ok, c.info
    assert len(c.statuses) == 1
    assert d["value"] - 0.01 < c.info["certified"] < d["value"]
    par = dict(c.mechanism.params)
    t_max, t_min, _, _, b_tr, b_stroke, b_gamma = brute.sixbar_cycle("coupler-slider", par)
    assert (b_tr, b_stroke) == pytest.approx((2.16, 1.0), abs=1e-8)
    assert b_gamma == pytest.approx(c.info["certified"], abs=1e-7)
    assert brute.sixbar_reversals("coupler-slider", par) == 1


def test_a_turn_back_the_certifier_finds_takes_the_slot_that_holds_least():
    """The lifted turn-back angles of a guarded NLP: added to an unguarded NLP's point (the switch a solve makes
    where the certifier sees a reversal), they start at a stationary point of the velocity inside each stroke; a
    turn-back found near a lifted one moves it, and one found elsewhere takes the slot where the velocity is
    farthest from turning back (the stroke's fastest point), keeping the one that holds a turn-back."""
    from qropt.synthesis.formulation import MONOTONE, TURN_GRID, TURN_NEAR

    p = type_problem("coupler-slider", 2.185, 0.567)
    r = Solver().solve(p)
    m, branch = r.mechanism, {k: r.params[k] for k in p.branches}
    d = m.dead_centres()
    theta = np.array([d.theta_max, d.theta_min if d.theta_min > d.theta_max else d.theta_min + 2 * np.pi])
    solver = Solver()
    plain = solver._formulations.get(p, branch, r.stats["orientation"], guarded=False)
    guarded = solver._formulations.get(p, branch, r.stats["orientation"], guarded=True)
    values = {k: r.params[k] for k in p.free}
    w = guarded.with_turns(plain.pack(values, theta), m)
    assert w.size == guarded.w_blocks.size > plain.w_blocks.size
    turn = guarded.unpack(w).turn
    assert turn.size == 2 * MONOTONE
    fall = theta[1] - theta[0]
    for s in range(2):
        lo, hi = (theta[0], theta[1]) if s == 0 else (theta[1], theta[0] + 2 * np.pi)
        step = (hi - lo) / (TURN_GRID - 1)  # the grid's: the velocity is stationary within a step of each
        for t in turn[s * MONOTONE : (s + 1) * MONOTONE]:
            assert lo < t < hi
            a = np.ravel(m.slider(np.array([t - step, t + step])).a)
            assert a[0] * a[1] <= 0
    held, fastest = turn[0], turn[1]  # the falling stroke's touching turn-back, and its fastest point
    assert abs(float(np.ravel(m.slider(held).v)[0])) < 1e-3 < abs(float(np.ravel(m.slider(fastest).v)[0]))
    near = guarded.turn_start(m, theta, [(0, (held + 0.5 * TURN_NEAR - theta[0]) / fall)], turn)
    assert near[0] == pytest.approx(held + 0.5 * TURN_NEAR) and near[1] == fastest
    at = fastest + 3 * TURN_NEAR * np.sign(held - fastest)  # nearer the fastest point, far from both
    assert min(abs(at - held), abs(at - fastest)) > TURN_NEAR
    far = (at - theta[0]) / fall
    moved = guarded.turn_start(m, theta, [(0, far)], turn)
    assert moved[0] == held and moved[1] == pytest.approx(theta[0] + far * fall)
    assert np.array_equal(moved[2:], turn[2:])  # the rising stroke's untouched
