"""General loads, timed against the cutting-force shorthand in the same run: a mechanism's cycle extremes (peak
and RMS torque, every joint's peak force, the shaking force) with ``Loads(1000.0, gravity=9.81)`` against the same
load stated as a general force at the ram's joint (``Force(joint, 1000.0)``, the working stroke) with gravity as a
vector, for random mechanisms of every slider type, after WARM calls (the shorthand's kernels compiled). The two
give the same peak torque (checked here to 1e-9); the ratio is the general route's cost.

Medians of repeats; writes ``results/loads.json``. Run: ``python -m benchmarks.loads`` (repository root).
"""

from __future__ import annotations

import statistics

import qropt
from benchmarks import analysis
from benchmarks.report import save
from qropt.mechanisms import TYPES
from tests.randmech import random_mechanisms

MASSES = qropt.Masses.bars(2.0, 5.0)
SHORTHAND = qropt.Loads(1000.0, gravity=9.81)
OMEGA2 = 10.0
WARM = 20  # calls before the timing


def main() -> int:
    rows = {}
    for cls in TYPES:
        if cls.OUTPUT != "slider":
            continue
        kind = cls.KIND
        general = qropt.Loads(forces=[qropt.Force(cls.OUTPUT_JOINT, 1000.0)], gravity=(0.0, -9.81))
        ratios = []
        for _, m in random_mechanisms(kind, 3, seed=7):
            for _ in range(WARM):  # the steady state: the shorthand's kernels compiled (``Batched.HOT`` calls)
                a = m.dynamic_extremes(OMEGA2, masses=MASSES, loads=SHORTHAND)
            b = m.dynamic_extremes(OMEGA2, masses=MASSES, loads=general)
            assert abs(a.peak_torque.value - b.peak_torque.value) <= 1e-9 * max(1.0, abs(a.peak_torque.value))
            t_short = analysis.median_ms(lambda m=m: m.dynamic_extremes(OMEGA2, masses=MASSES, loads=SHORTHAND), 5)
            t_general = analysis.median_ms(lambda m=m, g=general: m.dynamic_extremes(OMEGA2, masses=MASSES, loads=g), 5)
            ratios.append((t_short, t_general))
        short = statistics.median(r[0] for r in ratios)
        gen = statistics.median(r[1] for r in ratios)
        rows[kind] = {"shorthand_ms": short, "general_ms": gen, "ratio": gen / short}
        print(f"  {kind:22s} shorthand {short:8.2f} ms  general {gen:8.2f} ms  ratio {gen / short:5.2f}", flush=True)
    ratio = statistics.median(r["ratio"] for r in rows.values())
    print(f"median ratio over the types: {ratio:.2f}")
    save("loads.json", {"omega2": OMEGA2, "types": rows, "median_ratio": ratio})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
