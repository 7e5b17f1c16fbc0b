"""``qropt.chart``: a synthesis problem solved at every cell of a grid of target or fixed-parameter values.

Cells are solved by continuation inside tiles (blocks of cells, ``_continuation``): each cell starts one local
solve from the design of its best certified neighbour and is certified like any solve. The full default solve
(closed forms and multi-start) runs at the first cell of every tile, on a check lattice (every ``check``-th cell
each way), and wherever the warm start fails or jumps branch; a better design found that way is carried to the
cells around it. Tiles are independent and described by plain numbers, so they run in-process or on a Dask
cluster (``_dask``) with the same results, gathered into a ``Chart`` (``_chart``). This module is the only one
that imports all three: the others never import it. Angles in radians, lengths in the problem's units.
"""

from __future__ import annotations

import math
import sys
import time

import numpy as np

from qropt.errors import ChartError, ProblemError
from qropt.studies import _dask
from qropt.studies._chart import Axis, Chart, axis_kind, problem_at
from qropt.synthesis.problem import Problem

TILE = (10, 10)  # cells per tile along x and y
CHECK = 10  # the full solve also runs at the centre of every CHECK x CHECK block of cells
MAX_CELLS = 1_000_000


def chart(
    problem: Problem, x, y=None, *, scheduler=None, workers=None, progress=True, solver=None, tile=TILE, check=CHECK
) -> Chart:
    """``problem`` solved at every cell of x (and y): each ``(name, values)``, the name a target of the problem
    (time_ratio, stroke, swing in rad) or one of its fixed parameters, at least 2 distinct monotone values.

    scheduler: None (in-process), 'local' (a LocalCluster of ``workers`` processes, one thread each) or the
    address of a running Dask scheduler ('tcp://host:8786'); ``workers`` alone means 'local'. solver: the Solver
    (default ``qropt.synthesis.solver.DEFAULT``; workers rebuild it from its options); tile: cells per tile
    (x, y); check: the full solve also runs where both cell indices are multiples of it. A tqdm bar on standard
    error when ``progress`` and it is a terminal.
    """
    from qropt.synthesis.solver import DEFAULT, Solver

    if not isinstance(problem, Problem):
        raise ChartError(f"chart takes a qropt.Problem, got {type(problem).__name__}")
    solver = DEFAULT if solver is None else solver
    if not isinstance(solver, Solver):
        raise ChartError(f"solver must be a qropt.Solver, got {type(solver).__name__}")
    ax_x = _axis(problem, x, "x")
    ax_y = None if y is None else _axis(problem, y, "y")
    if ax_y is not None and ax_y.name == ax_x.name:
        raise ChartError(f"x and y are both {ax_x.name!r}: give two different axes")
    nx, ny = len(ax_x.values), len(ax_y.values) if ax_y else 1
    if nx * ny > MAX_CELLS:
        raise ChartError(f"{nx} x {ny} cells is more than {MAX_CELLS:,}: split the chart")
    tile, check = _tile_shape(tile), _positive_int("check", check)
    mode = _mode(scheduler, workers)
    for a in (ax_x, ax_y):  # every axis value gives a valid problem
        for v in a.values if a else ():
            try:
                problem_at(problem, [a], [v])
            except ProblemError as e:
                raise ChartError(f"{a.name} = {v:g} on the chart's axis: {e}") from None
    specs = [
        {
            "problem": problem.to_dict(),
            "x": [ax_x.name, list(ax_x.values)],
            "y": None if ax_y is None else [ax_y.name, list(ax_y.values)],
            "block": [i0, min(i0 + tile[0], nx), j0, min(j0 + tile[1], ny)],
            "check": check,
        }
        for j0 in range(0, ny, tile[1])
        for i0 in range(0, nx, tile[0])
    ]
    t0 = time.perf_counter()
    bar = _bar(progress, nx * ny)
    try:
        if mode is None:
            tiles, where = _dask.run_here(specs, solver, bar.update), "in-process"
        else:
            tiles, where = _dask.run_dask(specs, solver, mode, workers, bar.update)
    finally:
        bar.close()
    cells = sorted((c for t in tiles for c in t), key=lambda c: (c.j, c.i))
    seconds = time.perf_counter() - t0
    return Chart(problem, ax_x, ax_y, tuple(cells), _stats(cells, seconds, len(specs), where))


def _stats(cells, seconds, tiles, where) -> dict:
    n = len(cells)
    return {
        "cells": n,
        "certified": sum(c.success for c in cells),
        "no_design": sum(not c.success for c in cells),
        "continued": sum(c.method == "continued" for c in cells),
        "full": sum(c.method == "full" for c in cells),
        "needed": sum(c.needed_full for c in cells),
        "jumps": sum(c.jump for c in cells),
        "switched": sum(c.switched for c in cells),
        "seconds": seconds,
        "cells_per_second": n / seconds,
        "tiles": tiles,
        "scheduler": where,
    }


def _axis(problem, spec, which) -> Axis:
    if not (isinstance(spec, (tuple, list)) and len(spec) == 2 and isinstance(spec[0], str)):
        raise ChartError(f"{which} is (name, values), got {spec!r}")
    name, values = spec
    if name in problem.free:
        raise ChartError(
            f"{name!r} is free in the problem: a chart axis is a target or a fixed parameter (fix {name} to chart it)"
        )
    names = list(problem.targets) + list(problem.fixed)
    if name not in names:
        raise ChartError(f"unknown chart axis {name!r}; this problem's targets and fixed parameters: {names}")
    try:
        vals = tuple(float(v) for v in values)
    except (TypeError, ValueError):
        raise ChartError(f"the values of {name} must be numbers, got {values!r}") from None
    if len(vals) < 2:
        raise ChartError(f"a chart axis needs at least 2 values; {name} has {len(vals)}")
    if not all(math.isfinite(v) for v in vals):
        raise ChartError(f"the values of {name} must be finite numbers")
    steps = np.diff(vals)
    if not (np.all(steps > 0) or np.all(steps < 0)):
        raise ChartError(f"the values of {name} must be distinct and in increasing or decreasing order")
    return Axis(name, vals, axis_kind(problem, name))


def _positive_int(name, v) -> int:
    if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 1:
        raise ChartError(f"{name} must be an integer >= 1, got {v!r}")
    return int(v)


def _tile_shape(tile) -> tuple:
    if not (isinstance(tile, (tuple, list)) and len(tile) == 2):
        raise ChartError(f"tile is (cells along x, cells along y), got {tile!r}")
    return _positive_int("tile size", tile[0]), _positive_int("tile size", tile[1])


def _mode(scheduler, workers):
    """None (in-process), 'local' or a scheduler address; checks workers."""
    if workers is not None:
        _positive_int("workers", workers)
        _dask.check_workers(workers)
    if scheduler is None:
        return "local" if workers is not None else None
    if not isinstance(scheduler, str) or not scheduler.strip():
        raise ChartError(f"scheduler is None, 'local' or a Dask scheduler address, got {scheduler!r}")
    if scheduler != "local" and workers is not None:
        raise ChartError(f"workers sets the size of a local cluster; the cluster at {scheduler} has its own")
    return scheduler


def _bar(progress, total):
    from tqdm import tqdm

    return tqdm(total=total, desc="chart", unit="cell", leave=False, disable=not (progress and sys.stderr.isatty()))


__all__ = ["chart", "TILE", "CHECK", "MAX_CELLS"]
