"""Design charts at scale, in one run: the built-in 40 x 19 crank-rocker chart (problems/chart_crank_rocker.py)
in-process, on a 2-worker Dask LocalCluster, and as independent default solves at every cell (the baseline).

Prints cells per second, the speedup of 2 workers over one process, the continuation's gain over independent
solves, and how the chart would scale on a larger cluster (a schedule of the measured tile times);
writes ``results/chart.md`` and ``results/chart.json`` (date, machine, versions, load).

Run: ``python -m benchmarks.chart`` (from the repository root).
"""

from __future__ import annotations

import heapq
import importlib
import logging
import multiprocessing
import os
import statistics
import sys
import time

import dask
from tqdm import tqdm

from benchmarks.report import RESULTS, environment, save
from qropt import Problem, solve
from qropt.studies._chart_run import TILE, chart
from qropt.studies._dask import LOCAL_CONFIG

REPEAT = 3
SAME = ("status", "objective", "params", "method", "why", "source", "jump", "switched")


def makespan(tiles: list, workers: int, per_tile: float) -> float:
    """Longest worker time when tiles (seconds, largest first) go to the worker free first (as Dask does)."""
    free = [0.0] * workers
    for t in sorted(tiles, reverse=True):
        heapq.heapreplace(free, free[0] + t + per_tile)
    return max(free)


class _FromDesign:
    """A solver whose warm solves start IPOPT from the neighbour's design only (no ``continue_from``: the
    continuation before Newton on the neighbour's active set), the baseline of the same run."""

    def __init__(self, solver):
        self.solver = solver

    def solve(self, problem, diagnose=True, **options):
        options.pop("continue_from", None)
        return self.solver.solve(problem, diagnose=diagnose, **options)


def _tiles(args):
    """A plain process solving every ``step``-th tile from the ``k``-th: the in-process chart (step 1, away from
    the clusters' schedulers in the main process) or half of it (step 2: the ceiling for 2 workers, no Dask);
    ``newton`` False: the baseline without continuation by Newton (``_FromDesign``)."""
    specs, k, step, *newton = args
    from qropt import solve
    from qropt.studies._continuation import solve_tile
    from qropt.synthesis.solver import DEFAULT

    solver = DEFAULT if not newton or newton[0] else _FromDesign(DEFAULT)
    solve(Problem.from_dict(specs[0]["problem"]))
    seconds = []
    for s in specs[k::step]:
        t = time.perf_counter()
        solve_tile(s, solver)
        seconds.append(time.perf_counter() - t)
    return seconds


def main() -> None:
    from concurrent.futures import ProcessPoolExecutor

    from distributed import LocalCluster

    problem_file = importlib.import_module("problems.chart_crank_rocker")
    p, x, y = problem_file.build(), problem_file.X, problem_file.Y
    cells = len(x[1]) * len(y[1])
    load0 = os.getloadavg()
    solve(p)  # builds the NLPs of this process once (not timed); workers build their own, timed
    t = time.perf_counter()
    local = chart(p, x, y, workers=2)
    t_local = time.perf_counter() - t
    print(f"scheduler='local', 2 workers (cluster start and the workers' NLP builds included): {t_local:.2f} s")
    heres, befores, warms, ones, plains = [], [], [], [], []
    specs = [
        {
            "problem": p.to_dict(),
            "x": [x[0], list(x[1])],
            "y": [y[0], list(y[1])],
            "block": [i0, min(i0 + TILE[0], len(x[1])), j0, min(j0 + TILE[1], len(y[1]))],
            "check": 10,
        }
        for j0 in range(0, len(y[1]), TILE[1])
        for i0 in range(0, len(x[1]), TILE[0])
    ]
    quiet = {"threads_per_worker": 1, "dashboard_address": ":0", "silence_logs": logging.ERROR}
    with dask.config.set(LOCAL_CONFIG):
        lc2, lc1 = LocalCluster(n_workers=2, **quiet), LocalCluster(n_workers=1, **quiet)
    with lc2, lc1, ProcessPoolExecutor(2, mp_context=multiprocessing.get_context("spawn")) as pool:
        t = time.perf_counter()
        cold = chart(p, x, y, scheduler=lc2.scheduler_address, progress=False)
        t_cold = time.perf_counter() - t
        chart(p, x, y, scheduler=lc1.scheduler_address, progress=False)  # builds the 1-worker cluster's NLPs
        here = chart(p, x, y, progress=False)  # the in-process answers, to compare every cell with
        for _ in range(REPEAT):  # interleaved: a shared machine's speed drifts
            tiles = pool.submit(_tiles, (specs, 0, 1)).result()  # the last run's tile times feed the estimates
            heres.append(sum(tiles))
            befores.append(sum(pool.submit(_tiles, (specs, 0, 1, False)).result()))
            t = time.perf_counter()
            warm = chart(p, x, y, scheduler=lc2.scheduler_address, progress=False)
            warms.append(time.perf_counter() - t)
            t = time.perf_counter()
            chart(p, x, y, scheduler=lc1.scheduler_address, progress=False)
            ones.append(time.perf_counter() - t)
            plains.append(max(sum(half) for half in pool.map(_tiles, [(specs, 0, 2), (specs, 1, 2)])))
    t_here, t_before, t_warm, t_one, t_plain = (statistics.median(v) for v in (heres, befores, warms, ones, plains))
    print(f"in-process: {cells} cells in {t_here:.2f} s ({cells / t_here:.1f} cells/s); {here!r}")
    print(
        f"in-process, each continued cell by IPOPT from its neighbour's design (no Newton on the neighbour's active "
        f"set): {t_before:.2f} s ({cells / t_before:.1f} cells/s); Newton's gain {t_before / t_here:.2f}x"
    )
    same = all(
        [getattr(a, k) for k in SAME] == [getattr(b, k) for k in SAME]
        for ch in (local, cold, warm)
        for a, b in zip(here.cells, ch.cells, strict=True)
    )
    print(
        f"2-worker cluster: {t_cold:.2f} s (workers building their NLPs), {t_warm:.2f} s warm "
        f"({t_here / t_warm:.2f}x); 1-worker cluster {t_one:.2f} s; two plain processes with half the tiles "
        f"each {t_plain:.2f} s ({t_here / t_plain:.2f}x, the ceiling); every cell as in-process: {same}"
    )

    t = time.perf_counter()
    worse, better, diff = 0, 0, 0.0
    for c in tqdm(here.cells, desc="independent solves", unit="cell", disable=not sys.stderr.isatty()):
        r = solve(p, targets={x[0]: x[1][c.i], y[0]: y[1][c.j]})
        diff = max(diff, abs(r.objective - c.objective))
        worse += r.objective > c.objective + 1e-7
        better += r.objective < c.objective - 1e-7
    t_base = time.perf_counter() - t
    load1 = os.getloadavg()
    print(
        f"independent default solves: {t_base:.2f} s; the chart is {t_base / t_here:.2f}x faster; "
        f"largest objective difference {diff:.1e} rad ({worse} cells better by an independent solve, "
        f"{better} better in the chart)"
    )

    per_tile = max(0.0, t_warm - makespan(tiles, 2, 0.0)) / (
        len(tiles) / 2
    )  # the cluster's cost per tile over the clean tile times
    n_full = here.stats["full"]
    k = t_here / sum(c.seconds for c in here.cells)  # cell times from the main process, scaled to the clean run's
    t_full = k * sum(c.seconds for c in here.cells if c.method == "full") / n_full
    t_cont = k * sum(c.seconds for c in here.cells if c.method == "continued") / max(1, here.stats["continued"])
    big = 200 * 100  # a 200 x 100 chart: 200 tiles of 10 x 10
    tile_big = 2 * t_full + 98 * t_cont
    scale = {w: makespan([tile_big] * 200, w, per_tile) for w in (2, 8, 32, 128, 256)}
    here_scale = {w: makespan(tiles, w, per_tile) for w in (1, 2, 4, 8)}
    for w, s in scale.items():
        print(f"  estimated 200 x 100 chart on {w} workers: {s:.1f} s ({big / s:.0f} cells/s)")
    data = {
        "problem": "problems/chart_crank_rocker.py",
        "cells": cells,
        "tile": list(TILE),
        "tiles": here.stats["tiles"],
        "cpu_count": os.cpu_count(),
        "load_before": load0,
        "load_after": load1,
        "in_process_s": t_here,
        "in_process_without_newton_s": t_before,
        "runs_in_process_without_newton_s": befores,
        "local_with_start_s": t_local,
        "cluster_cold_s": t_cold,
        "cluster_warm_s": t_warm,
        "cluster_one_worker_s": t_one,
        "independent_s": t_base,
        "equal_results": same,
        "two_plain_processes_s": t_plain,
        "runs_in_process_s": heres,
        "runs_two_workers_s": warms,
        "speedup_two_workers": t_here / t_warm,
        "speedup_two_over_one_worker": t_one / t_warm,
        "continuation_gain": t_base / t_here,
        "full_solves": n_full,
        "needed": here.stats["needed"],
        "jumps": here.stats["jumps"],
        "switched": here.stats["switched"],
        "max_objective_difference": diff,
        "independent_better": int(worse),
        "chart_better": int(better),
        "mean_full_s": t_full,
        "mean_continued_s": t_cont,
        "dask_per_tile_s": per_tile,
        "estimate_this_chart_s": here_scale,
        "estimate_200x100_s": scale,
    }
    save("chart.json", data)
    (RESULTS / "chart.md").write_text(markdown(data, environment()))
    print(f"wrote {RESULTS / 'chart.md'} and chart.json")


def markdown(d: dict, env: dict) -> str:
    v = env["versions"]
    rows = [
        ("in-process", d["in_process_s"], "1 process"),
        ("in-process, without Newton", d["in_process_without_newton_s"], "each continued cell by IPOPT"),
        ("2-worker LocalCluster, workers building their NLPs", d["cluster_cold_s"], "first chart on the cluster"),
        ("2-worker LocalCluster, warm", d["cluster_warm_s"], "second chart on the same cluster"),
        ("1-worker LocalCluster, warm", d["cluster_one_worker_s"], "the same, one worker"),
        ("two plain processes, half the tiles each", d["two_plain_processes_s"], "no Dask: the ceiling"),
        ("scheduler='local', workers=2", d["local_with_start_s"], "starting and stopping the cluster included"),
        ("independent default solves", d["independent_s"], "solve() at every cell, in-process"),
    ]
    lines = [
        "# Design charts: the 40 x 19 crank-rocker chart",
        "",
        f"{env['date']}, {env['machine']}, Python {env['python']}, qropt {v['qropt']}, casadi {v['casadi']}; "
        f"{d['cpu_count']} cores, load average {d['load_before'][0]:.2f} before and {d['load_after'][0]:.2f} after "
        "(shared with other work)",
        "",
        "| run | seconds | cells/s | note |",
        "|---|---|---|---|",
        *(f"| {name} | {s:.2f} | {d['cells'] / s:.1f} | {note} |" for name, s, note in rows),
        "",
        f"- speedup of 2 workers over one process: {d['speedup_two_workers']:.2f}x (over a 1-worker cluster: "
        f"{d['speedup_two_over_one_worker']:.2f}x; two plain processes without Dask, the ceiling on this machine: "
        f"{d['in_process_s'] / d['two_plain_processes_s']:.2f}x); every cell equal to the in-process chart: "
        f"{d['equal_results']}; medians of {len(d['runs_in_process_s'])} interleaved runs",
        f"- continuation's gain over independent default solves: {d['continuation_gain']:.2f}x "
        f"({d['full_solves']} full solves of {d['cells']} cells, {d['needed']} needed; a full solve "
        f"{1e3 * d['mean_full_s']:.1f} ms, a continued cell {1e3 * d['mean_continued_s']:.1f} ms on average)",
        f"- agreement: largest objective difference to the independent solves {d['max_objective_difference']:.1e} rad; "
        f"cells where an independent solve is better by 1e-7: {d['independent_better']}",
        f"- {d['tiles']} tiles of {d['tile'][0]} x {d['tile'][1]}; the 2-worker run takes "
        f"{1e3 * d['dask_per_tile_s']:.0f} ms a tile more than the single-process tile times add up to (Dask, "
        "transfer, and two processes sharing the machine's two cores)",
        "",
        "Estimated (a schedule of measured tile times, each worker taking the next tile when free, plus the "
        "per-tile cost): this chart on "
        + ", ".join(f"{w} workers {s:.2f} s" for w, s in d["estimate_this_chart_s"].items())
        + " (8 tiles: more than 8 workers need smaller tiles); a 200 x 100 chart (200 tiles) on "
        + ", ".join(f"{w} workers {s:.1f} s" for w, s in d["estimate_200x100_s"].items())
        + ".",
        "",
    ]
    return "\n".join(lines)


if __name__ == "__main__":
    main()
