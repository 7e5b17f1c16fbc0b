"""Design charts: a synthesis problem solved at every cell of a grid of target or fixed-parameter values.

Cells are solved by continuation inside tiles (blocks of cells): each cell starts one local solve from the
design of its best certified neighbour and is certified like any solve. The full default solve (closed forms
and multi-start) runs at the first cell of every tile, on a check lattice (every ``check``-th cell each way),
and wherever the warm start fails or jumps branch; a better design found that way is carried to the cells
around it. Tiles are independent and described by plain numbers, so they run in-process or on a Dask cluster
(``qropt.chart_dask``) with the same results. Angles in radians, lengths in the problem's units.
"""

from __future__ import annotations

import csv
import json
import math
import sys
import time
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np

from qropt.errors import ChartError, ProblemError
from qropt.synthesis.criteria import maximises
from qropt.synthesis.problem import Problem
from qropt.synthesis.result import Result

TILE = (10, 10)  # cells per tile along x and y
CHECK = 10  # the full solve also runs at the centre of every CHECK x CHECK block of cells
MAX_CELLS = 1_000_000


class Axis(NamedTuple):
    """One chart axis: a target or fixed parameter of the problem and its values (rad for swing)."""

    name: str
    values: tuple
    kind: str  # 'target' or 'fixed'


@dataclass(frozen=True, eq=False, repr=False)
class Cell:
    """One solved cell at index (i, j) = (x index, y index).

    method: 'continued' (one local solve from the neighbour ``source``) or 'full' (the default solve); why: the
    reason the full solve ran ('tile start', 'check', 'no certified neighbour', 'warm start failed', 'jump',
    'closed form'), '' for a continued cell; jump: the continuation from a neighbour jumped branch here;
    switched: a better design than the neighbour's branch gives took over here. ``result`` is the cell's Result.
    """

    i: int
    j: int
    status: str
    objective: float | None
    params: dict
    quantities: dict
    message: str
    method: str
    why: str = ""
    source: tuple | None = None
    jump: bool = False
    switched: bool = False
    seconds: float = 0.0
    _result: Any = field(default=None, compare=False)
    _data: Any = field(default=None, compare=False)

    @classmethod
    def of(cls, i, j, r: Result, method, **flags) -> Cell:
        return cls(i, j, r.status, r.objective, dict(r.params), dict(r.quantities), r.message, method, **flags,
                   _result=r)  # fmt: skip

    @property
    def result(self) -> Result:
        """The cell's Result (rebuilt from its dictionary on first use for cells solved on a cluster)."""
        if self._result is None:
            object.__setattr__(self, "_result", Result.from_dict(self._data))
        return self._result

    @property
    def success(self) -> bool:
        return self.status in ("optimal", "local_optimum", "acceptable", "feasible")

    @property
    def needed_full(self) -> bool:
        """The continuation could not give this cell: it needed the full multi-start."""
        return self.why in ("no certified neighbour", "warm start failed", "jump")

    def to_dict(self) -> dict:
        result = self._data if self._result is None else self._result.to_dict()
        return {"i": self.i, "j": self.j, "method": self.method, "why": self.why,
                "source": list(self.source) if self.source else None, "jump": self.jump, "switched": self.switched,
                "seconds": self.seconds, "result": result}  # fmt: skip

    @classmethod
    def from_dict(cls, d: dict) -> Cell:
        r = d["result"]
        return cls(d["i"], d["j"], r["status"], r["objective"], dict(r["params"]), dict(r["quantities"]),
                   r["message"], d["method"], d["why"], tuple(d["source"]) if d["source"] else None, d["jump"],
                   d["switched"], d["seconds"], _data=r)  # fmt: skip

    def __repr__(self):
        obj = "" if self.objective is None else f", objective={self.objective:.10g}"
        flags = "".join(f", {k}=True" for k in ("jump", "switched") if getattr(self, k))
        how = f"{self.method}" + (f" ({self.why})" if self.why else f" from {self.source}")
        return f"Cell({self.i}, {self.j}, {self.status!r}{obj}, {how}{flags})"


def axis_kind(problem, name) -> str:
    """'target' for a target of the problem, else 'fixed'."""
    return "target" if name in problem.targets else "fixed"


def problem_at(problem, axes, values) -> Problem:
    """The problem with its axis targets and fixed parameters at these values."""
    fixed, targets = dict(problem.fixed), dict(problem.targets)
    for a, v in zip(axes, values, strict=True):
        (targets if a.kind == "target" else fixed)[a.name] = v
    return problem.replace(fixed=fixed, targets=targets)


# ---- the chart ---------------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False, repr=False)
class Chart:
    """A problem solved over a grid: ``cells`` in row order (index j * len(x.values) + i), ``stats`` counts and times.

    grid(quantity) and mask(flag) give arrays of shape (len(y values), len(x values)), one row without y.
    """

    problem: Problem
    x: Axis
    y: Axis | None
    cells: tuple
    stats: dict

    @property
    def shape(self) -> tuple:
        return (len(self.y.values) if self.y else 1, len(self.x.values))

    def cell(self, i: int, j: int = 0) -> Cell:
        return self.cells[j * self.shape[1] + i]

    def result(self, xv: float, yv: float | None = None) -> Result:
        """The Result of the cell at these axis values (as given; swing in rad)."""
        i = _index(self.x, xv)
        if self.y is None:
            if yv is not None:
                raise ChartError("this chart has no y axis: give the x value only")
            return self.cell(i).result
        if yv is None:
            raise ChartError(f"give the {self.y.name} value too")
        return self.cell(i, _index(self.y, yv)).result

    def grid(self, quantity: str = "objective") -> np.ndarray:
        """'objective', a quantity of the Results (gamma_min, time_ratio, swing, stroke, size, peak_accel), a
        parameter, or a ratio of two of them ('r3/r1'); nan where a cell has no design."""
        parts = quantity.split("/")
        if len(parts) > 2 or not all(parts):
            raise ChartError(f"a chart quantity is a name or a ratio 'a/b', got {quantity!r}")
        values = [self._grid(p.strip()) for p in parts]
        with np.errstate(divide="ignore", invalid="ignore"):
            return values[0] if len(values) == 1 else values[0] / values[1]

    def _grid(self, name) -> np.ndarray:
        ok = next((c for c in self.cells if c.success), None)
        known = {"objective"} | set(ok.params if ok else ()) | {k for k, v in (ok.quantities if ok else {}).items()
                                                                if isinstance(v, (int, float))}  # fmt: skip
        if name not in known:
            raise ChartError(f"unknown chart quantity {name!r}; known: {sorted(known)}")
        out = np.full(len(self.cells), np.nan)
        for k, c in enumerate(self.cells):
            v = c.objective if name == "objective" else c.params.get(name, c.quantities.get(name))
            if c.success and isinstance(v, (int, float)):
                out[k] = v
        return out.reshape(self.shape)

    FLAGS = ("certified", "infeasible", "continued", "full", "needed", "jump", "switched")

    def mask(self, flag: str) -> np.ndarray:
        """Boolean array of a flag: certified, infeasible (no design: infeasible or failed), continued, full,
        needed (the full solve was needed), jump, switched."""
        test = {"certified": lambda c: c.success, "infeasible": lambda c: not c.success,
                "continued": lambda c: c.method == "continued", "full": lambda c: c.method == "full",
                "needed": lambda c: c.needed_full, "jump": lambda c: c.jump,
                "switched": lambda c: c.switched}  # fmt: skip
        if flag not in test:
            raise ChartError(f"unknown chart flag {flag!r}; flags: {', '.join(self.FLAGS)}")
        return np.array([test[flag](c) for c in self.cells]).reshape(self.shape)

    def __repr__(self):
        s = self.stats
        ax = f"{self.x.name} {len(self.x.values)}" + (f" x {self.y.name} {len(self.y.values)}" if self.y else "")
        return (f"Chart({self.problem.mechanism.__name__} {self.problem.objective}, {ax}: {s['cells']} cells, "
                f"{s['certified']} certified, {s['no_design']} without a design; {s['continued']} continued, "
                f"{s['full']} full ({s['needed']} needed), {s['jumps']} jumps, {s['switched']} switched; "
                f"{s['seconds']:.3g} s, {s['scheduler']})")  # fmt: skip

    # ---- files ------------------------------------------------------------------------------------------
    def rows(self) -> list[dict]:
        """One flat dict per cell: axis values, status, how it was solved, objective, parameters, quantities."""
        names = [self.x.name] + ([self.y.name] if self.y else [])
        free = list(self.problem.free)
        out = []
        for c in self.cells:
            row = {n: a.values[k] for n, a, k in zip(names, (self.x, self.y), (c.i, c.j), strict=False)}
            row |= {"status": c.status, "method": c.method, "why": c.why, "jump": c.jump, "switched": c.switched,
                    "objective": c.objective}  # fmt: skip
            row |= {k: c.params.get(k) for k in free}
            row |= {k: v for k, v in c.quantities.items() if k not in row}
            row["message"] = c.message
            out.append(row)
        return out

    def to_csv(self, path) -> None:
        """Every cell as a CSV row (angles in rad, lengths in the problem's units)."""
        rows = self.rows()
        keys = list(dict.fromkeys(k for r in rows for k in r))
        with open(path, "w", newline="") as fh:
            w = csv.DictWriter(fh, fieldnames=keys)
            w.writeheader()
            w.writerows(rows)

    def to_dict(self) -> dict:
        axis = lambda a: None if a is None else {"name": a.name, "values": list(a.values), "kind": a.kind}  # noqa: E731
        return {"problem": self.problem.to_dict(), "x": axis(self.x), "y": axis(self.y), "stats": self.stats,
                "cells": [c.to_dict() for c in self.cells]}  # fmt: skip

    def to_json(self, path) -> None:
        """The whole chart (every cell's Result) as strict JSON; ``Chart.from_json`` reads it back."""
        with open(path, "w") as fh:
            json.dump(self.to_dict(), fh, allow_nan=False, default=float)

    @classmethod
    def from_json(cls, path) -> Chart:
        try:
            with open(path) as fh:
                d = json.load(fh)
            axes = [None if a is None else Axis(a["name"], tuple(a["values"]), a["kind"]) for a in (d["x"], d["y"])]
            cells = tuple(Cell.from_dict(c) for c in d["cells"])
            return cls(Problem.from_dict(d["problem"]), axes[0], axes[1], cells, d["stats"])
        except (OSError, ValueError, KeyError, TypeError) as e:
            raise ChartError(f"{path}: not a qropt chart file ({type(e).__name__}: {e})") from None

    def plot(self, path, dpi: int = 90) -> None:
        """Contour charts of the objective and the optimal free parameters beside how each cell was solved;
        cells without a design are crossed, branch changes ringed (PNG, PDF or SVG by the path's suffix)."""
        import matplotlib.pyplot as plt

        fig = chart_figure(self)
        fig.savefig(path, dpi=dpi)
        plt.close(fig)


def _index(axis: Axis, v) -> int:
    vals = np.asarray(axis.values)
    try:
        k = int(np.argmin(np.abs(vals - float(v))))
    except (TypeError, ValueError):
        raise ChartError(f"{axis.name} value must be a number, got {v!r}") from None
    if abs(vals[k] - float(v)) > 1e-9 * max(1.0, np.ptp(vals)):
        raise ChartError(f"{axis.name} = {v!r} is not a chart value; the nearest is {vals[k]:.12g}")
    return k


# ---- building a chart --------------------------------------------------------------------------------------
def chart(problem: Problem, x, y=None, *, scheduler=None, workers=None, progress=True, solver=None,
          tile=TILE, check=CHECK) -> Chart:  # fmt: skip
    """``problem`` solved at every cell of x (and y): each ``(name, values)``, the name a target of the problem
    (time_ratio, stroke, swing in rad) or one of its fixed parameters, at least 2 distinct monotone values.

    scheduler: None (in-process), 'local' (a LocalCluster of ``workers`` processes, one thread each) or the
    address of a running Dask scheduler ('tcp://host:8786'); ``workers`` alone means 'local'. solver: the Solver
    (default ``qropt.solve.DEFAULT``; workers rebuild it from its options); tile: cells per tile (x, y); check:
    the full solve also runs where both cell indices are multiples of it. A tqdm bar on standard error when
    ``progress`` and it is a terminal.
    """
    from qropt.studies import _tiles as chart_dask
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
    specs = [{"problem": problem.to_dict(), "x": [ax_x.name, list(ax_x.values)],
              "y": None if ax_y is None else [ax_y.name, list(ax_y.values)],
              "block": [i0, min(i0 + tile[0], nx), j0, min(j0 + tile[1], ny)], "check": check}
             for j0 in range(0, ny, tile[1]) for i0 in range(0, nx, tile[0])]  # fmt: skip
    t0 = time.perf_counter()
    bar = _bar(progress, nx * ny)
    try:
        if mode is None:
            tiles, where = chart_dask.run_here(specs, solver, bar.update), "in-process"
        else:
            tiles, where = chart_dask.run_dask(specs, solver, mode, workers, bar.update)
    finally:
        bar.close()
    cells = sorted((c for t in tiles for c in t), key=lambda c: (c.j, c.i))
    seconds = time.perf_counter() - t0
    return Chart(problem, ax_x, ax_y, tuple(cells), _stats(cells, seconds, len(specs), where))


def _stats(cells, seconds, tiles, where) -> dict:
    n = len(cells)
    return {"cells": n, "certified": sum(c.success for c in cells), "no_design": sum(not c.success for c in cells),
            "continued": sum(c.method == "continued" for c in cells), "full": sum(c.method == "full" for c in cells),
            "needed": sum(c.needed_full for c in cells), "jumps": sum(c.jump for c in cells),
            "switched": sum(c.switched for c in cells), "seconds": seconds, "cells_per_second": n / seconds,
            "tiles": tiles, "scheduler": where}  # fmt: skip


def _axis(problem, spec, which) -> Axis:
    if not (isinstance(spec, (tuple, list)) and len(spec) == 2 and isinstance(spec[0], str)):
        raise ChartError(f"{which} is (name, values), got {spec!r}")
    name, values = spec
    if name in problem.free:
        raise ChartError(f"{name!r} is free in the problem: a chart axis is a target or a fixed parameter "
                         f"(fix {name} to chart it)")  # fmt: skip
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


# ---- the picture ---------------------------------------------------------------------------------------------
def _shown(axis: Axis) -> tuple:
    """Display values and label of an axis: swing in degrees."""
    if axis.name == "swing":
        return np.degrees(axis.values), "swing [deg]"
    return np.asarray(axis.values), axis.name.replace("_", " ")


def _panel(ch: Chart, name: str) -> tuple:
    """Values and title of one panel: the objective (gamma_min in degrees) or a parameter."""
    if name != "objective":
        return ch.grid(name), f"optimal {name}"
    if maximises(ch.problem.objective):  # gamma_min, the one maximised criterion
        return np.degrees(ch.grid()), "best gamma_min [deg]"
    return ch.grid(), f"{ch.problem.objective or 'feasible'}: objective"


def chart_figure(ch: Chart):
    """The chart's figure (matplotlib): one panel for the objective, one per free parameter, one for how each
    cell was solved; with a fixed parameter on y, the best y of each x is drawn as a dashed ridge."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = ["objective", *ch.problem.free]
    xs, xlabel = _shown(ch.x)
    note = ", ".join([f"{k} = {v:g}" for k, v in ch.problem.fixed.items() if k != getattr(ch.y, "name", "")
                      and k in ch.problem.mechanism.LENGTHS and k != ch.x.name]
                     + [f"{k} = {v:g}" for k, v in ch.problem.targets.items() if k not in (ch.x.name,
                        getattr(ch.y, "name", "")) and k != "swing"])  # fmt: skip
    title = f"{ch.problem.name or ch.problem.mechanism.__name__}: {ch.problem.mechanism.KIND}" + (
        f", {note}" if note else ""
    )
    s = ch.stats
    how = (f"{s['cells']} cells: {s['continued']} continued, {s['full']} full solves ({s['needed']} needed), "
           f"{s['no_design']} without a design, {s['jumps'] + s['switched']} branch changes")  # fmt: skip
    if ch.y is None:
        fig, axes = plt.subplots(len(names), 1, figsize=(7, 2.2 * len(names)), sharex=True, squeeze=False)
        for ax, name in zip(axes[:, 0], names, strict=True):
            z, label = _panel(ch, name)
            ax.plot(xs, z[0], "o-", ms=3)
            ax.plot(xs[ch.mask("infeasible")[0]], np.zeros(ch.mask("infeasible").sum()), "x", color="0.5")
            ax.set_ylabel(label, fontsize=8)
            ax.grid(alpha=0.3)
        axes[-1, 0].set_xlabel(xlabel)
        fig.suptitle(f"{title}\n{how}", fontsize=9)
        fig.tight_layout()
        return fig
    ys, ylabel = _shown(ch.y)
    n = len(names) + 1
    cols = 3 if n > 4 else 2
    rows = -(-n // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(5.2 * cols, 3.9 * rows), squeeze=False)
    bad, change = ch.mask("infeasible"), ch.mask("jump") | ch.mask("switched")
    gx, gy = np.meshgrid(xs, ys)
    ridge = None
    if ch.y.kind == "fixed":  # a design choice on y: its best value for each x
        z = _panel(ch, "objective")[0]
        sign = 1.0 if maximises(ch.problem.objective) else -1.0
        cols_ok = np.isfinite(z).any(axis=0)
        ridge = (xs[cols_ok], ys[np.nanargmax(sign * np.where(np.isfinite(z), z, -np.inf * sign), axis=0)][cols_ok])
    for ax, name in zip(axes.flat, names, strict=False):
        z, label = _panel(ch, name)
        zm = np.ma.masked_invalid(z)
        if name == "objective":
            filled = ax.contourf(gx, gy, zm, levels=12, cmap="viridis")
            fig.colorbar(filled, ax=ax, shrink=0.9)
            lines = ax.contour(gx, gy, zm, levels=filled.levels[::2], colors="k", linewidths=0.6)
        else:
            lines = ax.contour(gx, gy, zm, levels=10, cmap="copper", linewidths=1.0)
        ax.clabel(lines, fontsize=7, fmt="%.3g")
        ax.set_title(label, fontsize=10)
    how_ax = axes.flat[len(names)]
    how_ax.set_title("how each cell was solved", fontsize=10)
    code = np.select([bad, ch.mask("needed"), ch.mask("full")], [3, 2, 1], 0)
    colours = matplotlib.colors.ListedColormap(["#dfe9f5", "#4c72b0", "#dd8452", "0.55"])
    how_ax.pcolormesh(gx, gy, code, cmap=colours, vmin=-0.5, vmax=3.5, shading="nearest")
    how_ax.set_xlim(xs.min(), xs.max())
    how_ax.set_ylim(ys.min(), ys.max())
    labels = ["continued", "full solve (tile start, check, closed form)", "full solve needed", "no design"]
    handles = [matplotlib.patches.Patch(color=colours(k), label=t) for k, t in enumerate(labels)]
    how_ax.legend(handles=handles, fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=2)
    for ax in axes.flat[:n]:
        ax.plot(gx[bad], gy[bad], "x", color="0.35", ms=4, mew=0.8, ls="none")
        ax.plot(gx[change], gy[change], "o", mfc="none", mec="red", ms=6, mew=1.0, ls="none")
        if ridge is not None:
            ax.plot(*ridge, "--", color="crimson", lw=1.2)
        ax.set_xlabel(xlabel, fontsize=8)
        ax.set_ylabel(ylabel, fontsize=8)
        ax.tick_params(labelsize=7)
    for ax in axes.flat[n:]:
        ax.set_visible(False)
    fig.suptitle(f"{title}\n{how}\nx: no design, red ring: branch change"
                 + ("; dashed: best " + ch.y.name + " for each " + ch.x.name if ridge is not None else ""),
                 fontsize=9)  # fmt: skip
    fig.tight_layout()
    return fig


__all__ = ["chart", "Chart", "Cell", "Axis", "ChartError", "chart_figure"]
