"""The outcome of a synthesis: an immutable record. A failed solve is a status, never an exception.

Statuses (grouped as cvxpy groups its own):
- ``optimal``: the best certified design found (the global claim in its certificate says how far that goes);
- ``local_optimum``: another certified local optimum (the entries of ``local_optima`` after the first);
- ``acceptable``: certified, but IPOPT stopped at its acceptable tolerance rather than its full one;
- ``feasible``: a certified design of a problem without an objective;
- ``infeasible``: no design meets the targets and conditions (with the reachable range of each target);
- ``failed``: no start converged to a certified design (with IPOPT's reasons, and a design meeting every target and
  condition where one is known: the optimum was not reached, not proved absent).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from qropt.synthesis.certificate import Certificate

STATUSES = ("optimal", "local_optimum", "acceptable", "feasible", "infeasible", "failed")
SOLUTION_PRESENT = ("optimal", "local_optimum", "acceptable", "feasible")
NO_SOLUTION = ("infeasible", "failed")
UNITS = {"angles": "rad (gamma_min, swing, theta)", "lengths": "the problem's length unit (stroke, size, params)",
         "footprint": "length^2", "peak_accel": "length/s^2 at the problem's omega2", "time_ratio": "1 (slow/fast)",
         "times": "s"}  # fmt: skip


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
    when no design was found.
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

    @property
    def success(self) -> bool:
        """A certified design is present."""
        return self.status in SOLUTION_PRESENT

    @property
    def max_violation(self) -> float:
        return max(self.residuals.values(), default=0.0)

    def _quantity_parts(self, sep: str) -> list[str]:
        q = self.quantities
        parts = [f"time_ratio{sep}{q['time_ratio']:.10g}"]
        if "stroke" in q:
            parts.append(f"stroke{sep}{q['stroke']:.10g}")
        if "swing" in q:
            parts.append(f"swing{sep}{math.degrees(q['swing']):.6f} deg")
        parts.append(f"gamma_min{sep}{math.degrees(q['gamma_min']):.6f} deg")
        if q.get("peak_accel") is not None:
            w = self.stats.get("omega2", 1.0)
            parts.append(f"peak_accel{sep}{q['peak_accel']:.6g} length/s^2 at omega2 = {w:g} rad/s")
        return parts

    def __repr__(self):
        lines = [f"Result(status={self.status!r}, objective={self.objective!r})", f"  message: {self.message}"]
        if self.params:
            lines.append("  params: " + ", ".join(f"{k}={v:.10g}" for k, v in self.params.items()))
        if self.quantities:
            lines.append("  quantities: " + ", ".join(self._quantity_parts("=")))
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
            lines.append("design: " + ", ".join(f"{k}={v:.10g}" for k, v in self.params.items()))
        if self.quantities:
            extra = [self.quantities["grashof"]] if self.quantities.get("grashof") else []
            lines.append("quantities: " + ", ".join(self._quantity_parts(" ") + extra))
        if self.certificate is not None:
            c = self.certificate
            obj = "" if c.certified is None else f"objective {c.certified:.12g}"
            if c.nlp is not None:
                obj += f" (NLP {c.nlp:.12g}, gap {c.gap:.2e})"
            lines.append(f"certificate: {obj + ', ' if obj else ''}max violation {self.max_violation:.2e}, "
                         f"{c.rounds} exchange round(s); {c.global_claim}")  # fmt: skip
        return "\n".join(lines)

    def to_dict(self) -> dict:
        """Strict-JSON dictionary (no NaN: None); the mechanism as its type kind and parameters."""
        return json_safe({
            "units": UNITS,
            "status": self.status,
            "success": self.success,
            "message": self.message,
            "type": getattr(self.mechanism, "KIND", None),
            "params": dict(self.params),
            "objective": self.objective,
            "quantities": self.quantities,
            "residuals": self.residuals,
            "max_violation": self.max_violation,
            "certificate": self.certificate.to_dict() if self.certificate is not None else None,
            "stats": self.stats,
            "reachable": {k: list(v) for k, v in self.reachable.items()},
            "local_optima": [r.to_dict() for r in self.local_optima],
        })  # fmt: skip

    @classmethod
    def from_dict(cls, d: dict) -> Result:
        """The Result of ``to_dict`` (the mechanism rebuilt from its type and parameters)."""
        from qropt.errors import ProblemError
        from qropt.mechanisms import mechanism_type

        try:
            d = {k: v for k, v in d.items() if k != "units"}
            mech = mechanism_type(d["type"])(**d["params"]) if d.get("type") else None
            cert = Certificate(**d["certificate"]) if d.get("certificate") else None
            return cls(
                status=d["status"],
                message=d["message"],
                params=dict(d.get("params") or {}),
                mechanism=mech,
                objective=d.get("objective"),
                quantities=dict(d.get("quantities") or {}),
                residuals={k: (v if v is not None else math.inf) for k, v in (d.get("residuals") or {}).items()},
                certificate=cert,
                stats=dict(d.get("stats") or {}),
                local_optima=tuple(cls.from_dict(x) for x in d.get("local_optima") or ()),
                reachable={
                    k: (math.nan if v[0] is None else v[0], math.nan if v[1] is None else v[1])
                    for k, v in (d.get("reachable") or {}).items()
                },  # fmt: skip
            )
        except (KeyError, TypeError, ValueError) as e:
            raise ProblemError(f"not a qropt Result dictionary: {e}") from None
