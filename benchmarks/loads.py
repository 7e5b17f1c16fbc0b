"""General loads, timed against the cutting-force shorthand in the same run: a mechanism's cycle extremes (peak
and RMS torque, every joint's peak force, the shaking force) with ``Loads(1000.0, gravity=9.81)`` against the same
load stated as a general force at the ram's joint (``Force(joint, 1000.0)``, the working stroke) with gravity as a
vector, for random mechanisms of every slider type, after WARM calls of each (the steady state: both routes' compiled
kernels built, ``Batched.HOT``). The two give the same peak torque (checked here to 1e-9); the ratio is the general
route's cost.

The two are timed in turns (shorthand, general, shorthand, ...), so that a machine's varying load falls on both
alike; medians of the repeats. Writes ``results/loads.json``. Run: ``python -m benchmarks.loads`` (repository
root).
"""

from __future__ import annotations

import statistics
import time

import qropt
from benchmarks.report import save
from qropt.mechanisms import TYPES
from tests.randmech import random_mechanisms

MASSES = qropt.Masses.bars(2.0, 5.0)
SHORTHAND = qropt.Loads(1000.0, gravity=9.81)
OMEGA2 = 10.0
WARM = 20  # calls of each before the timing
REPEAT = 15  # timed calls of each, in turns


def _ms(f) -> float:
    t = time.perf_counter()
    f()
    return 1e3 * (time.perf_counter() - t)


def main() -> int:
    rows = {}
    for cls in TYPES:
        if cls.OUTPUT != "slider":
            continue
        kind = cls.KIND
        general = qropt.Loads(forces=[qropt.Force(cls.OUTPUT_JOINT, 1000.0)], gravity=(0.0, -9.81))
        ratios = []
        for _, m in random_mechanisms(kind, 3, seed=7):

            def short(m=m):
                return m.dynamic_extremes(OMEGA2, masses=MASSES, loads=SHORTHAND)

            def gen(m=m, g=general):
                return m.dynamic_extremes(OMEGA2, masses=MASSES, loads=g)

            for _ in range(WARM):  # the steady state: each route's kernels compiled (``Batched.HOT`` calls)
                a, b = short(), gen()
            assert abs(a.peak_torque.value - b.peak_torque.value) <= 1e-9 * max(1.0, abs(a.peak_torque.value))
            times = [(_ms(short), _ms(gen)) for _ in range(REPEAT)]
            ratios.append((statistics.median(t[0] for t in times), statistics.median(t[1] for t in times)))
        short_ms = statistics.median(r[0] for r in ratios)
        gen_ms = statistics.median(r[1] for r in ratios)
        rows[kind] = {"shorthand_ms": short_ms, "general_ms": gen_ms, "ratio": gen_ms / short_ms}
        print(f"  {kind:22s} shorthand {short_ms:8.2f} ms  general {gen_ms:8.2f} ms  ratio {gen_ms / short_ms:5.2f}")
    ratio = statistics.median(r["ratio"] for r in rows.values())
    print(f"median ratio over the types: {ratio:.2f}")
    save("loads.json", {"omega2": OMEGA2, "types": rows, "median_ratio": ratio})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
