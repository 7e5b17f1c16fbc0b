"""The methods the benchmark compares, each a function (problem, seed) -> dict with the free-parameter
values it returns (or None), its function evaluations and a message. All start from the same points."""

from __future__ import annotations

import importlib

import numpy as np
from scipy.optimize import differential_evolution

from qropt import solve
from qropt.synthesis import starts
from qropt.synthesis.backends import Scipy
from qropt.synthesis.certificate import better
from qropt.synthesis.solver import DEFAULT

STARTS = 8  # Sobol starts for every multi-start method, as qropt's default
FEASIBLE = 1e-6  # a local method's design counts only if it meets the targets this well


def qropt_warm(problem, seed):
    r = solve(problem, starts_n=STARTS, seed=seed)
    return _from_result(problem, r)


def qropt_cold(problem, seed):
    r = solve(problem, starts_n=STARTS, seed=seed, use_analytic=False)
    return _from_result(problem, r)


def _from_result(problem, r):
    values = {k: r.params[k] for k in problem.free} if r.success else None
    return {
        "values": values,
        "nfev": r.stats.get("iterations_total"),
        "message": r.status,
        "branch": r.stats.get("branch"),
    }


def _scipy_local(problem, seed, method):
    """A local scipy method on qropt's NLP functions (exact CasADi derivatives) from qropt's starts (every closed
    form, then the Sobol points, both TR orientations for those); no exchange loop. The best design by exact
    evaluation."""
    from problems import _oracles as oracles

    best, nfev = None, 0
    for _origin, _v, br, _way, form, w0, p in local_starts(problem, seed):
        x, n = local_solve(problem, form, w0, p, method)
        nfev += n
        if x is None:
            continue
        values = form.unpack(x).values
        s = oracles.score(problem, values)
        feasible = s is not None and violation(problem, s[1]) <= FEASIBLE
        if feasible and better(problem, s[0], best[0] if best else None):
            best = (s[0], values, br)
    return {
        "values": best[1] if best else None,
        "nfev": nfev,
        "message": "best converged start" if best else "none",
        "branch": best[2] if best else None,
    }


def local_starts(problem, seed, starts_n=STARTS, solver=DEFAULT):
    """qropt's start points on its formulation: (origin, values, branch, orientation, formulation, w0, p)."""
    pts = [("analytic", v) for v in starts.plan(problem).analytic]
    pts += [("multistart", v) for v in starts.sobol(problem, starts_n, seed)]
    targets = dict(problem.targets)
    for origin, v in pts:
        for br in starts.branches(problem):
            own = starts.orientation(problem, v, br)
            for way in [own] if origin == "analytic" and own else [1, -1]:
                th0, way = starts.dead_centre_start(problem, v, br, targets, way, None)
                form = solver.formulation(problem, br, way)
                samples, fractions = form.base_samples()
                phi, box, turn = form.lifted_start(problem, v, theta=th0)  # the lifted angles, as qropt starts them
                p = form.param_vector(problem, targets, samples, fractions, box=box)
                w0 = form.pack(v, th0, phi=phi, box=box, turn=turn)
                yield origin, v, br, way, form, form.epigraph_start(w0, p), p


def local_solve(problem, form, w0, p, method="SLSQP"):
    """The one scipy driver of the benchmarks: SLSQP or trust-constr through qropt's backend protocol, on a
    formulation with exact derivatives. Returns (w or None, function evaluations)."""
    lbx, ubx = form.bounds(problem)
    run = Scipy(method).run(form, w0, p, lbx, ubx)
    return (run.w if np.all(np.isfinite(run.w)) else None), run.iterations


def scipy_slsqp(problem, seed):
    return _scipy_local(problem, seed, "SLSQP")


def scipy_trust_constr(problem, seed):
    return _scipy_local(problem, seed, "trust-constr")


def scipy_de(problem, seed):
    """differential_evolution over the free parameters: exact objective plus a penalty on target and
    condition violations (a design that does not work scores 1e6)."""
    from problems import _oracles as oracles

    names = list(problem.free)
    sign = -1.0 if problem.objective == "max_gamma_min" else 1.0
    calls = [0]

    def f(x):
        calls[0] += 1
        values = dict(zip(names, x.tolist(), strict=True))
        s = oracles.score(problem, values)
        if s is None:
            return 1e6
        obj, q = s
        return sign * (obj or 0.0) + 1e3 * violation(problem, q)

    r = differential_evolution(
        f, [problem.free[k] for k in names], seed=seed, popsize=10, maxiter=25, tol=1e-12, polish=False, init="sobol"
    )
    ok = r.fun < 1e5
    return {
        "values": dict(zip(names, r.x.tolist(), strict=True)) if ok else None,
        "nfev": calls[0],
        "message": r.message,
        "branch": None,
    }


def violation(problem, q) -> float:
    """Largest violation of a design's targets (relative for lengths) and gamma_min bound."""
    v = 0.0
    for k, t in problem.targets.items():
        got = q.get(k, q.get("swing") if k == "swing" else None)
        v = max(v, abs(got - t) / (abs(t) if k == "stroke" else 1.0))
    bound = problem.conditions.get("gamma_min")
    if bound is not None:
        v = max(v, bound - q["gamma_min"])
    return v


def pylinkage_pso(problem, seed):
    """pylinkage's own particle swarm on a linkage built in pylinkage (four-bars and slider-cranks)."""
    try:
        pl = importlib.import_module("pylinkage")
    except ImportError:
        return {"values": None, "nfev": None, "message": "not installed", "branch": None}
    from benchmarks import pylinkage_adapter

    return pylinkage_adapter.run(pl, problem, seed)


METHODS = {
    "qropt": qropt_warm,
    "qropt-cold": qropt_cold,
    "scipy-slsqp": scipy_slsqp,
    "scipy-trust-constr": scipy_trust_constr,
    "scipy-de": scipy_de,
    "pylinkage": pylinkage_pso,
}
