"""The convex layer's speed: servo speed profiles, tolerance allocation and its Monte Carlo check, each against a
baseline run in the same process.

Run: ``python -m benchmarks.convex``. Prints medians and ratios and writes ``results/convex.md`` and
``results/convex.json`` (date, machine, versions).
"""

from __future__ import annotations

import math
import statistics
import time

import cvxpy
import numpy as np

import qropt
from benchmarks.report import RESULTS, environment, save
from qropt.convex.servo import speed_profile
from qropt.convex.tolerance import allocate, sensitivities
from qropt.examples import paper_mechanism

TORQUE = dict(omega_max=13.0, alpha_max=200.0, force=1000.0, inertia=1.0, torque_max=113.0)
CUT = dict(omega_max=20.0, v_cut=0.5, a_max=40.0, alpha_max=400.0, v_max=2.0)
LIMITS = {"time_ratio": 0.01, "stroke": 0.001}


def median_s(f, repeat=5):
    out = []
    for _ in range(repeat):
        t = time.perf_counter()
        f()
        out.append(time.perf_counter() - t)
    return statistics.median(out)


def speed_only_numpy(m, omega_max, v_max, n):
    """The speed-limits-only profile in closed form on the same grid: b = min(omega_max^2, v_max^2 / x'^2)."""
    th = np.linspace(0, 2 * math.pi, n + 1)
    xp = np.abs(m.motion(th, 1.0, 0.0).v)
    with np.errstate(divide="ignore"):
        w = np.minimum(omega_max, v_max / xp)
    return float(np.sum(2 * np.diff(th) / (w[1:] + w[:-1])))


def run() -> list[tuple]:
    dl, sc = paper_mechanism(), qropt.SliderCrank(r2=0.1, r3=0.4)
    rows = []
    t720 = median_s(lambda: speed_profile(dl, **TORQUE, n=720))
    t360 = median_s(lambda: speed_profile(dl, **TORQUE, n=360))
    rows.append(("speed_profile, drag-link torque limit, n = 720", t720, "n = 360", t360, 0.5))
    tcut = median_s(lambda: speed_profile(sc, **CUT, n=720))
    rows.append(
        (
            "speed_profile, in-line slider-crank v_cut, n = 720",
            tcut,
            "n = 360",
            median_s(lambda: speed_profile(sc, **CUT, n=360)),
            0.5,
        )
    )
    tsp = median_s(lambda: speed_profile(dl, omega_max=12.0, v_max=1.5, n=720))
    tnp = median_s(lambda: speed_only_numpy(dl, 12.0, 1.5, 720), repeat=21)
    rows.append(("speed_profile, speed limits only, n = 720", tsp, "numpy closed form", tnp, 0.5))
    allocate(dl, LIMITS)  # builds the CasADi functions of the type once per process
    ta = median_s(lambda: allocate(dl, LIMITS), repeat=21)
    ts = median_s(lambda: sensitivities(dl), repeat=21)
    rows.append(("allocate, worst-case, TR + stroke", ta, "sensitivities(), all quantities", ts, 0.05))
    tr = median_s(lambda: allocate(dl, LIMITS, method="rss"), repeat=21)
    rows.append(("allocate, rss, TR + stroke", tr, "sensitivities(), all quantities", ts, 0.05))
    al = allocate(dl, LIMITS)
    tmc = median_s(lambda: al.monte_carlo(10_000, progress=False), repeat=3)
    rng = np.random.default_rng(0)
    samples = [
        {
            k: v + (rng.uniform(-1, 1) * al.tolerances.get(k, 0.0) if math.isfinite(al.tolerances.get(k, 0.0)) else 0.0)
            for k, v in dl.params.items()
        }
        for _ in range(200)
    ]
    tloop = median_s(lambda: [(lambda m: (m.time_ratio(), m.stroke()))(type(dl)(**p)) for p in samples], repeat=3)
    per = tloop / 200
    rows.append(("monte_carlo, 10,000 mechanisms, vectorised", tmc, "per-mechanism API x 10,000", per * 10_000, 2.0))
    return rows


def markdown(rows, env) -> str:
    versions = ", ".join(f"{k} {v}" for k, v in env["versions"].items())
    lines = [
        "# The convex layer (servo profiles, tolerance allocation)",
        "",
        f"{env['date']}, {env['machine']}, Python {env['python']}, {versions}, cvxpy {cvxpy.__version__}",
        "",
        "| task | median | baseline | baseline median | ratio | target |",
        "|---|---|---|---|---|---|",
    ]
    for name, t, base, tb, target in rows:
        ok = "met" if t <= target else "MISSED"
        row = f"| {name} | {1e3 * t:.1f} ms | {base} | {1e3 * tb:.2f} ms | {t / tb:.2f}x | <= {1e3 * target:g} ms"
        lines.append(f"{row} ({ok}) |")
    lines += [
        "",
        "ratio = task / baseline (both in this process). The per-mechanism Monte Carlo baseline is a loop of 200 "
        "constructions with exact time ratio and stroke, scaled to 10,000.",
    ]
    return "\n".join(lines) + "\n"


def main():
    rows = run()
    env = environment()
    print("the convex layer (median of repeats)")
    for name, t, base, tb, target in rows:
        print(
            f"  {name:52s} {1e3 * t:9.1f} ms   {base}: {1e3 * tb:9.2f} ms   ratio {t / tb:7.2f}x   "
            f"target <= {1e3 * target:g} ms {'met' if t <= target else 'MISSED'}"
        )
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / "convex.md").write_text(markdown(rows, env))
    save(
        "convex.json",
        {
            "cvxpy": cvxpy.__version__,
            "rows": [
                {"task": n, "median_s": t, "baseline": b, "baseline_s": tb, "ratio": t / tb, "target_s": g}
                for n, t, b, tb, g in rows
            ],
        },
    )


if __name__ == "__main__":
    main()
