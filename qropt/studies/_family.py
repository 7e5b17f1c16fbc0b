"""One-parameter families of designs: pseudo-arclength continuation of the curves that appear when a
problem has one more free parameter than equality targets (e.g. r1 and r3 free at a fixed TR).

The curve is F(u) = 0 for u = (free parameters, theta_max, theta_min), F being the NLP's equality rows
(zero output velocity at both dead centres, the TR equality, the stroke equality), with CasADi
Jacobians. Predictor along the tangent, Newton corrector on the hyperplane normal to it, adaptive
step. Ends at bounds and condition boundaries are located exactly; folds (where the number of designs
for a given value of the ``along`` parameter changes) are refined by bisection on arclength.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field
from functools import cached_property

import casadi
import numpy as np

from qropt.errors import ProblemError, QroptError
from qropt.synthesis import criteria
from qropt.synthesis import starts as starts_
from qropt.synthesis.certificate import quantities
from qropt.synthesis.problem import Problem
from qropt.synthesis.solver import DEFAULT, Solver

NEWTON_TOL = 1e-12
MAX_POINTS = 100_000  # points one trace may take (each half of a branch): a cap, not a target
MIN_DS = 1e-6  # the smallest ds, relative to the free box's diagonal (and at least 1e-12 of the largest bound)


@dataclass(frozen=True)
class FamilyPoint:
    """A design on a family: params (all), dead-centre crank angles (rad), arclength, the largest equation
    residual |F| (dead-centre velocities, TR, stroke); quantities on demand."""

    problem: Problem = field(repr=False)
    params: dict
    theta: tuple
    arclength: float
    residual: float = 0.0

    @cached_property
    def mechanism(self):
        return self.problem.mechanism(**self.params, units=self.problem.units)

    @cached_property
    def quantities(self) -> dict:
        """Exact time_ratio, stroke or swing, gamma_min (rad), peak_accel, grashof, size; {} if it fails."""
        try:
            return quantities(self.problem, self.mechanism)
        except QroptError:
            return {}


@dataclass(frozen=True)
class End:
    """Why a branch stops: reason, the branch, which end (0 start, 1 end) and the parameters there."""

    branch: int
    side: int
    reason: str
    params: dict


@dataclass
class Family:
    """Traced branches (ordered points), their ends, and folds in the ``along`` parameter."""

    problem: Problem
    along: str
    branches: list
    ends: list
    folds: list
    stats: dict

    def points(self):
        return [p for b in self.branches for p in b]

    def best(self, objective: str = "max_gamma_min", size: str | None = None, sample: int = 200):
        """The best family point for an objective, refined by ``solve()`` into a Result."""
        if not isinstance(objective, str) or objective not in criteria.objectives():
            raise ProblemError(f"best takes an objective from {criteria.objectives()[1:]}, got {objective!r}")
        if isinstance(sample, bool) or not isinstance(sample, (int, np.integer)) or sample < 1:
            raise ProblemError(f"sample is how many family points to score, an integer >= 1; got {sample!r}")
        pts = self.points()
        step = max(1, len(pts) // int(sample))
        chosen = pts[::step] + [b[-1] for b in self.branches]
        changes = {"objective": objective, **({"size": size} if size else {})}
        problem = self.problem.replace(**changes)
        c = criteria.of_problem(problem)

        def score(p):
            if not p.quantities:
                return -math.inf
            v = c.value(problem, p.mechanism)
            return v if c.maximise else -v

        top = sorted(chosen, key=score, reverse=True)[:3]
        free = list(self.problem.free)
        return DEFAULT.solve(
            problem, starts_n=0, use_analytic=False, extra_starts=[{k: p.params[k] for k in free} for p in top]
        )


class _Curve:
    """F, its Jacobian and the inequality rows of one problem structure, as fast CasADi functions."""

    def __init__(self, problem, branch, orientation, solver):
        self.form = form = solver.formulation(problem.replace(objective=None), branch, orientation)
        u = form.design_sym  # the free parameters and the dead centres
        n = u.numel()
        mine = form.design_rows  # a guarded NLP's turn-back rows are in its lifted angles, not in u
        eq = mine[form.lbg[mine] == form.ubg[mine]]
        ineq = mine[form.lbg[mine] != form.ubg[mine]]
        f = form.g_sym[eq.tolist()] - casadi.DM(form.lbg[eq])
        mid = form.midstroke_rows()  # a guarded type's velocity of the stroke's sign mid-stroke
        g = casadi.vertcat(form.g_sym[ineq.tolist()], *[r.expr for r in mid])
        self.fun = casadi.Function("F", [u, form.p_sym], [f, casadi.jacobian(f, u), g])
        self.fj = casadi.Function("FJ", [u, form.p_sym], [f, casadi.jacobian(f, u)])
        self.ineq_rows = [form.rows[i] for i in ineq] + mid
        self.glo = np.concatenate([form.lbg[ineq], [r.lb for r in mid]])
        self.ghi = np.concatenate([form.ubg[ineq], [r.ub for r in mid]])
        self.n = n
        lo, hi = form.bounds(problem)
        self.lo, self.hi = lo[form.design], hi[form.design]
        samples, fractions = form.base_samples()
        self.p = form.param_vector(problem, dict(problem.targets), samples, fractions)
        self.free = form.free

    def eval(self, u):
        """(F, dF/du, inequality rows) at u."""
        f, j, g = self.fun(u, self.p)
        return np.array(f).ravel(), np.array(j), np.array(g).ravel()

    def eval_fj(self, u):
        """(F, dF/du) at u: what a Newton step needs."""
        f, j = self.fj(u, self.p)
        return np.array(f).ravel(), np.array(j)

    def violation(self, g):
        """(largest violation, row index) of the inequality rows."""
        v = np.maximum(self.glo - g, g - self.ghi)
        k = int(np.argmax(v))
        return float(v[k]), k

    def tangent(self, j, previous):
        a = np.vstack([j, previous])
        b = np.zeros(self.n)
        b[-1] = 1.0
        t = np.linalg.solve(a, b)
        return t / np.linalg.norm(t)

    def correct(self, u, t, pred, extra=None, iters=12):
        """Newton on F = 0 and t.(u - pred) = 0 (or an extra scalar equation): (u, iterations) or None."""
        for k in range(iters):
            if extra is None:
                f, j = self.eval_fj(u)
                r, a = np.append(f, t @ (u - pred)), np.vstack([j, t])
            else:
                f, j, g = self.eval(u)
                e, de = extra(u, g, j)
                r, a = np.append(f, e), np.vstack([j, de])
            if not np.all(np.isfinite(r)) or not np.all(np.isfinite(a)):
                return None
            try:
                du = np.linalg.solve(a, -r)
            except np.linalg.LinAlgError:
                return None
            u = u + du
            if np.max(np.abs(du)) <= NEWTON_TOL * max(1.0, np.max(np.abs(u))) and np.max(np.abs(f)) < 1e-9:
                f, j, g = self.eval(u)  # one more step: the residual falls to rounding level
                e, de = (0.0, t) if extra is None else extra(u, g, j)
                r, a = np.append(f, e), np.vstack([j, de])
                with np.errstate(all="ignore"):
                    u2 = u + np.linalg.solve(a, -r)
                f2 = self.eval_fj(u2)[0]
                if np.all(np.isfinite(f2)) and np.max(np.abs(f2)) <= np.max(np.abs(f)):
                    u, f = u2, f2
                return (u, k + 1) if np.max(np.abs(f)) <= 1e-10 else None
        return None

    def project(self, u, iters=30):
        """Gauss-Newton onto F = 0 (minimal-norm steps): the nearest curve point, or None."""
        for _ in range(iters):
            f, j = self.eval_fj(u)
            if not np.all(np.isfinite(f)) or not np.all(np.isfinite(j)):
                return None
            du = -np.linalg.lstsq(j, f, rcond=None)[0]
            u = u + du
            if np.max(np.abs(du)) <= NEWTON_TOL * max(1.0, np.max(np.abs(u))):
                f, _ = self.eval_fj(u)
                return u if np.max(np.abs(f)) <= 1e-10 else None
        return None


def family(
    problem: Problem,
    along: str | None = None,
    *,
    ds: float | None = None,
    max_points: int = 5000,
    starts_n: int = 8,
    seed: int = 0,
    progress=None,
    solver: Solver | None = None,
) -> Family:
    """Trace every branch of a one-parameter family of designs.

    along: the parameter in which folds are counted (default: the first free one); ds: the largest
    arclength step (default 1/200 of the free box's diagonal; at least MIN_DS of it, and 1e-12 of the largest
    bound, so that points differ); max_points: the most points one trace takes (at most MAX_POINTS);
    starts_n, seed: the Sobol seeds of the branches; progress: callable(points traced);
    solver: whose formulations to use (default ``qropt.synthesis.solver.DEFAULT``).
    """
    if not isinstance(problem, Problem):
        raise ProblemError(f"family takes a qropt.Problem, got {type(problem).__name__}")
    if ds is not None and not (isinstance(ds, (int, float)) and not isinstance(ds, bool) and 0 < ds < math.inf):
        raise ProblemError(f"ds is the largest arclength step, a positive number; got {ds!r}")
    if isinstance(max_points, bool) or not isinstance(max_points, int) or not 2 <= max_points <= MAX_POINTS:
        raise ProblemError(f"max_points must be an integer from 2 to {MAX_POINTS:,}, got {max_points!r}")
    for name, v in (("starts_n", starts_n), ("seed", seed)):
        if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 0:
            raise ProblemError(f"{name} must be an integer >= 0, got {v!r}")
    if progress is not None and not callable(progress):
        raise ProblemError("progress must be a callable(points traced) or None")
    if solver is not None and not isinstance(solver, Solver):
        raise ProblemError(f"solver is a qropt.Solver or None, got {type(solver).__name__}")
    solver = solver or DEFAULT
    n_free, n_targets = len(problem.free), len(problem.targets)
    if n_free != n_targets + 1:
        raise ProblemError(f"a family needs one more free parameter than targets: {n_free} free, {n_targets} targets")
    if along is not None and not isinstance(along, str):
        raise ProblemError(f"along is the name of a free parameter ({list(problem.free)}), got {along!r}")
    along = along or next(iter(problem.free))
    if along not in problem.free:
        raise ProblemError(f"along={along!r} is not a free parameter ({list(problem.free)})")
    box = np.array([hi - lo for lo, hi in problem.free.values()])
    diagonal = float(np.linalg.norm(box))
    least = max(MIN_DS * diagonal, 1e-12 * max(abs(b) for bounds in problem.free.values() for b in bounds))
    if ds is not None and ds < least:
        raise ProblemError(
            f"ds = {ds:g} is below {least:.3g} {problem.units} (MIN_DS = {MIN_DS:g} of the free "
            "box's diagonal, and 1e-12 of its largest bound): its points would not differ"
        )
    ds_max = ds or diagonal / 200
    traced, ends, folds, n_points = [], [], [], 0
    seeds = list(starts_.plan(problem).analytic) + starts_.sobol(problem, starts_n, seed)
    for br, way in itertools.product(starts_.branches(problem), (1, -1)):
        curve = _Curve(problem, br, way, solver)
        ia = curve.free.index(along)
        for v in seeds:
            u0 = _seed(problem, curve, v, br, way)
            if u0 is None or _on_traced(u0, traced, ds_max):
                continue
            halves = []
            for direction in (1.0, -1.0):
                pts, end, fl = _trace(curve, u0, direction, ds_max, max_points, ia, progress)
                halves.append((pts, end))
                folds += [(curve, br, u) for u in fl]
            (back, end0), (fwd, end1) = halves[1], halves[0]
            us = back[::-1] + fwd[1:]
            if len(us) < 2:
                continue
            b = len(traced)
            traced.append((curve, br, us))
            ends += [
                End(b, 0, end0, _params(problem, curve, us[0], br)),
                End(b, 1, end1, _params(problem, curve, us[-1], br)),
            ]
            n_points += len(us)
    out = []
    for curve, br, us in traced:
        s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(np.array(us), axis=0), axis=1))])
        res = [float(np.max(np.abs(curve.eval_fj(u)[0]))) for u in us]
        out.append(
            [
                FamilyPoint(problem, _params(problem, curve, u, br), (u[-2], u[-1]), float(a), r)
                for u, a, r in zip(us, s, res, strict=True)
            ]
        )
    fold_params = [_params(problem, c, u, br) for c, br, u in folds]
    return Family(problem, along, out, ends, fold_params, {"points": n_points, "branches": len(out)})


def _params(problem, curve, u, br):
    return {**problem.fixed, **dict(zip(curve.free, u[: len(curve.free)].tolist(), strict=True)), **br}


def _seed(problem, curve, values, br, way):
    try:
        m = problem.build(values, br)
        d = m.dead_centres()
        th = (d.theta_max, d.theta_max + m.stroke_angles()[0])
    except QroptError:
        return None
    u = np.array([values[k] for k in curve.free] + list(th), float)
    u = curve.project(u)
    if (
        u is None
        or np.any(u[: len(curve.free)] < curve.lo[: len(curve.free)])
        or np.any(u[: len(curve.free)] > curve.hi[: len(curve.free)])
    ):
        return None
    _, _, g = curve.eval(u)
    return u if curve.violation(g)[0] <= 1e-9 else None


def _on_traced(u, traced, ds_max):
    for _, _, us in traced:
        d = np.min(np.linalg.norm(np.array(us)[:, : len(u) - 2] - u[: len(u) - 2], axis=1))
        if d < 2 * ds_max:
            return True
    return False


def _trace(curve, u0, direction, ds_max, max_points, ia, progress):
    """Follow the curve from u0 one way: (points, end reason, fold points)."""
    f, j, g = curve.eval(u0)
    t = curve.tangent(j, np.eye(curve.n)[ia] * direction + 1e-3)
    t = t * np.sign(t[ia] * direction) if t[ia] != 0 else t
    pts, folds, ds, u = [u0], [], ds_max / 4, u0
    nf = len(curve.free)
    while len(pts) < max_points:
        pred = u + ds * t
        res = curve.correct(pred, t, pred)
        if res is None:
            ds /= 2
            if ds < 1e-10 * ds_max:
                return pts, _singular_reason(curve, u), folds
            continue
        un, iters = res
        _, jn, gn = curve.eval(un)
        tn = curve.tangent(jn, t)
        # bounds of the free parameters: stop exactly on the bound
        out = np.flatnonzero((un[:nf] < curve.lo[:nf]) | (un[:nf] > curve.hi[:nf]))
        if out.size:
            k = int(out[0])
            bound = curve.lo[k] if un[k] < curve.lo[k] else curve.hi[k]
            hit = curve.correct(u, t, u, extra=lambda x, g, j, k=k, b=bound: (x[k] - b, np.eye(curve.n)[k]))
            if hit is not None:
                pts.append(hit[0])
            return pts, f"bound: {curve.free[k]} = {bound:g}", folds
        viol, row = curve.violation(gn)
        if viol > 1e-12:
            name = curve.ineq_rows[row].name
            lo_b, hi_b = curve.glo[row], curve.ghi[row]
            target = lo_b if gn[row] < lo_b else hi_b

            def edge(x, g, jj, row=row, target=target):
                val = g[row] - target
                eps = 1e-7
                grad = np.array(
                    [
                        (curve.eval(x + eps * e)[2][row] - curve.eval(x - eps * e)[2][row]) / (2 * eps)
                        for e in np.eye(curve.n)
                    ]
                )
                return val, grad

            hit = curve.correct(u, t, u, extra=edge)
            if hit is not None:
                pts.append(hit[0])
            return pts, f"condition: {name}", folds
        if np.sign(tn[ia]) != np.sign(t[ia]) and t[ia] != 0:
            fold = _fold(curve, u, t, ds, ia)
            if fold is not None:
                folds.append(fold)
        if len(pts) > 10 and np.linalg.norm(un[:nf] - pts[0][:nf]) < 0.5 * ds and np.dot(tn[:nf], t[:nf]) > 0:
            pts.append(pts[0])
            return pts, "closed loop", folds
        pts.append(un)
        u, t = un, tn
        if progress is not None:
            progress(1)
        ds = min(ds_max, ds * 1.5) if iters <= 3 else ds / 2 if iters >= 6 else ds
    return pts, f"max_points ({max_points}) reached", folds


def _singular_reason(curve, u):
    """Why the corrector fails at u: a condition row at its bound (e.g. a Grashof change point), or not."""
    _, _, g = curve.eval(u)
    slack = np.minimum(np.abs(g - curve.glo), np.abs(curve.ghi - g)) / np.maximum(1.0, np.abs(g))
    k = int(np.argmin(slack))
    if slack[k] < 1e-6:
        name = curve.ineq_rows[k].name
        what = "Grashof change point" if name.startswith("grashof") else "condition boundary"
        return f"singularity at a {what} ({name} holds with equality): the linkage degenerates"
    return "singularity: the corrector fails (the Jacobian loses rank)"


def _fold(curve, u, t, ds, ia):
    """The fold between u and u + ds t (the along-component of the tangent changes sign), by bisection."""
    lo, hi = 0.0, ds
    best = None
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        pred = u + mid * t
        res = curve.correct(pred, t, pred)
        if res is None:
            return best
        um = res[0]
        _, jm, _ = curve.eval(um)
        tm = curve.tangent(jm, t)
        best = um
        if np.sign(tm[ia]) == np.sign(t[ia]):
            lo = mid
        else:
            hi = mid
        if hi - lo < 1e-14:
            break
    return best
