"""Results made from the pool: the statistics of a solve's candidates, a candidate's Result with its certificate,
and the Result of the certified candidates, best first, its claim rendered from the pool's words."""

from __future__ import annotations

import time

from qropt.synthesis import criteria
from qropt.synthesis.backends import Status
from qropt.synthesis.certificate import Certificate, objective_value, quantities
from qropt.synthesis.multistart import distinct
from qropt.synthesis.result import Result

MESSAGES = {
    "optimal": "certified optimum",
    "feasible": "certified design (no objective)",
    "acceptable": "certified design; IPOPT stopped at its acceptable tolerance",
    "local_optimum": "another certified local optimum",
}


def stats(solver, problem, cands, plan) -> dict:
    """The statistics of a solve's candidates (starts, IPOPT runs, iterations, time)."""
    return {
        "starts": len(cands),
        "plan": plan.kind,
        "omega2": problem.omega2,
        "formulations": solver.formulations,
        "atlas_starts": len(plan.atlas.designs),
        "ipopt_runs": sum(len(c.statuses) for c in cands if c.origin not in ("enumeration", "walk")),
        "iterations_total": sum(c.iterations for c in cands),
        "t_ipopt": sum(c.t_ipopt for c in cands),
    }


def result(solver, problem, c, status, claim, stats, local=()) -> Result:
    """The Result of one certified candidate (status None: by its backend's last end and the objective)."""
    converged_to = c.statuses[-1] if c.statuses else ""
    if status is None:
        acceptable = bool(c.ends) and c.ends[-1] is Status.ACCEPTABLE
        status = "acceptable" if acceptable else "optimal" if problem.objective else "feasible"
    info = c.info
    cert = Certificate(
        exact=info.get("gap", 0.0) <= solver.tolerances["gap"],
        nlp=info.get("nlp"),
        certified=info.get("certified"),
        gap=float(info.get("gap", 0.0)),
        rounds=c.rounds,
        local=converged_to,
        global_claim=claim,
    )
    return Result(
        status=status,
        message=f"{MESSAGES[status]}; global: {claim}",
        params=dict(c.mechanism.params),
        mechanism=c.mechanism,
        objective=objective_value(problem, c.q),
        quantities=c.q,
        residuals=c.residuals,
        certificate=cert,
        continuation=c.hint,
        stats={
            **stats,
            "statuses": list(c.statuses),
            "iterations": c.iterations,
            "t_ipopt_design": c.t_ipopt,
            "branch": dict(c.branch),
            "orientation": c.orientation,
            "origin": c.origin,
        },
        local_optima=tuple(local),
        counterweight=c.problem.masses.counterweight if problem.masses and problem.masses.balancing else None,
    )


def best(solver, problem, cands, claim, plan, t0, guard: str = "") -> Result:
    """The Result of the certified candidates among ``cands``, best first (with every distinct local optimum);
    guard: the global strategies' words (``Pool.guard``)."""
    out = stats(solver, problem, cands, plan)
    good = [c for c in cands if c.ok]
    if not good:
        raise AssertionError("best() of candidates without a certified one")
    for c in good:
        c.q = quantities(c.problem or problem, c.mechanism)
    best_first = sorted(
        distinct(good),
        key=lambda c: objective_value(problem, c.q) or 0.0,
        reverse=criteria.maximises(problem.objective),
    )
    k = len(best_first)
    if not claim:
        shaped = sum(c.origin == "shape" for c in cands)
        related = sum(c.origin == "related" for c in cands)
        how = [f"{shaped} chosen by the objective among {solver.settings.shape_points} grid shapes"] if shaped else []
        how += [f"{related} the atlas's optima of this shape by kinematic objectives"] if related else []
        how = f" ({'; '.join(how)})" if how else ""
        started = sum(c.origin not in ("guard", "wrapped") for c in cands)
        claim = f"best of {k} distinct local optima from {started} starts{how}"
    if guard:
        claim += f"; with {guard}"
    out.update(t_total=time.perf_counter() - t0, local_optima=k)
    local = [result(solver, problem, c, "local_optimum" if i else None, claim, out) for i, c in enumerate(best_first)]
    return result(solver, problem, best_first[0], None, claim, out, local)
