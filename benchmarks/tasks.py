"""``design()`` over many tasks, not one: a fixed, seeded set of (TR, stroke) spread over TR 1.1-3 and strokes
0.05-5 m (a scrambled Halton sequence, log-uniform in the stroke), every design row, each objective asked.

For each objective the first task is run twice: its first call is the cold time (the NLPs built), and every task
after it is timed warm (the same structures, new numbers). Reported per type and objective: the median and the
worst row time, the statuses, and the median and worst ``design()`` time over the tasks. Writes
``results/tasks.json`` and ``results/tasks.md`` after each objective (a stopped run keeps the objectives done).

Run: ``python -m benchmarks.tasks [--tasks 12] [--objectives max_gamma_min min_peak_accel] [--dynamic]
[--workers K] [--gamma-min DEG] [--settings NAME=VALUE ...] [--ipopt NAME=JSON ...]`` (repository root).
``--dynamic`` adds ``min_peak_torque`` with the default mass model below; ``--workers`` solves each task's rows
in K worker processes (``design(..., workers=K)``; results/tasks_workers.json); ``--gamma-min`` bounds every
row's transmission angle (results/tasks_gamma<DEG>.json); ``--settings`` changes the search's numbers
(``qropt.synthesis.search.Settings``, e.g. ``relifts=1``: results/tasks_gamma30_relifts1.json); ``--ipopt``
gives the Solver IPOPT options (CasADi's ``nlpsol`` options, each value JSON, e.g.
``oracle_options={"cse": true}``).
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import time

from scipy.stats import qmc

import qropt
from benchmarks.report import RESULTS, save
from qropt import Solver
from qropt.studies._design import TYPES, design
from qropt.synthesis import criteria
from qropt.synthesis.settings import DEFAULT, Settings

SEED = 20261124
MASSES = qropt.Masses.steel(4e-4, ram=20.0)  # steel links of 4 cm^2 (3.14 kg/m), a 20 kg ram
LOADS = qropt.Loads(1000.0)
OMEGA2 = 10.0


def tasks(n: int, seed: int = SEED) -> list[tuple[float, float]]:
    """n tasks (TR, stroke m): TR uniform in [1.1, 3], stroke log-uniform in [0.05, 5], from a scrambled Halton
    sequence (spread over the square, the same every run)."""
    u = qmc.Halton(d=2, scramble=True, seed=seed).random(n)
    return [(round(float(1.1 + 1.9 * a), 3), round(float(0.05 * 100**b), 4)) for a, b in u]


def run_objective(
    objective: str,
    task_list,
    dynamic: bool,
    workers: int | None = None,
    conditions=None,
    settings=None,
    ipopt_options=None,
) -> dict:
    solver = Solver(settings=settings, ipopt_options=ipopt_options)
    kw = {"masses": MASSES, "loads": LOADS, "omega2": OMEGA2} if dynamic else {}
    kw["workers"], kw["conditions"] = workers, conditions
    tr, s = task_list[0]
    t = time.perf_counter()
    design(tr, s, objective=objective, solver=solver, **kw)
    cold = time.perf_counter() - t
    per_task, rows = [], {k: [] for k in TYPES}
    for tr, s in task_list:
        t = time.perf_counter()
        cmp = design(tr, s, objective=objective, solver=solver, **kw)
        per_task.append(time.perf_counter() - t)
        for r in cmp.rows:
            rows[r.type].append((r.result.status, r.result.stats.get("t_total", 0.0), tr, s, r.result.objective))
        print(f"  {objective:16s} TR {tr:5.3f} stroke {s:7.4f} m: {per_task[-1]:6.2f} s", flush=True)
    types = {}
    for k, v in rows.items():
        times = [x[1] for x in v]
        worst = max(v, key=lambda x: x[1])
        statuses = {st: sum(1 for x in v if x[0] == st) for st in sorted({x[0] for x in v})}
        types[k] = {
            "median_s": statistics.median(times),
            "worst_s": worst[1],
            "worst_task": [worst[2], worst[3]],
            "statuses": statuses,
            "objective": [x[4] for x in v],  # per task, in the task list's order (None: no design)
        }
    return {
        "cold_first_call_s": cold,
        "design_median_s": statistics.median(per_task),
        "design_worst_s": max(per_task),
        "design_s": per_task,
        "types": types,
    }


def markdown(results: dict, n: int) -> str:
    lines = [
        f"`design()` over {n} tasks (TR 1.1-3, stroke 0.05-5 m; warm: the NLPs built by a first call, whose time "
        "is the cold one):",
        "",
        "| objective | design median [s] | design worst [s] | cold first call [s] |",
        "|---|---|---|---|",
    ]
    for obj, r in results.items():
        lines.append(
            f"| {obj} | {r['design_median_s']:.2f} | {r['design_worst_s']:.2f} | {r['cold_first_call_s']:.2f} |"
        )
    lines += ["", "| type | " + " | ".join(f"{o} median / worst [s]" for o in results) + " |"]
    lines.append("|---|" + "---|" * len(results))
    for k in TYPES:
        cells = []
        for r in results.values():
            t = r["types"][k]
            bad = sum(v for st, v in t["statuses"].items() if st in ("failed",))
            cells.append(f"{t['median_s']:.2f} / {t['worst_s']:.2f}" + (f" ({bad} failed)" if bad else ""))
        lines.append(f"| {k} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tasks", type=int, default=12)
    ap.add_argument(
        "--objectives",
        nargs="+",
        default=["max_gamma_min", "min_peak_accel"],
        choices=[o for o in criteria.objectives() if o],
    )
    ap.add_argument("--dynamic", action="store_true", help="also min_peak_torque (steel links, 20 kg ram, 1000 N)")
    ap.add_argument("--workers", type=int, help="solve each task's rows in this many worker processes")
    ap.add_argument("--gamma-min", type=float, help="a transmission bound (deg) for every row")
    ap.add_argument(
        "--settings", nargs="+", default=[], metavar="NAME=VALUE", help="the search's numbers (qropt Settings)"
    )
    ap.add_argument("--ipopt", nargs="+", default=[], metavar="NAME=JSON", help="IPOPT options (CasADi nlpsol's)")
    ap.add_argument("--name", help="the results' file name (default: tasks, with the workers, bound and settings)")
    args = ap.parse_args(argv)
    ipopt_options = _ipopt(args.ipopt)
    bound = None if args.gamma_min is None else {"gamma_min": math.radians(args.gamma_min)}
    settings = _settings(args.settings)
    task_list = tasks(args.tasks)
    print(f"{len(task_list)} tasks: " + ", ".join(f"({a:g}, {b:g})" for a, b in task_list))
    name = "tasks" if args.workers is None else "tasks_workers"
    name += "" if args.gamma_min is None else f"_gamma{args.gamma_min:g}"
    name += "".join(f"_{a.replace('=', '')}" for a in args.settings)
    name = args.name or name
    saved = {"tasks": task_list, "seed": SEED, "workers": args.workers, "gamma_min_deg": args.gamma_min}
    saved["settings"] = {k: v for k, v in settings.to_dict().items() if v != getattr(DEFAULT, k)}
    saved["ipopt_options"] = ipopt_options
    objectives = list(args.objectives)
    if args.dynamic and "min_peak_torque" not in objectives:
        objectives.append("min_peak_torque")
    results = {}
    for obj in objectives:  # a dynamic objective runs with the default masses; the files hold each one done
        dynamic = criteria.of(obj).needs_masses
        results[obj] = run_objective(obj, task_list, dynamic, args.workers, bound, settings, ipopt_options)
        save(f"{name}.json", {**saved, "results": results})
        (RESULTS / f"{name}.md").write_text(markdown(results, len(task_list)))
    print(markdown(results, len(task_list)))
    return 0


def _settings(pairs) -> Settings:
    """Settings from NAME=VALUE pairs (each value as the default's type)."""
    defaults, given = DEFAULT.to_dict(), {}
    for pair in pairs:
        name, _, value = pair.partition("=")
        if name not in defaults or not value:
            raise SystemExit(f"--settings: {pair!r} is not NAME=VALUE of a Settings field")
        default = defaults[name]
        try:
            given[name] = type(default)(value)
        except ValueError:
            kind = "an integer" if isinstance(default, int) else "a number"
            raise SystemExit(f"--settings: {name} is {kind}, got {value!r}") from None
    try:
        return Settings(**given)
    except qropt.ProblemError as e:
        raise SystemExit(f"--settings: {e}") from None


def _ipopt(pairs) -> dict:
    """IPOPT options from NAME=JSON pairs."""
    given = {}
    for pair in pairs:
        name, _, value = pair.partition("=")
        try:
            given[name] = json.loads(value)
        except json.JSONDecodeError:
            raise SystemExit(f"--ipopt: {pair!r} is not NAME=JSON") from None
        if not name:
            raise SystemExit(f"--ipopt: {pair!r} is not NAME=JSON")
    return given


if __name__ == "__main__":
    raise SystemExit(main())
