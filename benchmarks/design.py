"""Type synthesis and trade-off fronts, timed: ``design()`` of the README's task (TR 1.5, stroke 0.3) for all six
types, and 20-point fronts, each against its baseline in the same run.

Baselines: each type solved cold (no closed-form starts, no atlas), and a front whose every point is a full
default solve (no warm start from the neighbour). Medians of ``--repeat`` runs after one warm-up (which builds
the NLPs). Writes ``results/design.json``.

Run: ``python -m benchmarks.design [--repeat 3]`` (from the repository root).
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from benchmarks.report import save
from problems import _bases as problem_bases
from qropt import Solver
from qropt.studies._design import TYPES, design, type_problem
from qropt.studies._pareto import pareto
from qropt.synthesis import criteria

FRONTS = {
    "slider_crank: max_gamma_min vs min_peak_accel": (
        problem_bases.slider_crank(omega2=2.0),
        ("max_gamma_min", "min_peak_accel"),
    ),
    "slider_crank: max_gamma_min vs min_peak_velocity": (
        problem_bases.slider_crank(omega2=2.0),
        ("max_gamma_min", "min_peak_velocity"),
    ),
    "crank_rocker_slider: max_gamma_min vs min_size (sum)": (
        problem_bases.crank_rocker_slider(omega2=2.0),
        ("max_gamma_min", "min_size"),
    ),
}


def timed(f, repeat):
    out, times = None, []
    for _ in range(repeat):
        t = time.perf_counter()
        out = f()
        times.append(time.perf_counter() - t)
    return out, statistics.median(times), times


def front_by_full_solves(problem, objectives, n, solver):
    """The baseline front: the same sweep, every point a full default solve."""
    a, b = objectives
    cb = criteria.of(b, problem.size)
    ends = [solver.solve(problem.replace(objective=o)) for o in (a, b)]
    lo, hi = (cb.value(problem, r.mechanism) for r in ends)
    return [
        solver.solve(problem.replace(objective=a, conditions={**problem.conditions, cb.bound: float(e)}))
        for e in np.linspace(lo, hi, n)[1:-1]
    ]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args(argv)
    solver = Solver()
    design(1.5, 0.3, solver=solver)  # warm-up: every type's NLPs built once
    cmp, t_design, runs = timed(lambda: design(1.5, 0.3, solver=solver), args.repeat)
    per_type = {r.type: r.result.stats["t_total"] for r in cmp.rows}
    print(f"design(1.5, 0.3), {len(TYPES)} types: median {t_design:.2f} s (runs {', '.join(f'{t:.2f}' for t in runs)})")
    for k, v in per_type.items():
        print(f"  {k:20s} {v:.2f} s")
    cold = Solver(atlas=False)
    for k in TYPES:
        cold.solve(type_problem(k, 1.5, 0.3), use_analytic=False)
    _, t_cold, _ = timed(
        lambda: [cold.solve(type_problem(k, 1.5, 0.3), use_analytic=False) for k in TYPES], args.repeat
    )
    cold_note = "no closed-form starts, no atlas"
    print(f"  the same types solved cold ({cold_note}): median {t_cold:.2f} s ({t_cold / t_design:.1f}x)")
    fronts = {}
    for name, (p, objectives) in FRONTS.items():
        pareto(p, objectives, n=20, solver=solver)  # warm-up
        f, t_front, _ = timed(
            lambda p=p, objectives=objectives: pareto(p, objectives, n=20, solver=solver), args.repeat
        )
        _, t_full, _ = timed(lambda p=p, objectives=objectives: front_by_full_solves(p, objectives, 20, solver), 1)
        fronts[name] = {
            "points": len(f.points),
            "removed": len(f.removed),
            "median_s": t_front,
            "full_solves_s": t_full,
            "gain": t_full / t_front,
        }
        print(
            f"20-point front, {name}: median {t_front:.2f} s, {len(f.points)} points ({len(f.removed)} "
            f"removed); every point a full solve: {t_full:.2f} s ({t_full / t_front:.1f}x)"
        )
    save(
        "design.json",
        {
            "design_median_s": t_design,
            "design_runs_s": runs,
            "per_type_s": per_type,
            "cold_types_s": t_cold,
            "fronts": fronts,
        },
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
