"""A traced family against a naive sweep, in one run: the paper's (r1, r3) family at TR 1.5 traced by
continuation, and ``solve()`` re-run at as many values of r1 (r3 free, analytic and Sobol starts).
Prints times, the largest equation residual along the trace, and the ratio; writes
benchmarks/results/family.json.

Run: ``python -m benchmarks.family``.
"""

from __future__ import annotations

import importlib
import sys
import time

import numpy as np
from tqdm import tqdm

from benchmarks.report import save
from qropt import Problem, solve
from qropt.studies._family import family


def main(points: int = 1000):
    problem = importlib.import_module("problems.paper_family_r1_r3").build()
    family(problem, starts_n=2)  # builds the NLP once (not timed)
    t = time.perf_counter()
    f = family(problem)
    t_trace = time.perf_counter() - t
    pts = f.points()
    residual = max(p.residual for p in pts)
    r1 = np.linspace(min(p.params["r1"] for p in pts), max(p.params["r1"] for p in pts), points)
    sweep = Problem(
        "DragLinkSlider",
        fixed={**problem.fixed, "r1": float(r1[0])},
        free={"r3": problem.free["r3"]},
        targets=dict(problem.targets),
        objective=None,
    )
    solve(sweep, starts_n=0)
    t = time.perf_counter()
    found = 0
    for x in tqdm(r1, desc="naive sweep", unit="solve", disable=not sys.stderr.isatty()):
        r = solve(sweep.replace(fixed={**problem.fixed, "r1": float(x)}), starts_n=2)
        found += len(r.local_optima)
    t_sweep = time.perf_counter() - t
    per = 1e3 * t_trace / len(pts)
    print(
        f"paper family (r1, r3 free, TR 1.5): {len(pts)} traced points in {t_trace:.3f} s ({per:.3f} ms a point), "
        f"largest residual {residual:.1e}, {len(f.folds)} fold"
    )
    print(
        f"naive sweep: solve() at {points} values of r1: {t_sweep:.2f} s "
        f"({1e3 * t_sweep / points:.2f} ms a value), {found} designs"
    )
    print(f"trace / sweep: {t_sweep / t_trace:.1f}x faster")
    save(
        "family.json",
        {
            "trace": {"points": len(pts), "seconds": t_trace, "max_residual": residual, "folds": len(f.folds)},
            "sweep": {"values": points, "seconds": t_sweep, "designs": found},
            "speedup": t_sweep / t_trace,
        },
    )


if __name__ == "__main__":
    main()
