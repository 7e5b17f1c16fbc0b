"""A synthesis problem: what the designer wants, validated and frozen.

Lengths are numbers in the problem's stated unit (``units``, one of ``qropt.units.LENGTH_UNITS``; default metres),
angles in radians. Targets are equality constraints, conditions inequalities, the objective one of
``criteria.objectives()``.

Magnitudes are bounded where the analysis would overflow: lengths and offsets (fixed values, bounds, the stroke,
length conditions) within MAGNITUDE (lengths at least 1 / MAGNITUDE), the crank speed |omega2| <= MAX_OMEGA2 rad/s
and the time ratio <= MAX_TIME_RATIO.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from types import MappingProxyType
from typing import Any

from qropt import schema
from qropt import units as units_
from qropt.dynamics.drive import Drive
from qropt.dynamics.model import Loads, Masses
from qropt.errors import ProblemError, QroptError
from qropt.mechanisms import Mechanism, mechanism_type, type_reference
from qropt.mechanisms.base import REQUIRED
from qropt.synthesis import criteria
from qropt.synthesis.criteria import SIZES, finite
from qropt.validate import MAGNITUDE, MAX_NESTING, nesting

MAX_OMEGA2 = 1e6  # rad/s: omega2^2 times a length up to MAGNITUDE stays finite (1e112); no machine turns faster
MAX_TIME_RATIO = 1e6  # slow/fast: beyond it the fast stroke takes under 2 pi / 1e6 rad and TR has no meaning


def _frozen(d):
    return MappingProxyType(dict(d or {}))


@dataclass(frozen=True, eq=False)
class Problem:
    """Dimensional synthesis of one mechanism type.

    mechanism: class or type name; fixed: name -> value; free: name -> (lower, upper);
    targets: 'time_ratio', 'stroke' (sliders) or 'swing' (FourBar, rad);
    conditions: 'grashof' ('drag-link' | 'crank-rocker'), 'gamma_min' (lower bound, rad), upper bounds
    'max_sum', 'max_longest' (length), 'max_footprint' (length^2), 'max_peak_accel' (length/s^2),
    'max_peak_velocity' (length/s), 'linear' [(coefficients, lower, upper)], 'ratio' [(numerator,
    denominator, lower, upper)]; objective: 'max_gamma_min', 'min_size' (with ``size``), 'min_peak_accel'
    (at ``omega2``, over the 'cycle' or the 'working' stroke), 'min_peak_velocity' (at ``omega2``, over the
    working stroke) or None (see ``qropt.criteria``); branches: name -> allowed signs; units: the length unit
    of every length above and of the answer (one of ``qropt.units.LENGTH_UNITS``; default metres); masses,
    loads: the mass model and loads of its dynamics (``qropt.Masses``, ``qropt.Loads``, or their dicts), SI; drive:
    the gearbox (and motor) the motor's criteria read (``qropt.Drive`` or its dict).
    """

    mechanism: Any
    fixed: Any = field(default_factory=dict)
    free: Any = field(default_factory=dict)
    targets: Any = field(default_factory=dict)
    conditions: Any = field(default_factory=dict)
    objective: str | None = "max_gamma_min"
    size: str = "sum"
    omega2: float = 1.0
    accel_over: str = "cycle"
    branches: Any = field(default_factory=dict)
    name: str = ""
    units: str = units_.DEFAULT
    masses: Any = None
    loads: Any = None
    drive: Any = None

    def __post_init__(self):
        try:
            cls = mechanism_type(self.mechanism)
        except Exception as e:
            raise ProblemError(str(e)) from None
        set_ = object.__setattr__
        set_(self, "mechanism", cls)
        if not isinstance(self.name, str):
            raise ProblemError(f"{cls.__name__}: name must be a string, got {self.name!r}")
        try:
            units_.length_unit(self.units)
        except QroptError as e:
            raise self._err(str(e)) from None
        for k, kind in (
            ("masses", Masses),
            ("loads", Loads),
            ("drive", Drive),
        ):  # a dict (a file's table) or the object
            v = getattr(self, k)
            try:
                set_(self, k, v if v is None or isinstance(v, kind) else kind.from_dict(v))
            except QroptError as e:
                raise self._err(f"{k}: {e}") from None
        for k in ("fixed", "free", "targets", "conditions", "branches"):
            v = getattr(self, k)
            if v is not None and not isinstance(v, Mapping):
                raise self._err(f"{k} must be a dict (name -> value), got {v!r}")
            set_(self, k, _frozen(v))
        try:
            self._validate()
        except (TypeError, ValueError, KeyError, IndexError, AttributeError, RecursionError) as e:  # malformed values
            if isinstance(e, ProblemError):
                raise
            raise self._err(f"malformed problem ({type(e).__name__}: {e})") from None

    def _validate(self):
        set_ = object.__setattr__
        set_(self, "free", _frozen({k: (float(lo), float(hi)) for k, (lo, hi) in self._check_free().items()}))
        set_(self, "branches", _frozen(self._branches()))
        set_(self, "fixed", _frozen(self._completed_fixed()))
        self._check_targets()
        set_(self, "conditions", _frozen(self._check_conditions()))
        self._check_objective()

    # ---- validation ---------------------------------------------------------
    def _err(self, msg):
        return ProblemError(f"{self.name or self.mechanism.__name__}: {msg}")

    def _check_free(self):
        cls, params = self.mechanism, self.mechanism.PARAMS
        if not self.free:
            raise self._err("no free parameter: give free={name: (lower, upper)}")
        for k in list(self.fixed) + list(self.free):
            if k in cls.BRANCHES and k in self.free:
                raise self._err(
                    f"{k!r} is a branch sign (+1 or -1), not a continuous parameter: fix it, or give "
                    f"branches={{{k!r}: (-1, 1)}} to try both"
                )
            if k not in params:
                raise self._err(f"unknown or non-continuous parameter {k!r}; {cls.__name__} takes {list(params)}")
        both = sorted(set(self.fixed) & set(self.free))
        if both:
            raise self._err(f"{both} are both fixed and free")
        for k, b in self.free.items():
            try:
                lo, hi = (float(v) for v in b)
            except (TypeError, ValueError):
                raise self._err(f"bounds of {k} must be (lower, upper), got {b!r}") from None
            if not (math.isfinite(lo) and math.isfinite(hi)):
                raise self._err(f"bounds of {k} must be finite, got ({lo:g}, {hi:g})")
            if not lo < hi:
                raise self._err(f"bounds of {k} are empty or contradictory: ({lo:g}, {hi:g}); fix it instead")
            if k in cls.LENGTHS and lo <= 0:
                raise self._err(f"length {k} needs a positive lower bound, got {lo:g}")
            self._check_magnitude(f"bounds of {k}", k in cls.LENGTHS, lo, hi)
        for k, v in self.fixed.items():
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise self._err(f"fixed {k} must be a finite number, got {v!r}")
            if k in cls.LENGTHS and v <= 0:
                raise self._err(f"fixed length {k} must be positive, got {v:g}")
            if k not in cls.BRANCHES:
                self._check_magnitude(f"fixed {k}", k in cls.LENGTHS, v)
        missing = [k for k, v in params.items() if v is REQUIRED and k not in self.fixed and k not in self.free]
        if missing:
            raise self._err(f"parameters {missing} are neither fixed nor free")
        return self.free

    def _check_magnitude(self, what, length: bool, *values):
        """Lengths in [1/MAGNITUDE, MAGNITUDE] and other values (offsets) within MAGNITUDE, as mechanisms take."""
        for v in values:
            if abs(v) > MAGNITUDE or (length and v < 1 / MAGNITUDE):
                span = "[1e-100, 1e100]" if length else "[-1e100, 1e100]"
                raise self._err(f"{what} = {v:g} is out of range ({span} {self.units})")

    def _branches(self):
        out = {}
        for k in self.mechanism.BRANCHES:
            vals = self.branches.get(k, (self.fixed.get(k, self.mechanism.PARAMS[k]),))
            vals = tuple(vals if isinstance(vals, (tuple, list)) else (vals,))
            if not vals or not all(finite(v) and v in (-1.0, 1.0) for v in vals):
                raise self._err(f"branch {k} takes signs from (-1, +1), got {vals}")
            out[k] = tuple(float(v) for v in vals)
        for k in self.branches:
            if k not in out:
                raise self._err(f"{self.mechanism.__name__} has no branch {k!r}")
        return out

    def _completed_fixed(self):
        cls = self.mechanism
        fixed = {k: float(v) for k, v in self.fixed.items() if k not in cls.BRANCHES}
        for k, v in cls.PARAMS.items():
            if k in cls.BRANCHES or k in fixed or k in self.free or v is None or v is REQUIRED:
                continue
            fixed[k] = float(v)
        given = {**fixed, **dict.fromkeys(self.free, 0.0)}
        fixed.update({k: float(v) for k, v in cls.completed(given).items() if k not in self.free})
        return fixed

    def _check_targets(self):
        allowed = ("time_ratio", self.mechanism.TRAVEL)
        if not self.targets:
            raise self._err(f"no target: give targets from {allowed}")
        for k, v in self.targets.items():
            if k not in allowed:
                raise self._err(f"unknown target {k!r} for {self.mechanism.__name__}; targets are {allowed}")
            if not isinstance(v, (int, float)) or not math.isfinite(v):
                raise self._err(f"target {k} must be a finite number, got {v!r}")
        tr = self.targets.get("time_ratio")
        if tr is not None and tr < 1.0:
            raise self._err(f"time_ratio is slow/fast >= 1 by definition, got {tr:g}")
        if tr is not None and tr > MAX_TIME_RATIO:
            raise self._err(f"time_ratio {tr:g} is beyond {MAX_TIME_RATIO:g} (a fast stroke under 2 pi / 1e6 rad)")
        if self.targets.get("stroke", 1.0) <= 0:
            raise self._err(f"stroke must be positive, got {self.targets['stroke']:g}")
        if "stroke" in self.targets:
            self._check_magnitude("stroke", True, self.targets["stroke"])
        if not 0 < self.targets.get("swing", 1.0) < math.pi:
            raise self._err(f"swing must be in (0, pi) rad, got {self.targets['swing']:g}")

    def _check_conditions(self):
        c = dict(self.conditions)
        bounds = criteria.bounds()
        known = {"grashof", "linear", "ratio", *bounds}
        for k in c:
            if k not in known:
                raise self._err(f"unknown condition {k!r}; conditions are {sorted(known)}")
        if self.mechanism.FOUR_BAR:
            c.setdefault("grashof", self.mechanism.CLASS or "crank-rocker")
            if c["grashof"] not in ("drag-link", "crank-rocker"):
                raise self._err(f"grashof condition is 'drag-link' or 'crank-rocker', got {c['grashof']!r}")
            need = self.mechanism.CLASS
            if need and c["grashof"] != need:
                raise self._err(f"{self.mechanism.__name__} is a {need} by definition, not {c['grashof']}")
        elif "grashof" in c:
            raise self._err(f"{self.mechanism.__name__} has no four-bar: no grashof condition")
        g = c.get("gamma_min")
        if g is not None and not (finite(g) and 0 <= g < math.pi / 2):
            raise self._err(f"gamma_min bound must be in [0, pi/2) rad, a number; got {g!r}")
        for k, crit in bounds.items():
            if k != "gamma_min" and k in c:
                if not (finite(c[k]) and c[k] > 0):
                    raise self._err(f"{k} is an upper bound, a positive number; got {c[k]!r}")
                c[k] = float(c[k])
                if c[k] > MAGNITUDE**2 or c[k] < MAGNITUDE**-2:  # footprints are length^2; MAGNITUDE^2 is finite
                    raise self._err(f"{k} = {c[k]:g} is out of range")
            if k in c and not crit.applies(self.mechanism):
                raise self._err(f"{crit.why_not(self.mechanism)}: {k} does not apply")
        linear = []
        for row in c.get("linear", ()):
            if not (
                isinstance(row, (list, tuple))
                and len(row) == 3
                and isinstance(row[0], Mapping)
                and all(finite(v) for v in (*row[0].values(), row[1], row[2]))
            ):
                raise self._err(f"a linear condition is (coefficients dict, lower, upper) of numbers, got {row!r}")
            coeffs, lo, hi = dict(row[0]), float(row[1]), float(row[2])
            self._check_names(coeffs)
            if lo > hi:
                raise self._err(f"linear condition {coeffs} has lower {lo:g} > upper {hi:g}")
            linear.append((coeffs, lo, hi))
        ratio = []
        for row in c.get("ratio", ()):
            if not (
                isinstance(row, (list, tuple))
                and len(row) == 4
                and all(isinstance(v, str) for v in row[:2])
                and all(finite(v) for v in row[2:])
            ):
                raise self._err(f"a ratio condition is (numerator, denominator, lower, upper), got {row!r}")
            num, den, lo, hi = row[0], row[1], float(row[2]), float(row[3])
            self._check_names({num: 1, den: 1})
            if den not in self.mechanism.LENGTHS or lo > hi:
                raise self._err(f"ratio {num}/{den} needs a length denominator and lower <= upper")
            ratio.append((num, den, lo, hi))
        if "linear" in c:
            c["linear"] = tuple(linear)
        if "ratio" in c:
            c["ratio"] = tuple(ratio)
        return c

    def _check_names(self, names):
        for k in names:
            if k not in self.fixed and k not in self.free:
                raise self._err(f"condition names {k!r}, which is not a parameter of this problem")

    def _check_objective(self):
        objectives = criteria.objectives()
        if self.objective not in objectives:
            raise self._err(f"unknown objective {self.objective!r}; objectives are {objectives}")
        if self.size not in SIZES:
            raise self._err(f"unknown size measure {self.size!r}; measures are {SIZES}")
        if self.accel_over not in ("cycle", "working"):
            raise self._err(f"accel_over is 'cycle' or 'working', got {self.accel_over!r}")
        if not (finite(self.omega2) and self.omega2 != 0):
            raise self._err(f"omega2 is the crank speed in rad/s, a nonzero finite number; got {self.omega2!r}")
        if abs(self.omega2) > MAX_OMEGA2:
            raise self._err(f"omega2 = {self.omega2:g} rad/s is out of range (|omega2| <= {MAX_OMEGA2:g} rad/s)")
        if self.objective and not criteria.of(self.objective, self.size).applies(self.mechanism):
            c = criteria.of(self.objective, self.size)
            raise self._err(f"{c.why_not(self.mechanism)}: {self.objective} does not apply")
        for c in criteria.used(self):
            why = c.check(self)
            if why:
                raise self._err(why)

    # ---- equality and serialisation (angles in radians, lengths in the problem's unit) -------------
    def to_dict(self) -> dict:
        """Plain JSON-ready values: the mechanism by its kind (a type not shipped with qropt as "module:Class",
        which ``from_dict`` imports), bounds as [lower, upper], objective None or a name."""
        c = dict(self.conditions)
        if "linear" in c:
            c["linear"] = [[dict(k), lo, hi] for k, lo, hi in c["linear"]]
        if "ratio" in c:
            c["ratio"] = [list(r) for r in c["ratio"]]
        return {
            "mechanism": type_reference(self.mechanism),
            "fixed": dict(self.fixed),
            "free": {k: [lo, hi] for k, (lo, hi) in self.free.items()},
            "targets": dict(self.targets),
            "conditions": c,
            "objective": self.objective,
            "size": self.size,
            "omega2": self.omega2,
            "accel_over": self.accel_over,
            "branches": {k: list(v) for k, v in self.branches.items()},
            "name": self.name,
            "units": self.units,
            **({} if self.masses is None else {"masses": self.masses.to_dict()}),
            **({} if self.loads is None else {"loads": self.loads.to_dict()}),
            **({} if self.drive is None else {"drive": self.drive.to_dict()}),
        }

    def __reduce__(self):  # pickled as its plain values (``to_dict``), validated again when loaded
        return (type(self).from_dict, (self.to_dict(),))

    @classmethod
    def from_dict(cls, d) -> Problem:
        """The Problem of ``to_dict`` (or a hand-written dict, TOML or JSON table), validated as always."""
        if not isinstance(d, Mapping):
            raise ProblemError(f"a problem is a table of fields, got {type(d).__name__}")
        schema.check(d, "the problem", ProblemError)  # a newer file is refused; its schema and qropt are not fields
        d = {k: v for k, v in d.items() if k not in schema.FIELDS}
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(d) - known)
        if unknown or "mechanism" not in d:
            raise ProblemError(f"problem fields are {sorted(known)} ('mechanism' required); unknown: {unknown}")
        d = dict(d)
        if d.get("objective") in ("none", "None", ""):
            d["objective"] = None
        return cls(**d)

    def to_json(self) -> str:
        """JSON, led by the schema version and qropt's (``qropt.schema.stamp``)."""
        return json.dumps({**schema.stamp(), **self.to_dict()}, indent=2, allow_nan=False)

    @classmethod
    def from_json(cls, text: str) -> Problem:
        return cls._from_text(text, json.loads, json.JSONDecodeError, "JSON")

    @classmethod
    def _from_text(cls, text, loads, error, kind) -> Problem:
        if not isinstance(text, str):
            raise ProblemError(f"a {kind} problem is text (str), got {type(text).__name__}")
        if nesting(text) > MAX_NESTING:
            raise ProblemError(f"not a {kind} problem: nested deeper than {MAX_NESTING} levels")
        try:
            d = loads(text)
        except error as e:
            raise ProblemError(f"not a {kind} problem: {e}") from None
        except RecursionError:
            raise ProblemError(f"not a {kind} problem: nested too deeply") from None
        return cls.from_dict(d)

    def to_toml(self) -> str:
        """TOML (an objective of None is written "none"), led by the schema version and qropt's."""
        import tomli_w

        d = {**schema.stamp(), **self.to_dict()}
        d["objective"] = d["objective"] or "none"
        return tomli_w.dumps(d)

    @classmethod
    def from_toml(cls, text: str) -> Problem:
        import tomllib

        return cls._from_text(text, tomllib.loads, tomllib.TOMLDecodeError, "TOML")

    def __eq__(self, other):
        return isinstance(other, Problem) and self.to_dict() == other.to_dict()

    def __hash__(self):
        return hash(json.dumps(self.to_dict(), sort_keys=True))

    # ---- helpers --------------------------------------------------------------
    def replace(self, **changes) -> Problem:
        """A copy with some fields changed (validated again)."""
        d = {k: getattr(self, k) for k in self.__dataclass_fields__}
        d["fixed"] = {**self.fixed, **{k: v[0] for k, v in self.branches.items() if len(v) == 1}}
        d.update(changes)
        return Problem(**{k: (dict(v) if isinstance(v, MappingProxyType) else v) for k, v in d.items()})

    def settled(self, result) -> Problem:
        """The problem as a result's design fixes it: a free counterweight at the one the result chose (the problem
        itself otherwise). Exact values of that design's dynamics need it."""
        cw = getattr(result, "counterweight", None)
        if cw is None or self.masses is None or not self.masses.balancing:
            return self
        return self.replace(masses=self.masses.replace(counterweight=cw))

    def build(self, values: dict, branch: dict) -> Mechanism:
        """The mechanism (in the problem's unit) with the free parameters at ``values`` on ``branch`` (may raise
        QroptError)."""
        return self.mechanism(**self.fixed, **values, **branch, units=self.units)
