"""The design criteria: what a problem can optimise or bound, each evaluated exactly in one place.

=============  ======================  =================================  ===========================
criterion      objective               bound condition                    unit
=============  ======================  =================================  ===========================
gamma_min      max_gamma_min           gamma_min (a lower bound)          rad
size           min_size (``size``)     max_sum, max_longest, max_footprint  length, length, length^2
peak_accel     min_peak_accel          max_peak_accel                     length/s^2 at omega2
peak_velocity  min_peak_velocity       max_peak_velocity                  length/s at omega2
=============  ======================  =================================  ===========================

Peak acceleration is over the problem's ``accel_over`` span ('cycle' or 'working'); peak velocity over the
working (slow) stroke, where it is also the peak crank torque per newton of a constant cutting force.
"""

from __future__ import annotations

import math

OBJECTIVES = (None, "max_gamma_min", "min_size", "min_peak_accel", "min_peak_velocity")
SIZES = ("sum", "longest", "footprint")
# bound condition -> the quantity it bounds (``quantities`` key) and its sense
BOUNDS = {
    "gamma_min": ("gamma_min", "lower"),
    "max_sum": ("sum", "upper"),
    "max_longest": ("longest", "upper"),
    "max_footprint": ("footprint", "upper"),
    "max_peak_accel": ("peak_accel", "upper"),
    "max_peak_velocity": ("peak_velocity", "upper"),
}
SLIDER_ONLY = ("min_peak_accel", "min_peak_velocity", "max_peak_accel", "max_peak_velocity")
UNITS = {"gamma_min": "rad", "sum": "length", "longest": "length", "footprint": "length^2",
         "peak_accel": "length/s^2", "peak_velocity": "length/s",
         "torque_per_newton": "length (N m per N)"}  # fmt: skip


def maximises(objective: str | None) -> bool:
    """Whether the objective is maximised (only max_gamma_min)."""
    return objective == "max_gamma_min"


def measured(objective: str, size: str = "sum") -> str:
    """The quantity an objective optimises: 'gamma_min', a size measure, 'peak_accel' or 'peak_velocity'."""
    if objective == "min_size":
        return size
    return objective[4:]


def bound_of(objective: str, size: str = "sum") -> str:
    """The condition that bounds what an objective optimises (for the epsilon-constraint method)."""
    q = measured(objective, size)
    return next(k for k, (quantity, _) in BOUNDS.items() if quantity == q)


def value(problem, quantity: str, m) -> float:
    """One criterion of a mechanism, exactly, at the problem's omega2 (and accel_over)."""
    if quantity == "gamma_min":
        return m.gamma_min().value
    if quantity in SIZES:
        return m.size(quantity)
    if quantity == "peak_accel":
        return m.peak_acceleration(problem.omega2, problem.accel_over).value
    if quantity == "peak_velocity":
        return m.peak_velocity(problem.omega2).value
    raise KeyError(quantity)


def in_nlp_terms(quantity: str, v: float, omega2: float) -> float:
    """A criterion's value as the NLP states it: cos gamma_min, accelerations per omega2^2 and velocities per
    |omega2| (the NLP works at omega2 = 1), sizes as they are."""
    if quantity == "gamma_min":
        return math.cos(v)
    return v / {"peak_accel": omega2**2, "peak_velocity": abs(omega2)}.get(quantity, 1.0)


def objective_for(quantity: str) -> tuple[str, str | None]:
    """(objective, size measure or None) that optimises a criterion: the inverse of ``measured``."""
    if quantity in SIZES:
        return "min_size", quantity
    return ("max_" if quantity == "gamma_min" else "min_") + quantity, None


def violations(problem, m) -> dict:
    """Exact violation (>= 0) of each bound condition of the problem: '<condition> bound (exact)' -> value."""
    out = {}
    for key, (quantity, sense) in BOUNDS.items():
        bound = problem.conditions.get(key)
        if bound is None:
            continue
        v = value(problem, quantity, m)
        out[f"{key} bound (exact)"] = max(0.0, bound - v if sense == "lower" else v - bound)
    return out


def objective_of(problem, m) -> float | None:
    """The problem's objective of a mechanism, exactly; None without one."""
    if not problem.objective:
        return None
    return value(problem, measured(problem.objective, problem.size), m)


def objective_value(problem, q) -> float | None:
    """The problem's objective read from a quantities dict."""
    if not problem.objective:
        return None
    key = measured(problem.objective, problem.size)
    return q["size"] if problem.objective == "min_size" else q.get(key)


def better(problem, a, b) -> bool:
    """Whether objective value a beats b for this problem (None loses)."""
    if b is None:
        return a is not None
    if a is None:
        return False
    return a > b if maximises(problem.objective) else a < b


def finite(v) -> bool:
    """A finite real number (not a bool)."""
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


__all__ = ["OBJECTIVES", "SIZES", "BOUNDS", "UNITS", "maximises", "measured", "bound_of", "objective_for",
           "in_nlp_terms", "value", "violations", "objective_of", "objective_value", "better", "finite"]  # fmt: skip
