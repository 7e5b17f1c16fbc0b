"""Design charts, the model: axes, solved cells and the Chart (lookups, grids, files, the picture).

A chart is made by ``qropt.chart`` (``qropt.studies._chart_run``): its cells are solved by continuation inside
tiles (``_continuation``), in-process or on a Dask cluster (``_dask``). This module imports neither, so both can
use its Axis and Cell. Angles in radians, lengths in the problem's units.
"""

from __future__ import annotations

import contextlib
import csv
import json
import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from qropt import schema, validate
from qropt.errors import ChartError, QroptError
from qropt.synthesis import criteria
from qropt.synthesis.criteria import maximises
from qropt.synthesis.problem import Problem
from qropt.synthesis.result import STATUSES, Result
from qropt.units import named

METHODS = ("continued", "full")
STATS = (
    "cells",
    "certified",
    "no_design",
    "continued",
    "full",
    "needed",
    "jumps",
    "switched",
    "seconds",
    "cells_per_second",
    "tiles",
    "scheduler",
)


class Axis(NamedTuple):
    """One chart axis: a target or fixed parameter of the problem and its values (rad for swing)."""

    name: str
    values: tuple
    kind: str  # 'target' or 'fixed'

    def shown(self, problem=None) -> tuple:
        """Display values and label: swing in degrees, a length (the stroke, a parameter) in the problem's unit."""
        if self.name == "swing":
            return np.degrees(self.values), "swing [deg]"
        label = self.name.replace("_", " ")
        if problem is not None and (self.name == "stroke" or self.name in problem.mechanism.PARAMS):
            label += f" [{problem.units}]"
        return np.asarray(self.values), label


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
        return cls(
            i, j, r.status, r.objective, dict(r.params), dict(r.quantities), r.message, method, **flags, _result=r
        )

    @property
    def result(self) -> Result:
        """The cell's Result (rebuilt from its dictionary on first use for cells solved on a cluster or read)."""
        if self._result is None:
            try:
                object.__setattr__(self, "_result", Result.from_dict(self._data))
            except QroptError as e:
                raise ChartError(f"cell ({self.i}, {self.j}): {e}") from None
        return self._result

    @property
    def success(self) -> bool:
        return self.status in ("optimal", "local_optimum", "acceptable", "feasible")

    @property
    def needed_full(self) -> bool:
        """The continuation could not give this cell: it needed the full multi-start."""
        return self.why in ("no certified neighbour", "warm start failed", "jump")

    def to_dict(self) -> dict:
        result = self._data if self._result is None else self._result.to_dict(stamped=False)
        return {
            "i": self.i,
            "j": self.j,
            "method": self.method,
            "why": self.why,
            "source": list(self.source) if self.source else None,
            "jump": self.jump,
            "switched": self.switched,
            "seconds": self.seconds,
            "result": result,
        }

    @classmethod
    def from_dict(cls, d: dict) -> Cell:
        """The cell of ``to_dict``; ChartError naming the first field that is missing or of the wrong type."""
        _fields(
            d,
            "cell",
            {
                "i": _is_index,
                "j": _is_index,
                "method": (lambda v: v in METHODS, "continued or full"),
                "why": _is_str,
                "source": (lambda v: v is None or _is_pair(v), "null or a pair of indices"),
                "jump": _is_bool,
                "switched": _is_bool,
                "seconds": _is_number,
                "result": _is_dict,
            },
        )
        r = d["result"]
        where = f"cell ({d['i']}, {d['j']}) result"
        _fields(
            r,
            where,
            {
                "status": (lambda v: v in STATUSES, "a Result status"),
                "objective": (lambda v: v is None or _is_number(v), "null or a finite number"),
                "params": _is_numbers,
                "quantities": _is_dict,
                "message": _is_str,
            },
        )
        return cls(
            d["i"],
            d["j"],
            r["status"],
            r["objective"],
            dict(r["params"]),
            dict(r["quantities"]),
            r["message"],
            d["method"],
            d["why"],
            tuple(d["source"]) if d["source"] else None,
            d["jump"],
            d["switched"],
            d["seconds"],
            _data=r,
        )

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
        """The cell at x index i and y index j (0 <= i < len(x values), 0 <= j < len(y values); j = 0 without y)."""
        ny, nx = self.shape
        for name, k, n in (("i", i, nx), ("j", j, ny)):
            if not _is_index(k):
                raise ChartError(f"cell index {name} must be an integer, got {k!r}")
            if not 0 <= k < n:
                axis = self.x if name == "i" else self.y
                span = f"0..{n - 1} ({n} {axis.name} values)" if axis else "0 (this chart has no y axis)"
                raise ChartError(f"cell index {name} = {k} is out of range: {span}")
        return self.cells[j * nx + i]

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
        if not isinstance(quantity, str):
            raise ChartError(f"a chart quantity is a name or a ratio 'a/b', got {quantity!r}")
        parts = quantity.split("/")
        if len(parts) > 2 or not all(parts):
            raise ChartError(f"a chart quantity is a name or a ratio 'a/b', got {quantity!r}")
        values = [self._grid(p.strip()) for p in parts]
        with np.errstate(divide="ignore", invalid="ignore"):
            return values[0] if len(values) == 1 else values[0] / values[1]

    def _grid(self, name) -> np.ndarray:
        ok = next((c for c in self.cells if c.success), None)
        known = (
            {"objective"}
            | set(ok.params if ok else ())
            | {k for k, v in (ok.quantities if ok else {}).items() if isinstance(v, (int, float))}
        )
        if name not in known:
            raise ChartError(f"unknown chart quantity {name!r}; known: {sorted(known)}")
        out = np.full(len(self.cells), np.nan)
        for k, c in enumerate(self.cells):
            v = c.objective if name == "objective" else c.params.get(name, c.quantities.get(name))
            if c.success and isinstance(v, (int, float)):
                out[k] = v
        return out.reshape(self.shape)

    def panel(self, name: str = "objective") -> tuple:
        """(values, title) of one panel of the chart's pictures: the objective (gamma_min in degrees, with its unit)
        or a free parameter, in the problem's unit."""
        if name != "objective":
            return self.grid(name), f"optimal {name} [{self.problem.units}]"
        if maximises(self.problem.objective):  # gamma_min, the one maximised criterion
            return np.degrees(self.grid()), "best gamma_min [deg]"
        if not self.problem.objective:
            return self.grid(), "feasible: objective"
        unit = named(criteria.of_problem(self.problem).unit, self.problem.units)
        return self.grid(), f"{self.problem.objective}: objective [{unit}]"

    FLAGS = ("certified", "infeasible", "continued", "full", "needed", "jump", "switched")

    def mask(self, flag: str) -> np.ndarray:
        """Boolean array of a flag: certified, infeasible (no design: infeasible or failed), continued, full,
        needed (the full solve was needed), jump, switched."""
        test = {
            "certified": lambda c: c.success,
            "infeasible": lambda c: not c.success,
            "continued": lambda c: c.method == "continued",
            "full": lambda c: c.method == "full",
            "needed": lambda c: c.needed_full,
            "jump": lambda c: c.jump,
            "switched": lambda c: c.switched,
        }
        if not isinstance(flag, str) or flag not in test:
            raise ChartError(f"unknown chart flag {flag!r}; flags: {', '.join(self.FLAGS)}")
        return np.array([test[flag](c) for c in self.cells]).reshape(self.shape)

    def __repr__(self):
        s = self.stats
        ax = f"{self.x.name} {len(self.x.values)}" + (f" x {self.y.name} {len(self.y.values)}" if self.y else "")
        return (
            f"Chart({self.problem.mechanism.__name__} {self.problem.objective}, {ax}: {s['cells']} cells, "
            f"{s['certified']} certified, {s['no_design']} without a design; {s['continued']} continued, "
            f"{s['full']} full ({s['needed']} needed), {s['jumps']} jumps, {s['switched']} switched; "
            f"{s['seconds']:.3g} s, {s['scheduler']})"
        )

    # ---- files ------------------------------------------------------------------------------------------
    def rows(self) -> list[dict]:
        """One flat dict per cell: axis values, status, how it was solved, objective, parameters, quantities."""
        names = [self.x.name] + ([self.y.name] if self.y else [])
        free = list(self.problem.free)
        out = []
        for c in self.cells:
            row = {n: a.values[k] for n, a, k in zip(names, (self.x, self.y), (c.i, c.j), strict=False)}
            row |= {
                "status": c.status,
                "method": c.method,
                "why": c.why,
                "jump": c.jump,
                "switched": c.switched,
                "objective": c.objective,
            }
            row |= {k: c.params.get(k) for k in free}
            row |= {k: v for k, v in c.quantities.items() if k not in row}
            row["message"] = c.message
            out.append(row)
        return out

    def to_csv(self, path) -> None:
        """Every cell as a CSV row (angles in rad, lengths in the problem's unit, named in the column "units")."""
        rows = [r | {"units": self.problem.units} for r in self.rows()]
        keys = list(dict.fromkeys(k for r in rows for k in r))
        with _writing(path, "CSV") as fh:
            w = csv.DictWriter(fh, fieldnames=keys)
            w.writeheader()
            w.writerows(rows)

    def to_dict(self) -> dict:
        axis = lambda a: None if a is None else {"name": a.name, "values": list(a.values), "kind": a.kind}  # noqa: E731
        return {
            **schema.stamp(),
            "problem": self.problem.to_dict(),
            "x": axis(self.x),
            "y": axis(self.y),
            "stats": self.stats,
            "cells": [c.to_dict() for c in self.cells],
        }

    def to_json(self, path) -> None:
        """The whole chart (every cell's Result) as strict JSON; ``Chart.from_json`` reads it back."""
        text = json.dumps(self.to_dict(), allow_nan=False, default=float)
        with _writing(path, "JSON") as fh:
            fh.write(text)

    @classmethod
    def from_json(cls, path) -> Chart:
        """A chart written by ``to_json``, checked whole on load: its schema (a newer one than this qropt's is
        refused), its axes, every cell in place, its stats (ChartError naming the file and what is wrong)."""
        _path(path, "JSON")
        try:
            d = validate.json_document(validate.read_text(path, "chart file"), str(path), "chart")
        except QroptError as e:
            raise ChartError(f"{path}: not a qropt chart file ({e})") from None
        schema.check(d, str(path), ChartError)  # a newer file is refused; an older one (or one with none) is read
        try:
            return cls._from_dict(d)
        except QroptError as e:
            raise ChartError(f"{path}: not a qropt chart file ({e})") from None
        except (KeyError, TypeError, AttributeError) as e:  # a malformed problem table
            raise ChartError(f"{path}: not a qropt chart file ({type(e).__name__}: {e})") from None

    @classmethod
    def _from_dict(cls, d) -> Chart:
        _fields(
            d,
            "chart",
            {
                "problem": _is_dict,
                "x": _is_dict,
                "y": (lambda v: v is None or _is_dict(v), "null or an axis"),
                "stats": _is_dict,
                "cells": (lambda v: isinstance(v, list), "a list"),
            },
        )
        problem = Problem.from_dict(d["problem"])
        x, y = (None if d[k] is None else _axis_of(problem, d[k], k) for k in ("x", "y"))
        if y is not None and y.name == x.name:
            raise ChartError(f"x and y are both {x.name!r}")
        _fields(d["stats"], "stats", {k: _is_str if k == "scheduler" else _is_number for k in STATS})
        nx, ny = len(x.values), len(y.values) if y else 1
        if len(d["cells"]) != nx * ny:
            raise ChartError(f"{len(d['cells'])} cells for {nx} x {ny} axis values: the file is incomplete")
        cells = tuple(Cell.from_dict(c) for c in d["cells"])
        for k, c in enumerate(cells):
            if (c.i, c.j) != (k % nx, k // nx):
                raise ChartError(f"cell {k} is ({c.i}, {c.j}), not ({k % nx}, {k // nx}): cells are in row order")
        return cls(problem, x, y, cells, dict(d["stats"]))


def _path(path, what):
    if isinstance(path, (bytes, bytearray)) or not isinstance(path, (str, os.PathLike)) or not str(path).strip():
        raise ChartError(f"the chart {what} file must be a path (str or pathlib.Path), got {path!r}")
    parent = Path(path).parent
    if what != "JSON" and not parent.is_dir():  # JSON: read, the open names a missing file
        raise ChartError(f"cannot write the chart {what} file {str(path)!r}: no directory {str(parent)!r}")


@contextlib.contextmanager
def _writing(path, what):
    """open(path, 'w') for a chart file: a bad path or a failed write is a ChartError naming the file."""
    _path(path, what)
    try:
        with open(path, "w", newline="") as fh:
            yield fh
    except OSError as e:
        raise ChartError(f"cannot write the chart {what} file {str(path)!r}: {e.strerror or e}") from None


# ---- checks of a chart read from a file -------------------------------------------------------------------
def _is_str(v) -> bool:
    return isinstance(v, str)


def _is_bool(v) -> bool:
    return isinstance(v, bool)


def _is_dict(v) -> bool:
    return isinstance(v, dict)


def _is_index(v) -> bool:
    return isinstance(v, (int, np.integer)) and not isinstance(v, bool)


def _is_number(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def _is_pair(v) -> bool:
    return isinstance(v, (list, tuple)) and len(v) == 2 and all(_is_index(k) for k in v)


def _is_numbers(v) -> bool:
    return isinstance(v, dict) and all(isinstance(k, str) and _is_number(x) for k, x in v.items())


def _fields(d, what, checks) -> None:
    """ChartError naming the first of the fields that is missing or fails its check (a predicate, or a predicate
    and what it wants)."""
    if not isinstance(d, dict):
        raise ChartError(f"{what} is {_shown_value(d)}, not an object")
    for k, check in checks.items():
        ok, wanted = check if isinstance(check, tuple) else (check, _WANTED[check])
        if k not in d:
            raise ChartError(f"{what} has no {k!r}")
        if not ok(d[k]):
            raise ChartError(f"{what} {k!r} is {_shown_value(d[k])}, not {wanted}")


def _shown_value(v) -> str:
    text = json.dumps(v, default=repr) if v is None or isinstance(v, (bool, int, float, str)) else type(v).__name__
    return text if len(text) <= 40 else text[:37] + "..."


_WANTED = {
    _is_str: "a string",
    _is_bool: "true or false",
    _is_dict: "an object",
    _is_index: "an integer",
    _is_number: "a finite number",
    _is_numbers: "an object of finite numbers",
}


def _axis_of(problem, d, which) -> Axis:
    _fields(
        d,
        f"axis {which}",
        {
            "name": _is_str,
            "values": (
                lambda v: isinstance(v, list) and len(v) >= 2 and all(map(_is_number, v)),
                "2 or more finite numbers",
            ),
            "kind": (lambda v: v in ("target", "fixed"), "target or fixed"),
        },
    )
    axis = Axis(d["name"], tuple(float(v) for v in d["values"]), d["kind"])
    if axis.name not in problem.targets and axis.name not in problem.fixed:
        raise ChartError(f"axis {which} {axis.name!r} is no target or fixed parameter of the chart's problem")
    if axis.kind != axis_kind(problem, axis.name):
        raise ChartError(f"axis {which} {axis.name!r} is a {axis_kind(problem, axis.name)}, not a {axis.kind}")
    steps = np.diff(axis.values)
    if not (np.all(steps > 0) or np.all(steps < 0)):
        raise ChartError(f"the values of axis {which} are not distinct and in order")
    return axis


def _index(axis: Axis, v) -> int:
    vals = np.asarray(axis.values)
    try:
        f = float(v)
    except (TypeError, ValueError):
        raise ChartError(f"{axis.name} value must be a number, got {v!r}") from None
    if isinstance(v, bool) or not math.isfinite(f):
        raise ChartError(f"{axis.name} value must be a finite number, got {v!r}")
    k = int(np.argmin(np.abs(vals - f)))
    if abs(vals[k] - f) > 1e-9 * max(1.0, np.ptp(vals)):
        raise ChartError(f"{axis.name} = {v!r} is not a chart value; the nearest is {vals[k]:.12g}")
    return k


# ---- the picture ---------------------------------------------------------------------------------------------
__all__ = ["Chart", "Cell", "Axis", "ChartError", "axis_kind", "problem_at"]
