"""Type synthesis: one task (time ratio, stroke) solved for every quick-return type, compared criterion by criterion.

Each type's problem has bounds that scale with the stroke s (every length in [s/20, 5 s], offsets in
[-5 s, 5 s]; angles, which a stroke does not scale, in [-pi, pi]) and its own conditions (the Grashof class of the
four-bar types). Every row comes from its type's parameter kinds (``Mechanism.kinds()``): every length and offset
free (an optional one only in the row of a type's option that gives it, ``Mechanism.OPTIONS``), its angles fixed at
their defaults (free in [-pi, pi] where they have none, or where ``bounds`` names them), its branch signs at their
defaults. The built-in rows are ``TYPES``: every shipped slider type and its options; any other slider type (a
class of one's own, its KIND or a ``"module:Class"`` reference) gets its row the same way. Every row is a certified
solve;
every criterion of a row is evaluated exactly on its design. Lengths in the stated unit (``units``, that of the
stroke and the bounds; metres by default), angles in radians.
"""

from __future__ import annotations

import csv
import dataclasses
import json
import math
import time
from collections.abc import Mapping
from dataclasses import dataclass, field

from qropt import schema
from qropt import units as units_
from qropt.errors import ProblemError, QroptError
from qropt.mechanisms import TYPES as SHIPPED
from qropt.mechanisms import mechanism_type
from qropt.mechanisms.base import REQUIRED
from qropt.studies import _workers
from qropt.synthesis import criteria
from qropt.synthesis.problem import Problem
from qropt.synthesis.result import SOLUTION_PRESENT, Result, json_safe
from qropt.validate import MAGNITUDE


def _kinds_row(cls, bounds=None, option: str = "") -> tuple:
    """(mechanism, free lengths, free offsets, fixed values, free angles) of a type from its parameter kinds
    (``Mechanism.kinds()``): every length and offset it has (an optional one, PARAMS default None, only where
    ``option``, a name of its ``OPTIONS``, gives it), its angles without a default or named by ``bounds``."""
    kinds, given, extra = cls.kinds(), set(bounds or ()), cls.OPTIONS.get(option, ())

    def free(kind):
        return tuple(k for k, v in cls.PARAMS.items() if kinds[k] == kind and (v is not None or k in extra))

    angles = tuple(k for k, v in cls.PARAMS.items() if kinds[k] == "angle" and (v is REQUIRED or k in given))
    return cls, free("length"), free("offset"), {}, angles


# the built-in rows, type name -> (mechanism kind, free lengths, free offsets, fixed values, free angles): every
# shipped slider type by its KIND, and by KIND-option for each of its OPTIONS
TYPES = {
    f"{cls.KIND}-{option}" if option else cls.KIND: (cls.KIND, *_kinds_row(cls, option=option)[1:])
    for cls in SHIPPED
    if cls.TRAVEL == "stroke"
    for option in ("", *cls.OPTIONS)
}


def bounds_of(kind: str, stroke: float) -> tuple:
    """The default bounds of a parameter of this kind ('length', 'offset' or 'angle') for a stroke s."""
    return {"length": (stroke / 20, 5 * stroke), "offset": (-5 * stroke, 5 * stroke), "angle": (-math.pi, math.pi)}[
        kind
    ]


def type_row(t, bounds=None) -> tuple:
    """(name, (mechanism, free lengths, free offsets, fixed values, free angles)) of a type: a built-in row of
    ``TYPES`` by its name, or the default row of any other slider type (a Mechanism class, its KIND, class name
    or "module:Class"); ProblemError naming the types where there is none."""
    if isinstance(t, str) and t in TYPES:
        return t, TYPES[t]
    try:
        cls = mechanism_type(t) if isinstance(t, (str, type)) else None
    except QroptError as e:
        raise ProblemError(f"unknown type {t!r}; types are {list(TYPES)}, or a slider type of your own ({e})") from None
    if cls is None:
        raise ProblemError(f"unknown type {t!r}; types are {list(TYPES)}, or a slider type of your own")
    if cls.TRAVEL != "stroke":
        raise ProblemError(f"{cls.__name__} has no slider (its output is a {cls.TRAVEL}): design compares strokes")
    return cls.__dict__.get("KIND") or cls.__name__, _kinds_row(cls, bounds)


def type_problem(
    kind,
    time_ratio: float,
    stroke: float,
    *,
    objective="max_gamma_min",
    bounds=None,
    conditions=None,
    omega2: float = 1.0,
    size: str = "footprint",
    units: str = units_.DEFAULT,
    masses=None,
    loads=None,
    drive=None,
) -> Problem:
    """The task as a Problem of one type (a name of ``TYPES``, or a slider type of one's own: see ``type_row``):
    default bounds scaled by the stroke, ``bounds`` (name -> (lo, hi)) overriding those the type has,
    ``conditions`` added to the type's own; lengths in ``units``; ``masses``, ``loads`` and ``drive`` for its
    dynamics."""
    kind, (mech, lengths, offsets, fixed, angles) = type_row(kind, bounds)
    s = stroke
    free = {k: bounds_of("length", s) for k in lengths} | {k: bounds_of("offset", s) for k in offsets}
    free |= {k: bounds_of("angle", s) for k in angles}
    for k, b in (bounds or {}).items():
        if k in free:
            free[k] = b
    return Problem(
        mechanism=mech,
        fixed=fixed,
        free=free,
        targets={"time_ratio": time_ratio, "stroke": stroke},
        conditions=dict(conditions or {}),
        objective=objective,
        omega2=omega2,
        size=size,
        name=f"{kind} TR {time_ratio:g} stroke {stroke:g} {units}",
        units=units,
        masses=masses,
        loads=loads,
        drive=drive,
    )


@dataclass(frozen=True)
class Row:
    """One type's answer: its Result, every criterion of its design evaluated exactly (None where the type
    has no design), and why not when it has none."""

    type: str
    result: Result
    criteria: dict = field(default_factory=dict)
    reason: str = ""

    @property
    def success(self) -> bool:
        return self.result.status in SOLUTION_PRESENT

    def record(self) -> dict:
        """Flat, JSON-ready: type, status, objective, each criterion, the parameters, the counterweight the solve
        chose (where the problem left it free; else None), the reason."""
        d = {"type": self.type, "status": self.result.status, "objective": self.result.objective}
        d |= {k: self.criteria.get(k) for k in columns()}
        d["params"] = dict(self.result.params)
        cw = self.result.counterweight
        d["counterweight"] = None if cw is None else cw.to_dict()
        d["reason"] = self.reason
        return d


@dataclass(frozen=True)
class Comparison:
    """The task solved for several types: ``rows`` best first by the objective, types without a design last;
    ``fronts``: type -> its Front, or why it has none (with ``design(..., pareto=(a, b))``)."""

    time_ratio: float
    stroke: float
    objective: str
    omega2: float
    rows: tuple
    fronts: dict = field(default_factory=dict)
    units: str = units_.DEFAULT

    def __repr__(self):
        u = criteria.units(self.units)
        lines = [f"Comparison(TR {self.time_ratio:g}, stroke {self.stroke:g} {self.units}, {self.objective}):"]
        for r in self.rows:
            if r.success:
                c = r.criteria
                lines.append(
                    f"  {r.type:20s} gamma_min {math.degrees(c['gamma_min']):6.2f} deg  footprint "
                    f"{c['footprint']:.4g} {u['footprint']}  peak accel {c['peak_accel']:.4g} "
                    f"{u['peak_accel']}  peak velocity {c['peak_velocity']:.4g} "
                    f"{u['peak_velocity']}"
                )
            else:
                lines.append(f"  {r.type:20s} no design: {r.reason}")
        return "\n".join(lines)

    def markdown(self) -> str:
        """The comparison as a Markdown table, best first: gamma_min in degrees, each criterion in its unit to four
        significant digits, the chosen parameters (lengths in the unit, angles in degrees)."""
        u = criteria.units(self.units)
        head = ["row", "gamma_min [deg]", f"footprint [{u['footprint']}]", f"peak accel [{u['peak_accel']}]"]
        head += [f"peak velocity [{u['peak_velocity']}]", "parameters"]
        lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
        for r in self.rows:
            if not r.success:
                lines.append(f"| {r.type} | no design: {r.reason} |" + " |" * (len(head) - 2))
                continue
            c, kinds = r.criteria, r.result.mechanism.kinds()
            params = {k: 0.0 if abs(v) < 1e-12 * self.stroke else v for k, v in r.result.params.items()}  # no noise
            shown = [
                f"{k} = {math.degrees(v):.4g} deg" if kinds[k] == "angle" else f"{k} = {v:.4g}"
                for k, v in params.items()
                if kinds[k] != "branch"
            ]
            cells = [r.type, f"{math.degrees(c['gamma_min']):.2f}", f"{c['footprint']:.4g}", f"{c['peak_accel']:.4g}"]
            lines.append("| " + " | ".join([*cells, f"{c['peak_velocity']:.4g}", ", ".join(shown)]) + " |")
        return "\n".join(lines)

    def table(self) -> list[dict]:
        """One dict per row (Row.record, with the length unit under "units"), best first."""
        return [r.record() | {"units": self.units} for r in self.rows]

    def to_json(self) -> str:
        """The comparison as JSON, led by the schema version and qropt's (``qropt.schema.stamp``); "units" names
        each criterion's unit, "length" the length unit."""
        d = {
            **schema.stamp(),
            "time_ratio": self.time_ratio,
            "stroke": self.stroke,
            "objective": self.objective,
            "omega2": self.omega2,
            "units": {"length": self.units, **criteria.units(self.units)},
            "rows": self.table(),
        }
        return json.dumps(json_safe(d), indent=2, allow_nan=False)

    def to_csv(self, path) -> None:
        """The table as CSV: a row per type, its criteria (lengths in the column "units"; angles in rad)."""
        rows = self.table()
        names = sorted({k for r in rows for k in r["params"]})
        with open(path, "w", newline="") as fh:
            w = csv.writer(fh)
            cw = ["counterweight_kg", "counterweight_radius_m", "counterweight_angle_rad"]
            w.writerow(["type", "status", "objective", *columns(), *names, *cw, "reason", "units"])
            for r in rows:
                c = r["counterweight"] or {}
                w.writerow(
                    [
                        r["type"],
                        r["status"],
                        _cell(r["objective"]),
                        *(_cell(r[k]) for k in columns()),
                        *(_cell(r["params"].get(k)) for k in names),
                        *(_cell(c.get(k)) for k in ("mass", "radius", "angle")),
                        r["reason"],
                        self.units,
                    ]
                )


def task_problems(
    time_ratio: float,
    stroke: float,
    *,
    objective: str = "max_gamma_min",
    types=None,
    bounds=None,
    conditions=None,
    omega2: float = 1.0,
    size: str = "footprint",
    units: str = units_.DEFAULT,
    masses=None,
    loads=None,
    drive=None,
) -> dict:
    """Row name -> the Problem ``design`` solves for it, every argument checked (ProblemError naming the first
    that is wrong); what ``design`` and the web application's design jobs check before any solve."""
    try:
        units = units_.length_unit(units)
    except QroptError as e:
        raise ProblemError(f"design: {e}") from None
    if bounds is not None and not isinstance(bounds, Mapping):
        raise ProblemError(f"bounds is a dict name -> (lower, upper), got {bounds!r}")
    chosen = _types(list(TYPES) if types is None else types)  # row name -> the type as given
    types = list(chosen)
    if not (criteria.finite(time_ratio) and time_ratio >= 1):
        raise ProblemError(f"time_ratio is slow/fast >= 1, got {time_ratio!r}")
    if not (criteria.finite(stroke) and stroke > 0):
        raise ProblemError(f"stroke must be a positive number, got {stroke!r}")
    if not 20 / MAGNITUDE <= stroke <= MAGNITUDE / 5:  # the default bounds [s/20, 5 s] within the magnitude range
        raise ProblemError(f"stroke {stroke:g} {units} is out of range [2e-99, 2e99] (its bounds reach s/20 and 5 s)")
    if conditions is not None and not isinstance(conditions, Mapping):
        raise ProblemError(f"conditions is a dict name -> bound (e.g. {{'gamma_min': 0.7}}), got {conditions!r}")
    known = set()
    for t in types:
        mech, lengths, offsets, _, _ = type_row(chosen[t])[1]
        angles = [k for k, kind in mechanism_type(mech).kinds().items() if kind == "angle"]
        known |= {*lengths, *offsets, *angles}
    unknown = sorted(set(bounds or {}) - known, key=str)
    if unknown:
        raise ProblemError(f"bounds name {unknown}, which no type of {types} has (they have {sorted(known)})")
    return {
        kind: type_problem(
            chosen[kind],
            time_ratio,
            stroke,
            objective=objective,
            bounds=bounds,
            conditions=conditions,
            omega2=omega2,
            size=size,
            units=units,
            masses=masses,
            loads=loads,
            drive=drive,
        )
        for kind in types
    }


def design(
    time_ratio: float,
    stroke: float,
    *,
    objective: str = "max_gamma_min",
    types=None,
    bounds=None,
    conditions=None,
    omega2: float = 1.0,
    size: str = "footprint",
    pareto=None,
    n: int = 12,
    solver=None,
    progress=None,
    units: str = units_.DEFAULT,
    masses=None,
    loads=None,
    drive=None,
    workers: int | None = None,
    time_limit: float | None = None,
) -> Comparison:
    """Solve the task (TR, stroke) for every type (or ``types``) and compare; see the module docstring.

    objective: as Problem.objective; conditions: bound conditions for every type (e.g. {'gamma_min': 0.7});
    pareto: two objectives whose front is computed for every type (``n`` points each; a type without one gets
    the reason in ``Comparison.fronts``); progress: a callable called once per finished type; units: the length
    unit of the stroke, the bounds and every length of the answer (one of ``qropt.units.LENGTH_UNITS``); masses,
    loads, drive: every type's mass model and loads (``qropt.Masses``, ``qropt.Loads``; the bars follow each
    design's links) and gearbox (``qropt.Drive``), for the dynamic objectives and bounds; workers: solve the rows
    in that many worker processes, kept for later calls (``qropt.studies._workers``; the same rows as in this
    process, the largest given out first); time_limit: seconds of wall time for the whole comparison, shared by
    the rows (in this process each row gets an equal share of what is left when it starts; in K workers each row
    K / rows of the whole), each row's Result the best found within its share (``Solver.solve``'s time_limit).
    Every argument is checked (every type's problem built, the front's objectives and ``n``) before any solve.
    """
    from qropt.synthesis.solver import DEFAULT, Solver, check_time_limit

    if solver is not None and not isinstance(solver, Solver):
        raise ProblemError(f"solver is a qropt.Solver or None, got {type(solver).__name__}")
    if progress is not None and not callable(progress):
        raise ProblemError(f"progress is a callable (called once per finished type) or None, got {progress!r}")
    if workers is not None:
        _workers.check_workers(workers)
    time_limit = check_time_limit(time_limit)
    solver = solver or DEFAULT
    problems = task_problems(
        time_ratio,
        stroke,
        objective=objective,
        types=types,
        bounds=bounds,
        conditions=conditions,
        omega2=omega2,
        size=size,
        units=units,
        masses=masses,
        loads=loads,
        drive=drive,
    )
    units = units_.length_unit(units)
    if pareto is not None:
        from qropt.studies._pareto import _check

        for p in problems.values():
            _check(p, pareto, n)
    rows, fronts = [], {}
    if workers is not None and workers > 1:
        each = (lambda _: progress(1)) if progress and pareto is None else None  # with fronts: once each is done
        share = None if time_limit is None else time_limit * min(workers, len(problems)) / len(problems)
        solved = _workers.solve_all(problems, solver, workers, done=each, time_limit=share)
    else:
        solved = None
    end = None if time_limit is None else time.perf_counter() + time_limit
    for i, (kind, p) in enumerate(problems.items()):
        share = None if end is None else max(end - time.perf_counter(), 1e-3) / (len(problems) - i)
        r = solved[kind] if solved is not None else solver.solve(p, time_limit=share)
        if r.mechanism is None and r.units != units:  # a Result without a design names the problem's unit too
            r = dataclasses.replace(r, units=units)
        rows.append(_row(kind, p, r))
        if pareto is not None:
            from qropt.studies._pareto import pareto as front

            try:
                fronts[kind] = front(p, pareto, n=n, solver=solver)
            except ProblemError as e:  # this type has no front (an end has no design): say why, keep the others
                fronts[kind] = str(e)
        if progress and (solved is None or pareto is not None):
            progress(1)
    maximise = criteria.maximises(objective)
    ok = [r for r in rows if r.success]
    if objective:
        ok.sort(key=lambda r: r.result.objective, reverse=maximise)
    rows = tuple(ok + [r for r in rows if not r.success])
    return Comparison(time_ratio, stroke, objective, omega2, rows, fronts, units)


def _row(kind, problem, r: Result) -> Row:
    if r.status not in SOLUTION_PRESENT:
        return Row(kind, r, {}, r.message)
    problem = problem.settled(r)  # with the counterweight the solve chose, where it was free
    values = {c.name: c.value(problem, r.mechanism) for c in criteria.reported(problem, problem.mechanism)}
    values["torque_per_newton"] = r.quantities["torque_per_newton"]
    return Row(kind, r, {k: values.get(k) for k in columns()}, "")


def columns() -> tuple:
    """The criteria a comparison reports, in registry order, and the torque per newton of cutting force."""
    return (*criteria.CRITERIA, "torque_per_newton")


def _types(types) -> list[str]:
    """Row name -> the type as given: names of TYPES, or slider types of one's own (classes, KINDs, "module:Class")."""
    if isinstance(types, str) or not hasattr(types, "__iter__"):
        raise ProblemError(f"types is a list of type names from {list(TYPES)} or types of your own, got {types!r}")
    given = list(types)
    out = {type_row(t)[0]: t for t in given}
    if not out or len(out) != len(given):
        raise ProblemError(f"types must name at least one type, each once; got {[type_row(t)[0] for t in given]}")
    return out


def _cell(v):
    return "" if v is None else f"{v:.12g}" if isinstance(v, float) else v


__all__ = ["TYPES", "columns", "type_problem", "design", "Comparison", "Row", "QroptError"]
