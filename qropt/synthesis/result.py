"""The outcome of a synthesis: an immutable record. A failed solve is a status, never an exception.

Statuses (grouped as cvxpy groups its own):
- ``optimal``: the best certified design found (the global claim in its certificate says how far that goes);
- ``local_optimum``: another certified local optimum (the entries of ``local_optima`` after the first);
- ``acceptable``: certified, but IPOPT stopped at its acceptable tolerance rather than its full one;
- ``feasible``: a design that meets every target and condition, checked exactly, with no optimality claimed: a
  certified design of a problem without an objective, or the end of a descent on the exact objective that beats
  every certified design (or stands where none certified; its certificate's ``local`` says so);
- ``infeasible``: no design meets the targets and conditions (with the reachable range of each target);
- ``failed``: no start converged to a certified design (with IPOPT's reasons, and a design meeting every target and
  condition where one is known: the optimum was not reached, not proved absent).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from qropt import schema
from qropt import units as units_
from qropt.errors import ProblemError, QroptError
from qropt.synthesis.certificate import Certificate

STATUSES = ("optimal", "local_optimum", "acceptable", "feasible", "infeasible", "failed")
SOLUTION_PRESENT = ("optimal", "local_optimum", "acceptable", "feasible")
NO_SOLUTION = ("infeasible", "failed")
MAX_DEPTH = 8  # levels of local_optima within local_optima a Result dictionary may hold (a solve writes 1)


def unit_names(unit: str = units_.DEFAULT) -> dict:
    """What the numbers of a Result in length unit ``unit`` are in (its ``to_dict()['units']``)."""
    from qropt.synthesis import criteria

    u = units_.length_unit(unit)
    c = criteria.CRITERIA
    return {
        "length": u,
        "angles": "rad (gamma_min, swing, theta)",
        "lengths": f"{u} (stroke, size, params)",
        "footprint": units_.named(c["footprint"].unit, u),
        "peak_accel": units_.named(c["peak_accel"].unit, u) + " at the problem's omega2",
        "peak_velocity": units_.named(c["peak_velocity"].unit, u) + " at the problem's omega2",
        "torque_per_newton": f"{u} (N m per N)",
        "time_ratio": "1 (slow/fast)",
        "times": "s",
    }


def json_safe(v):
    """JSON-safe copy: non-finite floats become None (strict JSON has no NaN)."""
    if isinstance(v, float):
        return v if math.isfinite(v) else None
    if isinstance(v, dict):
        return {str(k): json_safe(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [json_safe(x) for x in v]
    if hasattr(v, "item") and not isinstance(v, (str, bytes)):  # numpy scalars
        return json_safe(v.item())
    return v


@dataclass(frozen=True, repr=False)
class Result:
    """status: one of STATUSES; message: why, in words.

    params: every parameter (fixed, free and branch signs); mechanism: the ready mechanism or None;
    objective: gamma_min (rad) for max_gamma_min, the size for min_size, the peak slider acceleration
    (length/s^2 at the problem's omega2) for min_peak_accel, None otherwise; quantities: exact time_ratio,
    stroke or swing, gamma_min (rad), peak_accel, grashof, size, working_direction; residuals: constraint
    name -> violation (>= 0); certificate: a Certificate; stats: solver statistics and timings (s);
    local_optima: every distinct local optimum found (best first); reachable: target -> (low, high)
    when no design was found; units: the length unit of every length in it (None: its mechanism's, else
    ``qropt.units.DEFAULT``; always a unit name once built); counterweight: the crank counterweight the solve
    chose where the problem left it free (``qropt.Counterweight``, SI; its dynamic quantities include it).
    """

    status: str
    message: str
    params: dict = field(default_factory=dict)
    mechanism: Any = None
    objective: float | None = None
    quantities: dict = field(default_factory=dict)
    residuals: dict = field(default_factory=dict)
    certificate: Certificate | None = None
    stats: dict = field(default_factory=dict)
    local_optima: tuple = ()
    reachable: dict = field(default_factory=dict)
    units: str | None = None
    counterweight: Any = None
    continuation: Any = field(default=None, repr=False, compare=False)  # the optimum's NLP point and multipliers
    # (``newton.Hint``), for a solve that continues from this design (``Solver.solve(continue_from=...)``)

    def __post_init__(self):
        if self.status not in STATUSES:
            raise ProblemError(f"a Result's status is one of {list(STATUSES)}, got {self.status!r:.80}")
        if not isinstance(self.message, str):
            raise ProblemError(f"a Result's message is a string, got {type(self.message).__name__}")
        own = getattr(self.mechanism, "units", None)
        unit = self.units if self.units is not None else own or units_.DEFAULT
        try:
            units_.length_unit(unit)
        except QroptError as e:
            raise ProblemError(f"a Result's units: {e}") from None
        if own is not None and own != unit:
            raise ProblemError(f"a Result in {unit} has a mechanism in {own}")
        object.__setattr__(self, "units", unit)

    @property
    def success(self) -> bool:
        """A certified design is present."""
        return self.status in SOLUTION_PRESENT

    @property
    def max_violation(self) -> float:
        return max(self.residuals.values(), default=0.0)

    def _quantity_parts(self, sep: str) -> list[str]:
        from qropt.synthesis import criteria

        q = self.quantities
        parts = [f"time_ratio{sep}{q['time_ratio']:.10g}"]
        if "stroke" in q:
            parts.append(f"stroke{sep}{q['stroke']:.10g} {self.units}")
        if "swing" in q:
            parts.append(f"swing{sep}{math.degrees(q['swing']):.6f} deg")
        parts.append(f"gamma_min{sep}{math.degrees(q['gamma_min']):.6f} deg")
        if q.get("peak_accel") is not None:
            w = self.stats.get("omega2", 1.0)
            unit = units_.named(criteria.CRITERIA["peak_accel"].unit, self.units)
            parts.append(f"peak_accel{sep}{q['peak_accel']:.6g} {unit} at omega2 = {w:g} rad/s")
        for name, c in criteria.CRITERIA.items():  # registered criteria beyond the built-in ones
            if name not in criteria.BUILT_IN and isinstance(q.get(name), (int, float)):
                shown = math.degrees(q[name]) if c.unit == "rad" else q[name]
                unit = "deg" if c.unit == "rad" else units_.named(c.unit, self.units)
                parts.append(f"{name}{sep}{shown:.10g} {unit}")
        return parts

    def _counterweight_words(self) -> str:
        cw = self.counterweight
        return f"{cw.mass:.6g} kg at {cw.radius:g} m, {math.degrees(cw.angle):.4f} deg from the crank pin"

    def __repr__(self):
        lines = [f"Result(status={self.status!r}, objective={self.objective!r})", f"  message: {self.message}"]
        if self.params:
            lines.append(f"  params ({self.units}, rad): " + ", ".join(f"{k}={v:.10g}" for k, v in self.params.items()))
        if self.quantities:
            lines.append("  quantities: " + ", ".join(self._quantity_parts("=")))
        if self.counterweight is not None:
            lines.append(f"  counterweight: {self._counterweight_words()}")
        if self.certificate is not None:
            c = self.certificate
            lines.append(f"  certificate: gap {c.gap:.1e} after {c.rounds} round(s); {c.local}")
        if self.local_optima:
            lines.append(f"  local_optima: {len(self.local_optima)}")
        if self.reachable:
            ranges = (f"{k} {lo:.6g}..{hi:.6g}" for k, (lo, hi) in self.reachable.items())
            lines.append("  reachable: " + ", ".join(ranges))
        lines.append(f"  max_violation: {self.max_violation:.1e}, time {self.stats.get('t_total') or 0.0:.3g} s")
        return "\n".join(lines)

    def summary(self) -> str:
        """A few readable lines: status, design, quantities (gamma_min in degrees), certificate."""
        lines = [f"status: {self.status} - {self.message}"]
        if self.params:
            lines.append(f"design ({self.units}): " + ", ".join(f"{k}={v:.10g}" for k, v in self.params.items()))
        if self.quantities:
            extra = [self.quantities["grashof"]] if self.quantities.get("grashof") else []
            lines.append("quantities: " + ", ".join(self._quantity_parts(" ") + extra))
        if self.counterweight is not None:
            lines.append(f"counterweight: {self._counterweight_words()}")
        if self.certificate is not None:
            c = self.certificate
            obj = "" if c.certified is None else f"objective {c.certified:.12g}"
            if c.nlp is not None:
                obj += f" (NLP {c.nlp:.12g}, gap {c.gap:.2e})"
            lines.append(
                f"certificate: {obj + ', ' if obj else ''}max violation {self.max_violation:.2e}, "
                f"{c.rounds} exchange round(s); {c.global_claim}"
            )
        return "\n".join(lines)

    def to_dict(self, stamped: bool = True) -> dict:
        """Strict-JSON dictionary (no NaN: None), led by the schema version and qropt's (``qropt.schema.stamp``;
        ``stamped=False`` for one held inside another saved table, as its local optima and a chart's cells are);
        the mechanism as its type kind (a type not shipped with qropt as "module:Class", see
        ``qropt.mechanisms.type_reference``) and parameters."""
        from qropt.mechanisms import type_reference

        return json_safe(
            {
                **(schema.stamp() if stamped else {}),
                "units": unit_names(self.units),
                "status": self.status,
                "success": self.success,
                "message": self.message,
                "type": None if self.mechanism is None else type_reference(type(self.mechanism)),
                "params": dict(self.params),
                "objective": self.objective,
                "quantities": self.quantities,
                "residuals": self.residuals,
                "max_violation": self.max_violation,
                "certificate": self.certificate.to_dict() if self.certificate is not None else None,
                "stats": self.stats,
                "reachable": {k: list(v) for k, v in self.reachable.items()},
                "local_optima": [r.to_dict(stamped=False) for r in self.local_optima],
                **({} if self.counterweight is None else {"counterweight": self.counterweight.to_dict()}),
            }
        )

    @classmethod
    def from_dict(cls, d, _depth: int = 0) -> Result:
        """The Result of ``to_dict`` (the mechanism rebuilt from its type, parameters and unit); ProblemError naming
        the first field that is missing or of the wrong type. A dictionary without units is in the default unit."""
        if not isinstance(d, Mapping):
            raise ProblemError(f"not a qropt Result dictionary: a table of fields, got {type(d).__name__}")
        if _depth > MAX_DEPTH:
            raise ProblemError(f"not a qropt Result dictionary: local_optima nested deeper than {MAX_DEPTH} levels")
        schema.check(d, "the Result dictionary", ProblemError)  # a newer one is refused; an older one read as before
        try:
            return cls._from_dict(d, _depth)
        except QroptError as e:
            why = str(e)
        except (KeyError, TypeError, ValueError, RecursionError) as e:
            why = f"{type(e).__name__}: {e}"
        prefix = "not a qropt Result dictionary: "
        raise ProblemError(why if why.startswith(prefix) else prefix + why)

    @classmethod
    def _from_dict(cls, d, depth) -> Result:
        def need(key, ok, what, default=None):
            v = d.get(key, default)
            if not ok(v):
                raise ProblemError(f"{key} must be {what}, got {v!r:.80}")
            return v

        def numbers(v, none=False):
            return isinstance(v, Mapping) and all(
                isinstance(k, str) and (_number(x) or (none and x is None)) for k, x in v.items()
            )

        def pair(v):
            return isinstance(v, (list, tuple)) and len(v) == 2 and all(x is None or _number(x) for x in v)

        if "status" not in d or "message" not in d:
            raise ProblemError("it needs 'status' and 'message'")
        need("status", lambda v: v in STATUSES, f"one of {list(STATUSES)}")
        need("message", lambda v: isinstance(v, str), "a string")
        kind = need("type", lambda v: v is None or isinstance(v, str), "null or a type name")
        params = need("params", lambda v: numbers(v), "a table of numbers", {})
        objective = need("objective", lambda v: v is None or _number(v), "null or a number")
        quantities = need("quantities", lambda v: isinstance(v, Mapping), "a table", {})
        residuals = need("residuals", lambda v: numbers(v, none=True), "a table of numbers", {})
        cert = need("certificate", lambda v: v is None or isinstance(v, Mapping), "null or a table")
        stats = need("stats", lambda v: isinstance(v, Mapping), "a table", {})
        reach = need(
            "reachable",
            lambda v: isinstance(v, Mapping) and all(map(pair, v.values())),
            "a table of [low, high] pairs",
            {},
        )
        local = need("local_optima", lambda v: isinstance(v, (list, tuple)), "a list of Result tables", [])
        cw = need("counterweight", lambda v: v is None or isinstance(v, Mapping), "null or a table")
        if cw is not None:
            from qropt.dynamics.model import Counterweight

            if set(cw) - {"mass", "radius", "angle"} or not {"mass", "radius"} <= set(cw):
                raise ProblemError(f"counterweight is a table of mass, radius and angle, got {cw!r:.80}")
            cw = Counterweight(**cw)
        unit = d.get("units")
        if isinstance(unit, Mapping):  # to_dict's table names its length unit; older files: the default
            unit = unit.get("length", units_.DEFAULT)
        unit = units_.DEFAULT if unit is None else units_.length_unit(unit)
        from qropt.mechanisms import mechanism_type

        mech = mechanism_type(kind)(**params, units=unit) if kind else None
        return cls(
            status=d["status"],
            message=d["message"],
            params=dict(params),
            mechanism=mech,
            objective=None if objective is None else float(objective),
            quantities=dict(quantities),
            residuals={k: (v if v is not None else math.inf) for k, v in residuals.items()},
            certificate=None if cert is None else Certificate.from_dict(cert),
            stats=dict(stats),
            local_optima=tuple(cls.from_dict(x, depth + 1) for x in local),
            reachable={
                k: (math.nan if lo is None else lo, math.nan if hi is None else hi) for k, (lo, hi) in reach.items()
            },
            units=unit,
            counterweight=cw,
        )


def _number(v) -> bool:
    """A real number (int or float, not a bool); nan and inf allowed (a Result holds them)."""
    return isinstance(v, (int, float)) and not isinstance(v, bool)
