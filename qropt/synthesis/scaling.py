"""Scale invariance: a problem whose lengths are far from 1 is solved at unit scale and its Result scaled back.

The NLP's and the certificate's tolerances are absolute (IPOPT's 1e-12, a feasibility of 1e-8), so a problem in
micrometres or kilometres would be solved to another relative accuracy than one in metres. The Solver solves
``scaled(problem, k)`` with k = 1 / (its length scale) instead, and scales the Result back by 1 / k: every
length by k^-1, every criterion by k to the power of the lengths in its unit ('length^2', 'length/s^2' ...).
"""

from __future__ import annotations

import dataclasses
import math

from qropt.synthesis import criteria

UNIT_RANGE = (1e-2, 1e2)  # length scales solved as they are


def length_power(unit: str) -> int:
    """How many lengths a unit carries: 'rad' 0, 'length' 1, 'length/s^2' 1, 'length^2' 2."""
    if "length" not in unit:
        return 0
    return 2 if "length^2" in unit else 1


def length_scale(problem) -> float:
    """The problem's characteristic length: its stroke target, else its largest fixed or bounding length."""
    if "stroke" in problem.targets:
        return float(problem.targets["stroke"])
    lengths = [abs(v) for k, v in problem.fixed.items() if k in problem.mechanism.LENGTHS]
    lengths += [hi for k, (_, hi) in problem.free.items() if k in problem.mechanism.LENGTHS]
    return max(lengths, default=1.0)


def factor(problem) -> float:
    """k that brings the problem to unit scale (1.0 where its scale is within UNIT_RANGE): problems that differ
    only in scale are then solved as the same problem, up to rounding."""
    scale = length_scale(problem)
    if UNIT_RANGE[0] <= scale <= UNIT_RANGE[1] or not math.isfinite(scale) or scale <= 0:
        return 1.0
    return 1.0 / scale


def scales(problem, name: str) -> bool:
    """Whether a parameter scales with the lengths: a length or an offset (``Mechanism.scalable()``), not an angle
    or a branch sign."""
    return name in problem.mechanism.scalable()


def scaled(problem, k: float):
    """The problem with every length and offset times k (targets, bounds and bound conditions alike)."""
    if k == 1.0:
        return problem
    bounds = criteria.bounds()
    c = dict(problem.conditions)
    for key, v in list(c.items()):
        if key in bounds:
            c[key] = v * k ** length_power(bounds[key].unit)
    if "linear" in c:
        c["linear"] = [(coeffs, lo * k, hi * k) for coeffs, lo, hi in c["linear"]]
    return problem.replace(
        fixed={n: v * k if scales(problem, n) else v for n, v in problem.fixed.items()},
        free={n: (lo * k, hi * k) for n, (lo, hi) in problem.free.items()},
        targets={n: v * k if n == "stroke" else v for n, v in problem.targets.items()},
        conditions=c,
    )


def unscaled(result, problem, k: float):
    """A Result of ``scaled(problem, k)`` in the problem's own lengths (its mechanism rebuilt there)."""
    if k == 1.0:
        return result
    back = 1.0 / k
    params = {n: problem.fixed.get(n, v * back) if scales(problem, n) else v for n, v in result.params.items()}
    mechanism = None
    if result.mechanism is not None:
        branch = {n: v for n, v in params.items() if n in problem.mechanism.BRANCHES}
        mechanism = problem.build({n: params[n] for n in problem.free}, branch)
    powers = {name: length_power(c.unit) for name, c in criteria.CRITERIA.items()}
    powers |= {"stroke": 1, "size": length_power(criteria.CRITERIA[problem.size].unit), "torque_per_newton": 1}
    q = {
        n: (v * back ** powers[n] if n in powers and isinstance(v, float) else v) for n, v in result.quantities.items()
    }
    objective = result.objective
    if objective is not None and problem.objective:
        objective *= back ** length_power(criteria.of_problem(problem).unit)
    cert = result.certificate
    if cert is not None and problem.objective:
        p = length_power(criteria.of_problem(problem).unit)
        p_gap = 0 if criteria.of_problem(problem).unit == "rad" else p  # gamma_min's gap is in cos terms
        cert = dataclasses.replace(
            cert,
            nlp=None if cert.nlp is None else cert.nlp * back**p,
            certified=None if cert.certified is None else cert.certified * back**p,
            gap=cert.gap * back**p_gap,
        )
    reachable = {
        n: (lo * back ** powers.get(n, 0), hi * back ** powers.get(n, 0)) for n, (lo, hi) in result.reachable.items()
    }
    return dataclasses.replace(
        result,
        params=params,
        mechanism=mechanism,
        objective=objective,
        quantities=q,
        certificate=cert,
        reachable=reachable,
        stats={**result.stats, "length_scale": back},
        local_optima=tuple(unscaled(o, problem, k) for o in result.local_optima),
        continuation=None,  # the scaled NLP's: a continuation from these params starts afresh
    )


__all__ = ["length_power", "length_scale", "factor", "scaled", "unscaled"]
