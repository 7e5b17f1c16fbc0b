"""What a solve without a design costs: each infeasible or failing problem against a feasible solve of the same
problem structure (a reachable target, or the same problem with a reachable bound or another objective), as a
ratio in one run. ``--against REV`` runs the same cases on another commit (a git worktree, in a subprocess) and
reports both, so a change is measured against the code before it on the same machine and load.

Run: ``python -m benchmarks.diagnosis [--repeat K] [--against REV]`` from the repository root.
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(globals().get("__file__", ".")).resolve().parent.parent


def cases():
    """(name, feasible problem, the problem without a design); only qropt's public API (any version has it)."""
    from qropt import Problem
    from qropt.examples import paper_problem

    def paper(**kw):
        return paper_problem().replace(**kw)

    def rocker_slider(**kw):
        base = dict(
            mechanism="CrankRockerSlider",
            fixed={"r1": 0.3, "r2": 0.1, "r6": 0.5},
            free={"r3": (0.15, 0.6), "r4": (0.15, 0.45), "r5": (0.02, 0.45)},
            targets={"time_ratio": 1.2, "stroke": 0.15},
            objective="max_gamma_min",
        )
        return Problem(**{**base, **kw})

    def slider_crank(**kw):
        base = dict(
            mechanism="SliderCrank",
            free={"r2": (0.05, 0.3), "r3": (0.1, 1.5), "e": (0.0, 0.6)},
            targets={"time_ratio": 1.3, "stroke": 0.3},
        )
        return Problem(**{**base, **kw})

    def four_bar(**kw):
        base = dict(
            mechanism="FourBar",
            fixed={"r1": 1.0},
            free={"r2": (0.1, 0.5), "r3": (0.3, 2.0), "r4": (0.3, 2.0)},
            targets={"time_ratio": 1.3, "swing": math.radians(60)},
            conditions={"grashof": "crank-rocker"},
        )
        return Problem(**{**base, **kw})

    drag = {"grashof": "drag-link"}
    return [
        ("paper task at TR 9", paper(), paper(targets={"time_ratio": 9.0, "stroke": 0.3})),
        ("paper task, gamma_min >= 60 deg", paper(), paper(conditions={**drag, "gamma_min": math.radians(60)})),
        (
            "crank-rocker slider, gamma_min >= 80 deg",
            rocker_slider(),
            rocker_slider(conditions={"gamma_min": math.radians(80)}),
        ),
        ("slider-crank at TR 4", slider_crank(), slider_crank(targets={"time_ratio": 4.0, "stroke": 0.3})),
        ("slider-crank, stroke 5", slider_crank(), slider_crank(targets={"time_ratio": 1.3, "stroke": 5.0})),
        (
            "four-bar min_size (no attained optimum)",
            four_bar(objective="max_gamma_min"),
            four_bar(objective="min_size"),
        ),
    ]


def measure(repeat: int) -> list[dict]:
    """Median wall time of each feasible and each hard solve (after one warm-up each: NLPs built)."""
    import qropt

    out = []
    for name, ok, hard in cases():
        row = {"case": name}
        for key, p, k in (("feasible", ok, repeat), ("hard", hard, max(1, repeat // 3))):
            r = qropt.solve(p)
            times = []
            for _ in range(k):
                t = time.perf_counter()
                r = qropt.solve(p)
                times.append(time.perf_counter() - t)
            row[key] = statistics.median(times)
            row[key + "_status"] = r.status
        row["ratio"] = row["hard"] / row["feasible"]
        out.append(row)
    return out


def elsewhere(rev: str, repeat: int) -> list[dict]:
    """``measure`` on commit ``rev``: a detached worktree (kept under /tmp), this file run there in a subprocess."""
    tree = Path(f"/tmp/qropt-bench-{rev}")
    if not tree.exists():
        subprocess.run(
            ["git", "worktree", "add", "--detach", str(tree), rev], cwd=ROOT, check=True, capture_output=True
        )
    here = Path(__file__).resolve()
    code = f"import sys; sys.path.insert(0, {str(tree)!r}); sys.argv = ['x', '--json', '--repeat', '{repeat}']; "
    code += f"exec(open({str(here)!r}).read())"
    r = subprocess.run([sys.executable, "-P", "-c", code], capture_output=True, text=True, check=True, cwd=tree)
    return json.loads(r.stdout)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=9)
    ap.add_argument("--against", metavar="REV", help="also run the cases on this commit (e.g. b5ef221)")
    ap.add_argument("--json", action="store_true", help="print the measurements as JSON only")
    args = ap.parse_args(argv)
    before = elsewhere(args.against, args.repeat) if args.against else None
    now = measure(args.repeat)
    if args.json:
        print(json.dumps(now))
        return 0
    print("solves without a design, against a feasible solve of the same problem (median wall time, ms)")
    head = f"{'case':42s} {'feasible':>9s} {'hard':>9s} {'ratio':>6s}  status"
    print(head + (f"   | before: {'feasible':>8s} {'hard':>9s} {'ratio':>6s}  status" if before else ""))
    for i, r in enumerate(now):
        line = (
            f"{r['case']:42s} {1e3 * r['feasible']:9.1f} {1e3 * r['hard']:9.1f} {r['ratio']:6.1f}  {r['hard_status']}"
        )
        if before:
            b = before[i]
            line += (
                f"   |         {1e3 * b['feasible']:8.1f} {1e3 * b['hard']:9.1f} {b['ratio']:6.1f}  {b['hard_status']}"
            )
        print(line)
    if __package__:
        from benchmarks.report import save

        path = save("diagnosis.json", {"now": now, "before": before, "against": args.against})
        print(f"results in {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
