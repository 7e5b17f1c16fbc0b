"""NLP backends behind one small protocol: a Formulation, a start, parameters and bounds in; a ``Run`` out.

IPOPT (through CasADi) is the default; ``Scipy`` runs SLSQP or trust-constr on the same Formulation with its
exact derivatives (the benchmarks' baselines). Each backend reads its own statuses here, once, into ``Status``.
"""

from __future__ import annotations

import enum
import math
import weakref
from dataclasses import dataclass
from typing import Protocol

import casadi
import numpy as np

from qropt.synthesis.formulation import IPOPT


class Status(enum.Enum):
    """How a local run ended, whatever the backend."""

    SOLVED = "solved"
    ACCEPTABLE = "acceptable"  # to the backend's looser tolerance
    ITERATION_LIMIT = "iteration limit"
    INFEASIBLE = "infeasible"  # the backend found the constraints locally infeasible
    STALLED = "stalled"  # steps too small to go on: maybe converged, to a tolerance too tight to show it
    FAILED = "failed"  # invalid numbers, a failed restoration, an error


CONVERGED = (Status.SOLVED, Status.ACCEPTABLE)


@dataclass(frozen=True)
class Run:
    """One local run: the point w, objective f and constraint values g; its Status, the backend's own word for
    it (``message``), iterations and wall time (s); the multipliers of the rows and of the bounds where the backend
    gives them (IPOPT's signs: positive at an upper bound), for a continuation to start from."""

    w: np.ndarray
    f: float
    g: np.ndarray
    status: Status
    message: str
    iterations: int
    seconds: float
    lam_g: np.ndarray | None = None
    lam_x: np.ndarray | None = None

    @property
    def converged(self) -> bool:
        return self.status in CONVERGED


class Backend(Protocol):
    """A local NLP solver: ``run(form, w0, p, lbx, ubx, warm)``; warm: a re-solve from a converged point."""

    name: str

    def run(self, form, w0, p, lbx, ubx, warm: bool = False) -> Run: ...


IPOPT_STATUS = {
    "Solve_Succeeded": Status.SOLVED,
    "Solved_To_Acceptable_Level": Status.ACCEPTABLE,
    "Maximum_Iterations_Exceeded": Status.ITERATION_LIMIT,
    "Infeasible_Problem_Detected": Status.INFEASIBLE,
    "Search_Direction_Becomes_Too_Small": Status.STALLED,
}
WARM = {"ipopt.bound_push": 1e-8, "ipopt.bound_frac": 1e-8}
PUSH = 0.01  # IPOPT's default bound_push: a start this near a bound (relative to it, at least 1) would move
NEAR_MU = 1e-6  # the barrier's first value for a start at an optimum of a nearby problem (``Ipopt.near``)
NEAR = {"ipopt.mu_strategy": "monotone", "ipopt.mu_init": NEAR_MU}
DERIVATIVES = {"grad_f": "grad_f", "jac_g": "jac_g", "hess_lag": "hess_l"}  # nlpsol's option -> nlp_<its function>
# A formulation's derivatives are built by its first solver and given to the others (warm, near, patient, each
# objective scale, every backend's): a solver that builds its own costs many times the memory and build time of one
# given them, and a process holding many such solvers grows without need; the same functions, the same numbers
_DERIVATIVES: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
STALLED_KKT = 1e-9  # an IPOPT run stopped short of its tolerance is acceptable at a KKT point to this, relative


def _push(bound) -> np.ndarray:
    """How far IPOPT's default bound_push moves a start inside each bound: PUSH of its magnitude, at least PUSH."""
    return PUSH * np.maximum(1.0, np.abs(np.where(np.isfinite(bound), bound, 0.0)))


def objective_scale(form, w0, p) -> float:
    """1, or for a dynamic objective (newtons, newton-metres, their squares) the power of ten that brings its value
    at the start to order one: IPOPT's tolerance (1e-12) is absolute, below the rounding of a peak force of 1e3 N
    (an N^2 epigraph of 1e6 cannot meet it and runs to the iteration limit)."""
    c = form.objective
    if c is None or not c.needs_masses:
        return 1.0
    f = abs(float(form.objective_function(w0, p)))
    return 10.0 ** -math.ceil(math.log10(f)) if math.isfinite(f) and f > 10.0 else 1.0


class Ipopt:
    """IPOPT through CasADi, one compiled solver per formulation (two: re-solves, and starts on or near a bound,
    move off a bound by 1e-8 only, since IPOPT's default push of 0.01 is absolute and can move a small link across a
    Grashof or assembly limit, where the loop has no real solution, or a start that meets its targets far from
    them; and a re-solve of a dynamic objective one per objective scale, ``objective_scale``), all given the
    formulation's derivatives built once (``DERIVATIVES``)."""

    name = "ipopt"
    PATIENCE = 4  # a patient run's iteration limit, in multiples of the default's

    def __init__(self, options: dict | None = None):
        self.given = dict(options or {})  # the caller's, which the variants below keep
        self.options = {**IPOPT, **self.given}
        self._solvers: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
        self._patient = self._near = None

    def patient(self) -> Ipopt:
        """The same backend with PATIENCE times the iteration limit (for a start known to be near an optimum of
        a nearby problem, where a first run can need more iterations than a blind start's budget)."""
        if self._patient is None:
            limit = self.PATIENCE * int(self.options.get("ipopt.max_iter", 3000))
            self._patient = Ipopt({**self.given, "ipopt.max_iter": limit})
        return self._patient

    def near(self) -> Ipopt:
        """The same backend with a barrier that starts at NEAR_MU and falls monotonically, for a run that starts at
        or near an optimum: an exchange loop's re-solve (the last round's optimum, a few samples added) and a start
        from the atlas or a neighbour's design. The adaptive barrier's first large steps move such a start off its
        active constraints, often to another local optimum: a re-solve can end at a design whose dead centres are
        local (no design), and a walk from one of the atlas's nodes to the next can leave the branch this one keeps.
        A barrier option the caller gave stays theirs."""
        if self._near is None:
            self._near = Ipopt({**NEAR, **self.given})
        return self._near

    def solver(self, form, warm: bool = False, scale: float = 1.0):
        """The compiled solver of ``form`` (its objective scaled by ``scale``, ``objective_scale``)."""
        kept = self._solvers.setdefault(form, {})
        key = (warm, scale)
        if key not in kept:
            opts = {**WARM, **self.options} if warm else dict(self.options)
            if scale != 1.0:
                opts["ipopt.obj_scaling_factor"] = scale
            shared = _DERIVATIVES.setdefault(form, {})
            kept[key] = s = casadi.nlpsol("qropt_warm" if warm else "qropt", "ipopt", form.nlp, {**opts, **shared})
            # a quasi-Newton solver (IPOPT's hessian_approximation limited-memory) has no Hessian to give
            shared.update(
                {
                    k: s.get_function(f"nlp_{n}")
                    for k, n in DERIVATIVES.items()
                    if k not in shared and s.has_function(f"nlp_{n}")
                }
            )
        return kept[key]

    def run(self, form, w0, p, lbx, ubx, warm: bool = False) -> Run:
        w0 = np.clip(w0, lbx, ubx)
        # a start on a bound (a family's end), or nearer one than IPOPT's default push would move it (an optimum
        # with a link at its bound, from the atlas or a neighbour), stays where it is
        on_bound = bool(np.any((w0 - lbx < _push(lbx)) | (ubx - w0 < _push(ubx))))
        solver = self.solver(form, warm or on_bound, objective_scale(form, w0, p) if warm else 1.0)
        r = solver(x0=w0, p=p, lbx=lbx, ubx=ubx, lbg=form.lbg, ubg=form.ubg)
        st = solver.stats()
        word = st.get("return_status", "?")
        status = IPOPT_STATUS.get(word, Status.SOLVED if st.get("success") else Status.FAILED)
        if status in (Status.STALLED, Status.ITERATION_LIMIT) and self._stationary(form, r, p, lbx, ubx):
            status, word = Status.ACCEPTABLE, f"{word} (a KKT point to {STALLED_KKT:g} of its own scale)"
        return Run(
            np.array(r["x"]).ravel(),
            float(r["f"]),
            np.array(r["g"]).ravel(),
            status,
            word,
            int(st.get("iter_count", 0)),
            float(st.get("t_wall_total", 0.0)),
            np.array(r["lam_g"]).ravel(),
            np.array(r["lam_x"]).ravel(),
        )

    def _stationary(self, form, r, p, lbx, ubx) -> bool:
        """Whether a run that stopped short of IPOPT's tolerance (stalled, or at the iteration limit) ends at a KKT
        point relative to its own scale: the Lagrangian's gradient (with the bounds' multipliers) within
        STALLED_KKT of the largest of its terms, each multiplier times its distance to its bound within
        STALLED_KKT of the objective, and every constraint met to STALLED_KKT of the largest. The dynamic
        criteria's rows are in N^2, where IPOPT's absolute tolerance can be below the rounding of a converged
        point."""
        f = getattr(form, "_kkt_terms", None)
        if f is None:
            lam = casadi.SX.sym("lam", form.g_sym.numel())
            w, g = form.w_sym, form.g_sym
            grad_f = casadi.gradient(form.f_sym, w)
            f = form._kkt_terms = casadi.Function("kkt", [w, form.p_sym, lam], [grad_f, casadi.jtimes(g, w, lam, True)])
        x, g = np.array(r["x"]).ravel(), np.array(r["g"]).ravel()
        lam_x, lam_g = np.array(r["lam_x"]).ravel(), np.array(r["lam_g"]).ravel()
        grad_f, jl = (np.array(v).ravel() for v in f(x, p, lam_g))
        scale = max(1.0, np.max(np.abs(grad_f)), np.max(np.abs(jl), initial=0.0), np.max(np.abs(lam_x), initial=0.0))
        if np.max(np.abs(grad_f + jl + lam_x)) > STALLED_KKT * scale:
            return False
        lbx, ubx = np.broadcast_to(lbx, x.shape), np.broadcast_to(ubx, x.shape)
        slack = [np.where(lam_x > 0, ubx - x, x - lbx), np.where(lam_g > 0, form.ubg - g, g - form.lbg)]
        with np.errstate(invalid="ignore"):  # an infinite bound with a zero multiplier: no term
            comp = [np.where(lam == 0, 0.0, np.abs(lam) * s) for lam, s in zip((lam_x, lam_g), slack, strict=True)]
        if max(np.max(c, initial=0.0) for c in comp) > STALLED_KKT * max(1.0, abs(float(r["f"]))):
            return False
        violation = np.maximum(np.maximum(form.lbg - g, g - form.ubg), 0.0)
        return bool(np.max(violation, initial=0.0) <= STALLED_KKT * max(1.0, np.max(np.abs(g), initial=0.0)))


class Scipy:
    """scipy.optimize.minimize (SLSQP or trust-constr) on a Formulation's functions with exact derivatives."""

    def __init__(self, method: str = "SLSQP"):
        self.method, self.name = method, method.lower()

    def run(self, form, w0, p, lbx, ubx, warm: bool = False) -> Run:
        import time

        from scipy.optimize import NonlinearConstraint, minimize

        fn, calls, t0 = form.functions, [0], time.perf_counter()

        def f(w):
            calls[0] += 1
            return float(fn(w, p)[0])

        def df(w):
            return np.array(fn(w, p)[2]).ravel()

        def g(w):
            return np.array(fn(w, p)[1]).ravel()

        def dg(w):
            return np.array(fn(w, p)[3])

        w0 = np.clip(w0, lbx, ubx)
        bounds = list(zip(np.where(np.isfinite(lbx), lbx, None), np.where(np.isfinite(ubx), ubx, None), strict=True))
        lb, ub = form.lbg, form.ubg
        with np.errstate(all="ignore"):
            try:
                if self.method == "SLSQP":
                    eq, lo, hi = lb == ub, (lb != ub) & np.isfinite(lb), (lb != ub) & np.isfinite(ub)
                    cons = [
                        {"type": "eq", "fun": lambda w: g(w)[eq] - lb[eq], "jac": lambda w: dg(w)[eq]},
                        {"type": "ineq", "fun": lambda w: g(w)[lo] - lb[lo], "jac": lambda w: dg(w)[lo]},
                        {"type": "ineq", "fun": lambda w: ub[hi] - g(w)[hi], "jac": lambda w: -dg(w)[hi]},
                    ]
                    r = minimize(
                        f,
                        w0,
                        jac=df,
                        bounds=bounds,
                        constraints=cons,
                        method="SLSQP",
                        options={"ftol": 1e-12, "maxiter": 300},
                    )
                    status = Status.SOLVED if r.success else Status.ITERATION_LIMIT if r.status == 9 else Status.FAILED
                else:
                    con = NonlinearConstraint(g, lb, ub, jac=dg)
                    r = minimize(
                        f,
                        w0,
                        jac=df,
                        bounds=bounds,
                        constraints=[con],
                        method="trust-constr",
                        options={"gtol": 1e-10, "xtol": 1e-12, "maxiter": 200},
                    )
                    status = Status.SOLVED if r.success else Status.FAILED
            except (ValueError, np.linalg.LinAlgError) as e:
                return Run(
                    np.full(w0.size, np.nan),
                    np.nan,
                    np.full(lb.size, np.nan),
                    Status.FAILED,
                    str(e),
                    calls[0],
                    time.perf_counter() - t0,
                )
        w = np.asarray(r.x, float)
        if not np.all(np.isfinite(w)):
            status = Status.FAILED
        gv = g(w) if np.all(np.isfinite(w)) else np.full(lb.size, np.nan)
        return Run(w, float(r.fun), gv, status, str(r.message), calls[0], time.perf_counter() - t0)


__all__ = ["Status", "CONVERGED", "Run", "Backend", "Ipopt", "Scipy"]
