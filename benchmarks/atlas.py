"""Builds the atlas (``qropt/synthesis/atlas.json``): for every ``design`` row and each objective in OBJECTIVES,
the best distinct certified designs at time-ratio nodes, lengths in strokes (a solve uses them where the closed
forms neither enumerate nor walk every solution).

At each node the row's problem at stroke 1 is solved without the atlas by a multi-start of ``--starts`` Sobol
points per two free parameters (the default solve's is 8), closed forms and grid shapes first. Then each node is
solved again from its neighbours' designs (continuation), until no node improves: a design found at one TR is
carried to the next; a node still without a design is walked to from the nearest with one, TR in small steps.
Last (``fill``), each node is solved again from the row's other objectives' designs there (a design by one
objective starts a solve by another) and, with ``--shapes N``, from the best of N random shapes within 5 % of
its TR (the grid analysis of ``benchmarks.search``), the walk is tried again, and the continuation run once more;
its solves have four times IPOPT's iteration limit (a patient solve's). Each node keeps its KEEP best distinct
designs. Rows run in ``--jobs`` processes; ``--fill`` runs only the last step, on the atlas as it is.

Run: ``python -m benchmarks.atlas [--starts 24] [--jobs 2]`` (repository root; about 35 min on 2 cores);
``python -m benchmarks.atlas --fill [--rows coupler-slider] [--shapes 1000000]`` (about 5 min without shapes;
10^6 shapes a node add about 10 min a row).
"""

from __future__ import annotations

import argparse
import json
import time
from concurrent.futures import ProcessPoolExecutor

import numpy as np

from benchmarks import search
from qropt import Solver
from qropt.studies._design import TYPES, type_problem
from qropt.synthesis import atlas, criteria, starts
from qropt.synthesis.backends import Ipopt
from qropt.synthesis.result import SOLUTION_PRESENT

NODES = tuple(round(float(x), 3) for x in np.arange(1.05, 3.55 + 1e-9, 0.1))
OBJECTIVES = ("max_gamma_min", "min_peak_accel")
KEEP = 2  # designs kept per node
PASSES = 3  # continuation passes at most
SHAPE_WINDOW = 0.05  # random shapes within this (relative) of a node's TR start local solves there (``--shapes``)
POLISH = 16  # ... the best this many of them by the objective's grid value


HEAVY = ("coupler-slider", "drag-link-slider", "crank-rocker-slider")  # built first: the longest jobs


def _designs(problem, r) -> list[dict]:
    """A Result's distinct certified designs, best first: free values (lengths in strokes at stroke 1), branch,
    objective."""
    out = []
    for x in (r, *r.local_optima[1:]) if r.local_optima else (r,):
        if x.status not in SOLUTION_PRESENT or x.status == "feasible" or x.objective is None:
            continue
        params = {k: min(max(float(x.params[k]), lo), hi) for k, (lo, hi) in problem.free.items()}  # rounding
        branch = {k: float(x.params[k]) for k in problem.branches}
        out.append({"params": params, "branch": branch, "value": float(x.objective)})
    return out


def _better(problem, a: list, b: list) -> bool:
    """Whether the designs a have a better best than b."""
    if not a:
        return False
    if not b:
        return True
    sign = criteria.sense(problem.objective)
    return sign * (a[0]["value"] - b[0]["value"]) > 1e-9 * max(1.0, abs(b[0]["value"]))


def _merge(problem, *lists) -> list:
    """The KEEP best distinct designs of several lists (apart by 1e-6 in some value)."""
    sign = -criteria.sense(problem.objective)  # best first
    out = []
    for d in sorted((d for ds in lists for d in ds), key=lambda d: sign * d["value"]):
        v = np.array(list(d["params"].values()))
        if all(d["branch"] != o["branch"] or np.max(np.abs(v - list(o["params"].values()))) > 1e-6 for o in out):
            out.append(d)
    return out[:KEEP]


def _walk(solver, problem, designs, step: float = 0.01) -> list:
    """The designs at a node without one, from the nearest nodes with designs on either side, its time ratio moved
    toward the node's in steps of ``step``, each solve from the last design ([] where a step fails)."""
    tr = problem.targets["time_ratio"]
    found = []
    for side in (-1, 1):
        js = [j for j, d in enumerate(designs) if d and (NODES[j] - tr) * side > 0]
        if not js:
            continue
        j = min(js, key=lambda j: abs(NODES[j] - tr))
        last = [d["params"] for d in designs[j]]
        n = max(1, round(abs(NODES[j] - tr) / step))
        for t in np.linspace(NODES[j], tr, n + 1)[1:]:
            r = solver.solve(
                problem, targets={"time_ratio": float(t)}, starts_n=0, use_analytic=False, extra_starts=last
            )
            if r.status not in SOLUTION_PRESENT:
                break
            last = [{k: float(r.params[k]) for k in problem.free}]
        else:
            found = _merge(problem, found, _designs(problem, r))
    return found


def _from(solver, problem, seeds: list, kept: list) -> tuple[list, bool]:
    """(kept merged with the designs of a solve of ``problem`` from the designs ``seeds``, whether that solve
    found a better best)."""
    r = solver.solve(problem, starts_n=0, use_analytic=False, extra_starts=[d["params"] for d in seeds])
    found = _designs(problem, r)
    return _merge(problem, kept, found), _better(problem, found, kept)


def _walked(solver, problems, designs) -> tuple[list, int]:
    """(designs with each node still without one walked to (``_walk``), how many nodes that filled)."""
    designs, filled = list(designs), 0
    for i, p in enumerate(problems):
        if not designs[i]:
            designs[i] = _walk(solver, p, designs)
            filled += bool(designs[i])
    return designs, filled


def _continued(solver, problems, designs) -> list:
    """Each node solved again from its neighbours' designs, pass after pass until no node improves (PASSES at
    most), its KEEP best kept."""
    designs = list(designs)
    for _ in range(PASSES):
        changed = False
        for i, p in enumerate(problems):
            near = [d for j in (i - 1, i + 1) if 0 <= j < len(NODES) for d in designs[j]]
            if near:
                designs[i], improved = _from(solver, p, near, designs[i])
                changed |= improved
        if not changed:
            break
    return designs


def build_row(kind: str, objective: str, starts_n: int) -> dict:
    t0 = time.perf_counter()
    solver = Solver(atlas=False, starts_n=starts_n)
    problems = [type_problem(kind, tr, 1.0, objective=objective) for tr in NODES]
    designs = [_designs(p, solver.solve(p)) for p in problems]
    first = [len(d) > 0 for d in designs]
    designs, walked = _walked(solver, problems, _continued(solver, problems, designs))
    print(
        f"{kind:20s} {objective:15s} {sum(map(bool, designs))}/{len(NODES)} nodes "
        f"({sum(first)} by the search alone, {walked} walked to) in {time.perf_counter() - t0:.0f} s",
        flush=True,
    )
    return {
        "signature": atlas.signature(problems[0]),
        "row": kind,
        "objective": objective,
        "starts": solver.starts_n * starts.grown(1, problems[0], starts.plan(problems[0])),
        "nodes": list(NODES),
        "designs": designs,
    }


def _shaped(solver, problem, kept: list, n: int, seed: int) -> tuple[list, bool]:
    """(kept merged with the designs of a solve from the POLISH best of n random shapes within SHAPE_WINDOW of the
    node's TR (``benchmarks.search.shapes``: the grid analysis, no solver), whether that solve found a better
    best)."""
    found, _, _ = search.shapes(problem, n, seed, window=SHAPE_WINDOW)
    if not found:
        return kept, False
    return _from(solver, problem, [{"params": v} for v in found[:POLISH]], kept)


def fill_row(entry: dict, others: list, shapes_n: int = 0) -> dict:
    """An entry improved where the row's other objectives' designs at a node (``others``: per node, a list) give a
    better one, and (``shapes_n``) where the best of that many random shapes near the node's TR does (``_shaped``),
    its nodes still without a design walked to (``_walk``) from the nearest nodes with designs, and the whole
    continued once more (``_continued``)."""
    t0, kind, objective = time.perf_counter(), entry["row"], entry["objective"]
    # on the patient backend (its iteration limit): from a neighbour's design the default's can run out (the
    # coupler slider's gamma_min at TR 2.25 went from 1.0827 to 1.1752 rad with it)
    solver, designs = Solver(atlas=False, backend=Ipopt().patient()), list(entry["designs"])
    problems = [type_problem(kind, tr, 1.0, objective=objective) for tr in NODES]
    empty = [i for i, d in enumerate(designs) if not d]
    better = 0
    for i, seeds in enumerate(others):
        if seeds:
            designs[i], improved = _from(solver, problems[i], seeds, designs[i])
            better += improved
    for i, p in enumerate(problems) if shapes_n else ():
        designs[i], improved = _shaped(solver, p, designs[i], shapes_n, seed=i)
        better += improved
    designs, _ = _walked(solver, problems, designs)
    before = designs
    designs = _continued(solver, problems, designs)
    better += sum(_better(p, d, b) for p, d, b in zip(problems, designs, before, strict=True))
    got = sum(bool(designs[i]) for i in empty)
    print(
        f"{kind:20s} {objective:15s} {better} nodes improved from the other objectives' and the neighbours' "
        f"designs; {got} of {len(empty)} empty nodes filled in {time.perf_counter() - t0:.0f} s",
        flush=True,
    )
    out = {**entry, "designs": designs}
    if shapes_n:  # the atlas's claim names the largest shape search its nodes had
        out["shapes"] = max(shapes_n, entry.get("shapes", 0))
    return out


def fill(data: dict, rows, jobs: int, shapes_n: int = 0) -> dict:
    """The atlas with the entries of ``rows`` improved (``fill_row``)."""
    todo = [e for e in data["entries"] if e["row"] in rows]
    others = [
        [
            [d for o in data["entries"] if o["row"] == e["row"] and o is not e for d in o["designs"][i]]
            for i in range(len(NODES))
        ]
        for e in todo
    ]
    with ProcessPoolExecutor(jobs) as pool:
        filled = {(e["row"], e["objective"]): e for e in pool.map(fill_row, todo, others, [shapes_n] * len(todo))}
    return {**data, "entries": [filled.get((e["row"], e["objective"]), e) for e in data["entries"]]}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--starts", type=int, default=24)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--rows", nargs="+", default=list(TYPES), help="rebuild these rows only (the others kept)")
    ap.add_argument("--fill", action="store_true", help="only improve the atlas's nodes (see fill_row)")
    ap.add_argument("--shapes", type=int, default=0, help="in the last step, also polish the best of this many shapes")
    args = ap.parse_args(argv)
    if args.fill:
        data = json.loads(atlas.PATH.read_text())
    else:
        order = [*(k for k in HEAVY if k in args.rows), *(k for k in args.rows if k not in HEAVY)]
        jobs = [(k, o) for k in order for o in reversed(OBJECTIVES)]
        with ProcessPoolExecutor(args.jobs) as pool:
            entries = list(pool.map(build_row, *zip(*jobs, strict=True), [args.starts] * len(jobs)))
        if atlas.PATH.exists():  # the rows not rebuilt, as they were
            kept = [e for e in json.loads(atlas.PATH.read_text())["entries"] if e["row"] not in args.rows]
            entries = sorted(kept + entries, key=lambda e: (list(TYPES).index(e["row"]), e["objective"]))
        data = {"nodes": list(NODES), "keep": KEEP, "entries": entries}
        atlas.PATH.write_text(json.dumps(data, indent=1) + "\n")  # kept, whatever the last step does
    data = fill(data, args.rows, args.jobs, args.shapes)
    atlas.PATH.write_text(json.dumps(data, indent=1) + "\n")
    print(f"wrote {atlas.PATH}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
