"""Each strategy's gain against its cost: ``benchmarks.tasks``' tasks solved for every design row by the default
pipeline and by the pipeline with one strategy left out in turn, in the same process.

Per left-out strategy: the rows it changes (better, worse, newly certified or lost without it, relative 1e-6),
and the time it costs (the rows' total with it, less without it); and, from the default runs, the seconds each
strategy takes (``Result.stats['t_strategies']``) summed over the rows. A strategy that changes no row costs only
time. Writes ``results/strategies.json`` and ``results/strategies.md``.

Run: ``python -m benchmarks.strategies [--tasks 12] [--objectives max_gamma_min min_peak_torque]
[--leave-out evolution guard ...] [--types whitworth ...] [--evolutions K] [--gamma-min DEG] [--name NAME]``
(repository root; ``--types``: those rows only; ``--evolutions``: every Solver runs K evolutions where the
evolution applies; ``--gamma-min``: every row under that transmission bound).
By ``min_peak_torque`` the rows use ``benchmarks.tasks``' mass model, loads and speed; a run of the 12 tasks by
it takes hours on two cores.
"""

from __future__ import annotations

import argparse
import math
import time

from benchmarks.report import RESULTS, save
from benchmarks.tasks import LOADS, MASSES, OMEGA2, tasks

SAME = 1e-6  # relative: values this close are the same
DYNAMIC = {"masses": MASSES, "loads": LOADS, "omega2": OMEGA2}


def pipelines(names: list[str]) -> dict:
    """{'default': the default pipeline, name: it without the strategy of that name} (the starts phase's
    strategies left out inside the phase)."""
    from qropt.synthesis import search

    def without(stages, name):
        out = []
        for s in stages:
            if isinstance(s, search.Phase):
                out.append(search.Phase(tuple(without(s.stages, name))))
            elif s.name != name:
                out.append(s)
        return out

    known = {s.name for s in (*search.DEFAULT, *search.STARTS)}
    unknown = sorted(set(names) - known)
    if unknown:
        raise SystemExit(f"unknown strategies {unknown}; the default pipeline's are {sorted(known)}")
    return {"default": list(search.DEFAULT), **{n: without(search.DEFAULT, n) for n in names}}


def run(
    n_tasks: int, objectives: list[str], names: list[str], types=None, evolutions=None, gamma_min=None
) -> list[dict]:
    """One record per (pipeline, objective, task, row): status, objective value, seconds, strategy seconds;
    gamma_min: a transmission bound (deg) for every row."""
    from qropt import Solver
    from qropt.studies._design import design
    from qropt.synthesis import criteria

    out = []
    for label, pipeline in pipelines(names).items():
        solver = Solver(pipeline=pipeline, evolutions=evolutions)
        for objective in objectives:
            kw = {} if criteria.of(objective).kinematic else dict(DYNAMIC)
            if gamma_min is not None:
                kw["conditions"] = {"gamma_min": math.radians(gamma_min)}
            for i, (tr, stroke) in enumerate(tasks(n_tasks)):
                t = time.perf_counter()
                cmp = design(tr, stroke, objective=objective, solver=solver, types=types, **kw)
                print(f"  {label:28s} {objective:16s} task {i:2d}: {time.perf_counter() - t:7.2f} s", flush=True)
                for r in cmp.rows:
                    res = r.result
                    out.append(
                        {
                            "pipeline": label,
                            "objective": objective,
                            "task": i,
                            "type": r.type,
                            "status": res.status,
                            "value": res.objective,
                            "s": res.stats.get("t_total", 0.0),
                            "strategies": res.stats.get("t_strategies", {}),
                        }
                    )
    return out


def _certified(row) -> bool:
    return row["status"] in ("optimal", "acceptable", "feasible") and row["value"] is not None


def summary(records: list[dict]) -> dict:
    """Per left-out strategy: rows better, worse, gained (certified only without it), lost (certified only with
    it), the same, and the seconds it costs (with it less without it); per strategy, its seconds in the default
    runs."""
    from qropt.synthesis import criteria

    default = {(r["objective"], r["task"], r["type"]): r for r in records if r["pipeline"] == "default"}
    share: dict = {}
    for r in default.values():
        for name, s in r["strategies"].items():
            share[name] = share.get(name, 0.0) + s
    out = {}
    for label in dict.fromkeys(r["pipeline"] for r in records if r["pipeline"] != "default"):
        count = {"better": 0, "worse": 0, "gained": 0, "lost": 0, "same": 0}
        saved = 0.0
        for r in (r for r in records if r["pipeline"] == label):
            d = default[(r["objective"], r["task"], r["type"])]
            saved += d["s"] - r["s"]
            a, b = _certified(d), _certified(r)
            if a != b:
                count["lost" if a else "gained"] += 1  # without the strategy
            elif not a or abs(r["value"] - d["value"]) <= SAME * max(1.0, abs(d["value"])):
                count["same"] += 1
            else:
                better = criteria.sense(r["objective"]) * (r["value"] - d["value"]) > 0
                count["better" if better else "worse"] += 1  # without the strategy
        out[label] = {**count, "seconds_saved": saved}
    return {"left_out": out, "default_seconds": dict(sorted(share.items(), key=lambda kv: -kv[1]))}


def markdown(s: dict) -> str:
    lines = [
        "Rows changed by leaving one strategy out (without it: better, worse, gained, lost, same), and the "
        "seconds it saves over all rows:",
        "",
        "| left out | better | worse | gained | lost | same | seconds saved |",
        "|---|---|---|---|---|---|---|",
    ]
    for name, c in s["left_out"].items():
        cells = " | ".join(str(c[k]) for k in ("better", "worse", "gained", "lost", "same"))
        lines.append(f"| {name} | {cells} | {c['seconds_saved']:.1f} |")
    lines += ["", "Seconds each strategy took in the default runs (a phase's include its own):", ""]
    lines += ["| strategy | seconds |", "|---|---|"]
    lines += [f"| {k} | {v:.1f} |" for k, v in s["default_seconds"].items()]
    return "\n".join(lines) + "\n"


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tasks", type=int, default=12)
    ap.add_argument("--objectives", nargs="+", default=["max_gamma_min", "min_peak_accel"])
    ap.add_argument(
        "--leave-out",
        nargs="+",
        default=["shape search", "related atlas optima", "atlas", "across a full turn's edge", "least-size tie-break"],
        help="strategy names (search.DEFAULT's), each left out in turn",
    )
    ap.add_argument("--types", nargs="+", default=None, help="these design rows only (default every type)")
    ap.add_argument("--evolutions", type=int, default=None, help="evolutions every Solver runs where they apply")
    ap.add_argument("--gamma-min", type=float, help="a transmission bound (deg) for every row")
    ap.add_argument("--name", default="strategies", help="results/NAME.json and results/NAME.md")
    args = ap.parse_args(argv)
    records = run(args.tasks, args.objectives, args.leave_out, args.types, args.evolutions, args.gamma_min)
    s = summary(records)
    saved = {"tasks": args.tasks, "objectives": args.objectives, "gamma_min_deg": args.gamma_min}
    save(f"{args.name}.json", {**saved, "summary": s, "rows": records})
    (RESULTS / f"{args.name}.md").write_text(markdown(s))
    print(markdown(s))


if __name__ == "__main__":
    main()
