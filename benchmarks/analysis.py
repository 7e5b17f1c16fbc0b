"""Full-cycle analysis speed of every type against a plain-Python loop over the same formulas.

Run: ``python -m benchmarks.analysis``. Prints medians (ms) and ratios; the
baseline and qropt run in the same process on the same mechanisms.
"""

from __future__ import annotations

import math
import statistics
import sys
import time

import numpy as np
from tqdm import tqdm

from qropt.kinematics.ops import JET, NUMPY, Jet
from qropt.mechanisms import TYPES
from tests.randmech import random_mechanisms

SAMPLES = 3600
NEW = 25  # random new mechanisms per type for the exact analysis


class _Scalar:
    """The NUMPY namespace's functions on Python floats (the baseline's 'plain Python')."""

    name = "math"
    sin, cos, atan2, sqrt, acos, asin, fabs = math.sin, math.cos, math.atan2, math.sqrt, math.acos, math.asin, abs
    fmin, fmax, pi = min, max, math.pi

    @staticmethod
    def if_else(c, a, b):
        return a if c else b


def median_ms(f, repeat=7):
    out = []
    for _ in range(repeat):
        t = time.perf_counter()
        f()
        out.append(time.perf_counter() - t)
    return 1e3 * statistics.median(out)


def run(samples: int = SAMPLES):
    th = 2 * np.pi * np.arange(samples) / samples
    th_list = th.tolist()
    rows = []
    for cls in tqdm(TYPES, desc="types", disable=not sys.stderr.isatty(), leave=False):
        _, m = random_mechanisms(cls.KIND, 1, seed=11)[0]
        p = m.params
        t_pos = median_ms(lambda m=m, p=p: m.loop(NUMPY, th, p))
        t_xva = median_ms(lambda m=m, p=p: m.loop(JET, Jet.seed(th, 10.0, 0.0), p))
        t_loop = median_ms(lambda cls=cls, p=p: [cls.loop(_Scalar, t, p) for t in th_list], repeat=3)

        def exact(p, cls=cls):
            mm = cls(**p)
            mm.time_ratio(), mm.stroke(), mm.gamma_min()

        t_exact = [
            median_ms(lambda p=q.params: exact(p), repeat=15) for _, q in random_mechanisms(cls.KIND, NEW, seed=5)
        ]
        rows.append((cls.__name__, t_pos, t_xva, t_loop, t_loop / t_pos, statistics.median(t_exact), max(t_exact)))
    return rows


def main():
    rows = run()
    print(f"full-cycle evaluation, {SAMPLES} crank angles (median of repeats, ms)")
    head = f"{'type':18s} {'positions':>10s} {'x,v,a':>8s} {'py loop':>9s} {'speed-up':>9s}"
    head += f" {'TR+S+gmin':>10s} {'slowest':>8s}"
    print(head)
    for name, a, b, c, r, e, worst in rows:
        print(f"{name:18s} {a:10.3f} {b:8.3f} {c:9.2f} {r:8.0f}x {e:10.3f} {worst:8.3f}")
    print("positions/x,v,a: qropt vectorised; py loop: the same loop() on floats, one angle at a time;")
    print("TR+S+gmin: construction (with the full-turn assembly check) plus exact time ratio, stroke, gamma_min,")
    print(f"median over {NEW} random new mechanisms; slowest: the one whose quantities need the finer grids.")


if __name__ == "__main__":
    main()
