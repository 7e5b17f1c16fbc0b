"""What more differential evolutions buy a dynamic row: the four-bar-driven rows of ``benchmarks.tasks``' tasks
by ``min_peak_torque`` (its mass model, loads and speed) solved with ``Solver(evolutions=K)``, against the same
rows of ``results/tasks_workers.json`` (the last ``benchmarks.tasks --workers`` run: its evolutions, its date).

The tasks are split over ``--processes`` processes (task i in process i mod P, each with its own Solver, its rows
one after another). Each finished row is a JSON line of ``--log`` (type, task, status, objective in N m, its time
and the evolutions' time in s, the design); ``--summarise LOG`` writes the summary from such a log without
solving. Writes ``results/evolutions.json`` and ``results/evolutions.md``: per row the value before and K's,
how many rows are better, worse and the same (relative 1e-6), and each type's median and worst row time.

Run: ``python -m benchmarks.evolutions [--evolutions 4] [--processes 2] [--log rows.jsonl]`` (repository root;
about an hour on two cores at K = 4).
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import statistics
import sys
import time
from pathlib import Path

from benchmarks.report import RESULTS, save
from benchmarks.tasks import LOADS, MASSES, OMEGA2, SEED, tasks

TYPES = ("coupler-slider", "crank-rocker-slider", "drag-link-slider")
SAME = 1e-6  # relative: rows this close are the same
N_TASKS = 12


def rows(part: int, parts: int, evolutions: int, log: str | None) -> list[dict]:
    """The rows of the tasks i with i mod parts == part, solved with ``Solver(evolutions=evolutions)``."""
    from qropt import Solver
    from qropt.studies._design import type_problem

    solver, out = Solver(evolutions=evolutions), []
    for i, (tr, stroke) in enumerate(tasks(N_TASKS)):
        if i % parts != part:
            continue
        for kind in TYPES:
            p = type_problem(kind, tr, stroke, objective="min_peak_torque", masses=MASSES, loads=LOADS, omega2=OMEGA2)
            t0 = time.perf_counter()
            r = solver.solve(p)
            row = {
                "k": evolutions,
                "i": i,
                "type": kind,
                "tr": tr,
                "stroke": stroke,
                "status": r.status,
                "obj": r.objective,
                "s": round(time.perf_counter() - t0, 1),
                "t_evo": round(r.stats.get("t_evolution", 0.0), 1),
                "params": dict(r.params) if r.params else None,
            }
            out.append(row)
            print(json.dumps(row), flush=True)
            if log:
                with open(log, "a") as f:
                    f.write(json.dumps(row) + "\n")
    return out


def summary(found: list[dict], before: dict) -> dict:
    """Each row against its value in ``before`` (``results/tasks_workers.json``'s layout)."""
    tasks_ = [tuple(t) for t in before["tasks"]]
    values = before["results"]["min_peak_torque"]["types"]
    table, count = [], {"better": 0, "worse": 0, "same": 0}
    for r in sorted(found, key=lambda r: (r["i"], TYPES.index(r["type"]))):
        old = values[r["type"]]["objective"][tasks_.index((r["tr"], r["stroke"]))]
        now = r["obj"]
        if old is None or now is None:
            change = "better" if old is None and now is not None else "worse" if now is None else "same"
        else:
            change = "better" if now < old * (1 - SAME) else "worse" if now > old * (1 + SAME) else "same"
        count[change] += 1
        table.append({**{k: r[k] for k in ("type", "tr", "stroke", "status", "s")}, "before": old, "now": now})
        table[-1]["change"] = change
    times = {}
    for kind in TYPES:
        s = [r["s"] for r in found if r["type"] == kind]
        d = values[kind]
        times[kind] = {"median_s": statistics.median(s), "worst_s": max(s)} if s else {}
        times[kind] |= {"before_median_s": d["median_s"], "before_worst_s": d["worst_s"]}
    return {"evolutions": sorted({r["k"] for r in found}), "counts": count, "rows": table, "times": times}


def markdown(s: dict) -> str:
    k = ", ".join(str(x) for x in s["evolutions"])
    lines = [
        f"The four-bar-driven rows by `min_peak_torque` with `Solver(evolutions={k})` against the rows of "
        f"`results/tasks_workers.json`: {s['counts']['better']} better, {s['counts']['worse']} worse, "
        f"{s['counts']['same']} the same (relative {SAME:g}).",
        "",
        "| type | TR | stroke [m] | before [N m] | now [N m] | status | row [s] |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in s["rows"]:
        mark = {"better": " (better)", "worse": " (worse)", "same": ""}[r["change"]]
        d = "none" if r["before"] is None else f"{r['before']:.6g}"
        n = "none" if r["now"] is None else f"{r['now']:.6g}"
        lines.append(
            f"| {r['type']} | {r['tr']:g} | {r['stroke']:g} | {d} | {n}{mark} | {r['status']} | {r['s']:.1f} |"
        )
    lines += ["", "| type | row median / worst [s] | tasks_workers.json's (another run) [s] |", "|---|---|---|"]
    for kind, t in s["times"].items():
        lines.append(
            f"| {kind} | {t['median_s']:.1f} / {t['worst_s']:.1f} | "
            f"{t['before_median_s']:.1f} / {t['before_worst_s']:.1f} |"
        )
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--evolutions", type=int, default=4)
    ap.add_argument("--processes", type=int, default=2)
    ap.add_argument("--log", help="append each finished row to this file (JSON lines)")
    ap.add_argument("--summarise", nargs="+", metavar="LOG", help="the summary of logged rows, without solving")
    args = ap.parse_args(argv)
    if args.summarise:
        found = [json.loads(line) for p in args.summarise for line in Path(p).read_text().splitlines() if line]
    else:
        n = max(1, args.processes)
        with multiprocessing.get_context("spawn").Pool(n) as pool:
            parts = pool.starmap(rows, [(i, n, args.evolutions, args.log) for i in range(n)])
        found = [r for part in parts for r in part]
    default = json.loads((RESULTS / "tasks_workers.json").read_text())
    if default.get("seed") != SEED:
        sys.exit("results/tasks_workers.json holds other tasks")
    s = summary(found, default)
    table = markdown(s)
    print(table)
    save("evolutions.json", s)
    (RESULTS / "evolutions.md").write_text(table)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
