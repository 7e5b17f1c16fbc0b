"""Dynamics, timed against the kinematics in the same run: full-cycle inverse dynamics (torque, every joint force,
shaking) at 3,600 crank angles against the 3,600-angle motion (x, v, a and the link rates) of the same mechanism,
for random mechanisms of every type, in their first calls and once compiled; and a ``min_peak_torque`` solve
against a ``min_peak_accel`` solve of the same problem, both from the same starts (without the atlas, which
holds kinematic objectives only: it would start the second and not the first).

Medians of repeats; writes ``results/dynamics.json``. Run: ``python -m benchmarks.dynamics`` (repository root).
"""

from __future__ import annotations

import statistics
import time

import numpy as np

import qropt
from benchmarks import analysis
from benchmarks.report import save
from qropt.kinematics.kernel import Batched
from qropt.mechanisms import TYPES
from qropt.studies._design import type_problem
from tests.randmech import random_mechanisms

SAMPLES = 3600
MASSES = qropt.Masses.bars(2.0, 5.0)
LOADS = qropt.Loads(1000.0, gravity=9.81)


def median_ms(f, repeat=7):
    f()  # warm
    return analysis.median_ms(f, repeat)


def main() -> int:
    """Two regimes per mechanism: uncompiled (the motion and the dynamics on CasADi's VM, as in a shape's first
    Batched.HOT calls; the compiled calls held back for the measurement) and compiled (machine code, from
    Batched.HOT uses on)."""
    th = 2 * np.pi * np.arange(SAMPLES) / SAMPLES
    rows = {}
    print(f"{SAMPLES} crank angles, ms: uncompiled (CasADi's VM) | compiled")
    print(f"{'type':20s} {'motion':>8s} {'dynamics':>9s} {'ratio':>6s} | {'motion':>8s} {'dynamics':>9s} {'ratio':>6s}")
    for cls in TYPES:
        out = {"first": ([], [], []), "compiled": ([], [], [])}
        for _, m in random_mechanisms(cls.KIND, 3, seed=21):
            for regime in ("first", "compiled"):
                hot = Batched.HOT
                if regime == "compiled":
                    for _ in range(hot):
                        m.motion(th, 10.0)
                        m.dynamics(th, 10.0, masses=MASSES, loads=LOADS)
                else:
                    Batched.HOT = 10**9  # nothing runs compiled
                try:
                    a = median_ms(lambda m=m: m.motion(th, 10.0))
                    b = median_ms(lambda m=m: m.dynamics(th, 10.0, masses=MASSES, loads=LOADS))
                finally:
                    Batched.HOT = hot
                tm, td, ratios = out[regime]
                tm.append(a)
                td.append(b)
                ratios.append(b / a)
        rows[cls.KIND] = {
            regime: {
                "motion_ms": statistics.median(tm),
                "dynamics_ms": statistics.median(td),
                "ratio": statistics.median(r),
                "ratios": r,
            }
            for regime, (tm, td, r) in out.items()
        }
        f, c = rows[cls.KIND]["first"], rows[cls.KIND]["compiled"]
        print(
            f"{cls.KIND:20s} {f['motion_ms']:8.3f} {f['dynamics_ms']:9.3f} {f['ratio']:6.1f} | "
            f"{c['motion_ms']:8.3f} {c['dynamics_ms']:9.3f} {c['ratio']:6.1f}"
        )
    solves = {}
    for kind in ("crank-shaper", "whitworth", "slider-crank"):
        p = type_problem(kind, 1.5, 0.3, objective="min_peak_accel", masses=MASSES, loads=LOADS, omega2=10.0)
        times = {}
        for objective in ("min_peak_accel", "min_peak_torque"):
            q = p.replace(objective=objective)
            solver = qropt.Solver(atlas=False)  # the same starts for both (the atlas holds no dynamic objective)
            solver.solve(q)  # warm: the NLPs built
            out = []
            for _ in range(3):
                t = time.perf_counter()
                r = solver.solve(q)
                out.append(time.perf_counter() - t)
            times[objective] = (statistics.median(out), r.status)
        ratio = times["min_peak_torque"][0] / times["min_peak_accel"][0]
        solves[kind] = {k: {"s": v[0], "status": v[1]} for k, v in times.items()} | {"ratio": ratio}
        print(
            f"{kind:20s} min_peak_accel {times['min_peak_accel'][0]:.3f} s ({times['min_peak_accel'][1]}), "
            f"min_peak_torque {times['min_peak_torque'][0]:.3f} s ({times['min_peak_torque'][1]}): {ratio:.1f}x"
        )
    save("dynamics.json", {"samples": SAMPLES, "analysis": rows, "solves": solves})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
