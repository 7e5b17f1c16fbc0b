"""The benchmark suite: every problem in problems/ by every method, against each problem's oracle.

Run: ``python -m benchmarks [--problems GLOB] [--methods ...] [--repeat K] [--out DIR]`` (or ``qropt bench``
from the repository root). Writes results.md, results.csv and results.json to DIR (default
benchmarks/results/) with the machine, versions and date, and prints the summary.
"""

from __future__ import annotations

import argparse
import csv
import fnmatch
import importlib
import json
import math
import statistics
import sys
import time
from pathlib import Path

from tqdm import tqdm

from benchmarks.methods import METHODS, violation
from benchmarks.report import environment
from qropt import solve

ROOT = Path(__file__).resolve().parent.parent
FEASIBLE = 1e-6  # largest accepted violation of a target (relative for lengths) or condition


def problem_names(pattern="*"):
    names = sorted(p.stem for p in (ROOT / "problems").glob("*.py") if not p.stem.startswith("_"))
    return [n for n in names if fnmatch.fnmatch(n, pattern) and hasattr(_module(n), "oracle")]


def _module(name):
    return importlib.import_module(f"problems.{name}")


def evaluate(problem, values):
    """(objective, violation) of a returned design by exact analysis; (None, inf) if it does not work."""
    from problems import _oracles as oracles

    if values is None:
        return None, math.inf
    s = oracles.score(
        problem.replace(conditions={k: v for k, v in problem.conditions.items() if k != "gamma_min"}), values
    )
    if s is None:
        return None, math.inf
    return s[0], violation(problem, s[1])


def warm_up(problem, seed):
    """Build the NLPs of a problem's structures once, untimed: every method then solves on built formulations
    (the default Solver's, shared by qropt and the scipy methods), so the times compare solving, not compiling."""
    for use_analytic in (True, False):
        solve(problem, seed=seed, use_analytic=use_analytic)


def run(names, methods, repeat=1, seed=0, progress=True):
    """Rows (one per problem and method) and oracles."""
    rows, oracles = [], {}
    bar = tqdm(total=len(names) * len(methods), disable=not progress or not sys.stderr.isatty(), unit="run")
    for name in names:
        mod = _module(name)
        problem, spec = mod.build(), mod.ORACLE
        t = time.perf_counter()
        ref = mod.oracle()
        oracles[name] = {**spec, "objective": ref["objective"], "seconds": time.perf_counter() - t}
        warm_up(problem, seed)
        for method in methods:
            times, out = [], None
            for _ in range(repeat):
                t = time.perf_counter()
                try:
                    out = METHODS[method](problem, seed)
                except Exception as e:  # noqa: BLE001 - a method that crashes is a result, reported as such
                    out = {"values": None, "nfev": None, "message": f"error: {type(e).__name__}: {e}"[:120]}
                times.append(time.perf_counter() - t)
            bar.set_description(f"{name} {method}")
            bar.update()
            rows.append(_row(name, method, problem, spec, ref, out, statistics.median(times)))
    bar.close()
    return rows, oracles


def _row(name, method, problem, spec, ref, out, seconds):
    if out["message"] in ("not installed", "not applicable"):
        return {
            "problem": name,
            "method": method,
            "status": out["message"],
            "objective": None,
            "oracle": ref["objective"],
            "error": None,
            "violation": None,
            "seconds": None,
            "nfev": None,
            "success": None,
        }
    obj, viol = evaluate(problem, out["values"])
    err = None if obj is None else abs(obj - ref["objective"]) / max(1.0, abs(ref["objective"]))
    better = obj is not None and (
        obj > ref["objective"] if problem.objective == "max_gamma_min" else obj < ref["objective"]
    )
    success = obj is not None and viol <= FEASIBLE and (err <= spec["tolerance"] or better)
    status = (
        "meets oracle"
        if success
        else ("no design" if obj is None else "infeasible design" if viol > FEASIBLE else "worse than oracle")
    )
    return {
        "problem": name,
        "method": method,
        "status": status,
        "objective": obj,
        "oracle": ref["objective"],
        "error": err,
        "violation": viol,
        "seconds": seconds,
        "nfev": out["nfev"],
        "success": success,
    }


def summary(rows, methods):
    """Per method: success rate over the problems it applies to, median time, median time ratio to qropt."""
    base = {r["problem"]: r["seconds"] for r in rows if r["method"] == "qropt" and r["seconds"]}
    out = []
    for m in methods:
        mine = [r for r in rows if r["method"] == m and r["success"] is not None]
        if not mine:
            status = next((r["status"] for r in rows if r["method"] == m), "not run")
            out.append(
                {"method": m, "applies": 0, "success_rate": None, "median_seconds": None, "ratio": None, "note": status}
            )
            continue
        ratios = [r["seconds"] / base[r["problem"]] for r in mine if r["problem"] in base]
        out.append(
            {
                "method": m,
                "applies": len(mine),
                "success_rate": sum(r["success"] for r in mine) / len(mine),
                "median_seconds": statistics.median(r["seconds"] for r in mine),
                "ratio": statistics.median(ratios) if ratios else None,
                "note": "",
            }
        )
    return out


def _fmt(v, spec=".3g"):
    return "" if v is None else (format(v, spec) if isinstance(v, float) else str(v))


def markdown(rows, summ, meta):
    lines = [
        f"# qropt benchmark ({meta['date']})",
        "",
        f"{meta['machine']}; Python {meta['python']}; qropt {meta['versions']['qropt']}, casadi "
        f"{meta['versions']['casadi']}, scipy {meta['versions']['scipy']}, numpy {meta['versions']['numpy']}, "
        f"pylinkage {meta['versions']['pylinkage']}; repeat {meta['repeat']}, seed {meta['seed']}.",
        "",
        "## Summary",
        "",
        "| method | problems | meets oracle | median time [s] | median time / qropt |",
        "|---|---|---|---|---|",
    ]
    for s in summ:
        rate = "" if s["success_rate"] is None else f"{100 * s['success_rate']:.0f}%"
        lines.append(
            f"| {s['method']} | {s['applies']} | {rate or s['note']} | {_fmt(s['median_seconds'])} | "
            f"{_fmt(s['ratio'], '.2f')} |"
        )
    lines += [
        "",
        "## Every problem and method",
        "",
        "| problem | method | status | objective | oracle | error | violation | time [s] | evaluations |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['problem']} | {r['method']} | {r['status']} | {_fmt(r['objective'], '.10g')} | "
            f"{_fmt(r['oracle'], '.10g')} | {_fmt(r['error'], '.1e')} | {_fmt(r['violation'], '.1e')} | "
            f"{_fmt(r['seconds'], '.3f')} | {_fmt(r['nfev'])} |"
        )
    return "\n".join(lines) + "\n"


def main(argv=None):
    ap = argparse.ArgumentParser(prog="qropt bench", description=__doc__.splitlines()[0])
    ap.add_argument("--problems", default="*", help="glob over problem names (default: all)")
    ap.add_argument("--methods", nargs="+", default=list(METHODS), choices=list(METHODS))
    ap.add_argument("--repeat", type=int, default=1, help="repeats per problem and method (median time)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", default=str(ROOT / "benchmarks" / "results"), help="directory for the tables")
    args = ap.parse_args(argv)
    names = problem_names(args.problems)
    if not names:
        ap.error(f"no problem matches {args.problems!r}")
    t0 = time.perf_counter()
    rows, oracles = run(names, args.methods, args.repeat, args.seed)
    summ = summary(rows, args.methods)
    meta = {**environment(), "repeat": args.repeat, "seed": args.seed, "seconds": time.perf_counter() - t0}
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "results.md").write_text(markdown(rows, summ, meta))
    with open(out / "results.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    (out / "results.json").write_text(
        json.dumps({"meta": meta, "summary": summ, "oracles": oracles, "rows": rows}, indent=2, default=float) + "\n"
    )
    print(markdown([], summ, meta).split("## Every problem")[0].strip())
    print(f"\n{len(names)} problems, {len(args.methods)} methods in {meta['seconds']:.0f} s; tables in {out}")
    return 0 if all(r["success"] for r in rows if r["method"] == "qropt") else 1


if __name__ == "__main__":
    sys.exit(main())
