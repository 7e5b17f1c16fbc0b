"""The outcome of a synthesis: a fresh, immutable record. A failed solve is a status, never an exception."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

STATUSES = ("optimal", "feasible", "infeasible", "failed")


@dataclass(frozen=True)
class Result:
    """status: 'optimal' (objective given), 'feasible' (no objective), 'infeasible' or 'failed'.

    params: every parameter (fixed, free and branch signs); mechanism: the ready mechanism or None;
    objective: gamma_min (rad) for max_gamma_min, the size for min_size, the peak slider acceleration
    for min_peak_accel, None otherwise; quantities: exact time_ratio, stroke or swing, gamma_min (rad),
    peak_accel, grashof; residuals: constraint name -> violation (>= 0); certificate: how the optimum
    was checked; stats: solver statistics and timings (s); local_optima: every distinct local optimum
    found (best first); reachable: target -> (low, high) when infeasible.
    """

    status: str
    message: str
    params: dict = field(default_factory=dict)
    mechanism: Any = None
    objective: float | None = None
    quantities: dict = field(default_factory=dict)
    residuals: dict = field(default_factory=dict)
    certificate: dict = field(default_factory=dict)
    stats: dict = field(default_factory=dict)
    local_optima: tuple = ()
    reachable: dict = field(default_factory=dict)

    @property
    def success(self) -> bool:
        return self.status in ("optimal", "feasible")

    @property
    def max_violation(self) -> float:
        return max(self.residuals.values(), default=0.0)

    def summary(self) -> str:
        """A few readable lines: status, design, quantities, certificate."""
        lines = [f"status: {self.status} - {self.message}"]
        if self.params:
            lines.append("design: " + ", ".join(f"{k}={v:.10g}" for k, v in self.params.items()))
        q = self.quantities
        if q:
            parts = [f"TR {q['time_ratio']:.10g}"]
            parts += [f"{k} {q[k]:.10g}" for k in ("stroke", "swing") if k in q]
            parts.append(f"gamma_min {math.degrees(q['gamma_min']):.6f} deg")
            if q.get("peak_accel") is not None:
                parts.append(f"peak accel {q['peak_accel']:.6g}")
            if q.get("grashof"):
                parts.append(q["grashof"])
            lines.append("quantities: " + ", ".join(parts))
        if self.certificate:
            c = self.certificate
            obj = "" if c.get("certified") is None else f"objective {c['certified']:.12g} (NLP {c['nlp']:.12g}, "
            obj += "" if c.get("certified") is None else f"gap {c['gap']:.2e}), "
            lines.append(
                f"certificate: {obj}max violation {self.max_violation:.2e}, {c.get('rounds', 0)} exchange round(s)"
            )
        return "\n".join(lines)

    def to_dict(self) -> dict:
        """JSON-ready dictionary (the mechanism as its type and parameters)."""
        return {
            "status": self.status,
            "success": self.success,
            "message": self.message,
            "type": getattr(self.mechanism, "KIND", None),
            "params": self.params,
            "objective": self.objective,
            "quantities": self.quantities,
            "residuals": self.residuals,
            "max_violation": self.max_violation,
            "certificate": self.certificate,
            "stats": self.stats,
            "reachable": {k: list(v) for k, v in self.reachable.items()},
            "local_optima": [r.to_dict() for r in self.local_optima],
        }
