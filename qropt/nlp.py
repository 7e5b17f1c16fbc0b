"""Problem -> CasADi NLP for IPOPT, built once per problem structure.

Decision variables: the free parameters, the dead-centre crank angles
(theta_max, theta_min) and epigraph variables z. The dead centres are lifted:
the output velocity vanishes there and its curvature has the right sign, so
TR is the linear equality ``theta_min - theta_max = 2 pi TR / (TR + 1)`` (or
``2 pi / (TR + 1)``, by orientation) and the stroke a difference of two
positions. Continuous-cycle quantities (transmission cosines, rod assembly
margins, accelerations, joint coordinates) enter through sample angles that
are CasADi parameters, so an exchange loop can add angles without a rebuild;
the four-bar joint's transmission extremes are exact at theta2 = 0 and pi.
Fixed parameters and targets are CasADi parameters too.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import casadi
import numpy as np

from qropt.closures import RIGHT_ANGLE, transmission_cos
from qropt.mechanisms import FourBar, FourBarSlider
from qropt.ops import CASADI

TWO_PI = 2.0 * math.pi
BASE_SAMPLES = 8  # uniform sample angles of the epigraphs; the exchange loop adds what binds
LIFTED = 2  # lifted acceleration extremes for min_peak_accel
EXTRA_SAMPLES = 8  # slots for the exchange loop's angles
IPOPT = {
    "ipopt.print_level": 0,
    "ipopt.sb": "yes",
    "print_time": 0,
    "record_time": True,
    "ipopt.tol": 1e-12,
    "ipopt.acceptable_tol": 1e-9,
    "ipopt.max_iter": 60,
    "ipopt.mu_strategy": "adaptive",
    "ipopt.bound_relax_factor": 0.0,
    "show_eval_warnings": False,
    "calc_lam_p": False,
}


def slow_interval(time_ratio, orientation):
    """theta_min - theta_max (rad): the slow interval if orientation = +1, else the fast one."""
    return TWO_PI * (time_ratio if orientation > 0 else 1.0) / (time_ratio + 1.0)


@dataclass
class Row:
    name: str
    expr: object
    lb: float
    ub: float


class Formulation:
    """The NLP of one problem structure: branch signs, orientation and (optionally) a target to range.

    ``range_target``: drop that target's equality and make its value the objective (``sense`` +1
    minimises, -1 maximises); used for reachable ranges.
    """

    def __init__(self, problem, branch: dict, orientation: int, range_target: str | None = None, sense: int = 1,
                 base_samples: int = BASE_SAMPLES, extra_samples: int = EXTRA_SAMPLES,
                 ipopt: dict | None = None):  # fmt: skip
        self.problem, self.branch, self.orientation = problem, dict(branch), orientation
        self.range_target, self.sense = range_target, sense
        cls = problem.mechanism
        self.free, self.fixed = list(problem.free), list(problem.fixed)
        self.targets = [k for k in problem.targets if k != range_target]
        self.n_base, self.n_extra = base_samples, extra_samples
        self.n_samples = base_samples + extra_samples
        X = casadi.SX.sym("x", len(self.free))
        TH = casadi.SX.sym("th", 2)
        PF = casadi.SX.sym("pf", len(self.fixed))
        PT = casadi.SX.sym("pt", len(self.targets))
        S = casadi.SX.sym("s", self.n_samples)
        W = casadi.SX.sym("w", self.n_samples)  # fractions of the working arc
        self._W = W
        params = {k: X[i] for i, k in enumerate(self.free)}
        params.update({k: PF[i] for i, k in enumerate(self.fixed)})
        params.update(self.branch)
        t = casadi.SX.sym("t")
        lp = cls.loop(CASADI, t, params)
        four_bar = issubclass(cls, (FourBar, FourBarSlider))
        exact_joints = ["B"] if four_bar else []
        self.sampled_joints = [j for j, v in lp.transmission.items() if v is not RIGHT_ANGLE and j not in exact_joints]
        self.exact_joints = exact_joints
        margins = [m for what, m in lp.margins if not (four_bar and "four-bar" in what)]
        dx = casadi.jacobian(lp.x, t)
        ddx = casadi.jacobian(dx, t)
        dddx = casadi.jacobian(ddx, t)
        cos_all = [transmission_cos(CASADI, lp.transmission[j]) for j in self.exact_joints + self.sampled_joints]
        coords = [c for pt in lp.points.values() for c in pt]
        kin = casadi.Function(
            "kin",
            [t, X, PF],
            [lp.x, dx, ddx, casadi.vertcat(*cos_all, 0), casadi.vertcat(*margins, 0), casadi.vertcat(*coords), dddx],
        )
        n_exact = len(self.exact_joints)

        def at(theta):
            return kin(theta, X, PF)

        x_max, v_max, a_max, *_ = at(TH[0])
        x_min, v_min, a_min, *_ = at(TH[1])
        span = TH[1] - TH[0]
        rows = [
            Row("dead centre theta_max: output velocity", v_max, 0.0, 0.0),
            Row("dead centre theta_min: output velocity", v_min, 0.0, 0.0),
            Row("dead centre theta_max: a maximum", a_max, -casadi.inf, 0.0),
            Row("dead centre theta_min: a minimum", a_min, 0.0, casadi.inf),
        ]
        tgt = {k: PT[i] for i, k in enumerate(self.targets)}
        if "time_ratio" in tgt:
            rows.append(Row("time_ratio", span - slow_interval(tgt["time_ratio"], orientation), 0.0, 0.0))
        elif orientation > 0:
            rows.append(Row("time_ratio orientation", span, math.pi, TWO_PI))
        else:
            rows.append(Row("time_ratio orientation", span, 0.0, math.pi))
        travel = x_max - x_min
        for k in ("stroke", "swing"):
            if k in tgt:
                rows.append(Row(k, travel - tgt[k], 0.0, 0.0))
        rows += self._conditions(params, problem)
        # sample angles: absolute, or fractions of the working arc for the working-stroke acceleration
        working = problem.objective == "min_peak_accel" and problem.accel_over == "working"
        start = TH[0] if orientation > 0 else TH[1]
        length = span if orientation > 0 else TWO_PI - span
        sampled = [at(S[k]) for k in range(self.n_samples)]
        exact = [at(a) for a in (0.0, math.pi)]
        self.z_names, epi = self._objective(problem, params, sampled, exact, n_exact, at, start, length, working)
        Z = casadi.SX.sym("z", len(self.z_names))
        # peak acceleration: the largest extremes are lifted like the dead centres (d3x/dtheta3 = 0 there)
        self.n_lift = LIFTED if problem.objective == "min_peak_accel" and not range_target else 0
        PHI = casadi.SX.sym("phi", self.n_lift)
        for k in range(self.n_lift):
            out = at(PHI[k])
            rows.append(Row("lifted acceleration extreme: stationary", out[6], 0.0, 0.0))
            epi += [(0, out[2]), (0, -out[2])]
            if working:
                rows.append(Row("lifted acceleration extreme: in the working stroke", (PHI[k] - start) / length, 0, 1))
        for zi, e in epi:
            rows.append(Row(f"epigraph {self.z_names[zi]}", e - Z[zi], -casadi.inf, 0.0))
        g_min = problem.conditions.get("gamma_min")
        cos_lb = math.cos(g_min) if g_min is not None else None
        for k, out in enumerate(sampled):
            for m in range(len(margins)):
                rows.append(Row(f"rod assembly at sample {k}", out[4][m], 0.0, casadi.inf))
            if cos_lb is not None:
                for j, name in enumerate(self.sampled_joints):
                    c = out[3][n_exact + j]
                    rows.append(Row(f"gamma_min >= bound at joint {name}", c, -cos_lb, cos_lb))
        if cos_lb is not None:
            for out in exact:
                for j, name in enumerate(self.exact_joints):
                    rows.append(Row(f"gamma_min >= bound at joint {name}", out[3][j], -cos_lb, cos_lb))
        f = self._objective_value(problem, params, Z, travel, span)
        self.rows = rows
        w = casadi.vertcat(X, TH, Z, PHI)
        p = casadi.vertcat(PF, PT, S, W)
        g = casadi.vertcat(*[r.expr for r in rows])
        self.w_sym, self.p_sym, self.g_sym = w, p, g
        self.solver = casadi.nlpsol("qropt", "ipopt", {"x": w, "p": p, "f": f, "g": g}, {**IPOPT, **(ipopt or {})})
        self._f = f
        self.epi_fun = casadi.Function("epi", [w, p], [casadi.vertcat(*[e for _, e in epi], 0)])
        self.epi_index = np.array([zi for zi, _ in epi], int)
        self.lbg = np.array([r.lb for r in rows], float)
        self.ubg = np.array([r.ub for r in rows], float)
        self.nx, self.nz = len(self.free), len(self.z_names)

    @functools.cached_property
    def functions(self):
        """The same NLP as plain functions (f, g, df, dg) with exact derivatives, for other solvers."""
        w, p, f, g = self.w_sym, self.p_sym, self._f, self.g_sym
        return casadi.Function(
            "fg", [w, p], [f, g, casadi.gradient(f, w), casadi.jacobian(g, w)], ["w", "p"], ["f", "g", "df", "dg"]
        )

    # ---- pieces --------------------------------------------------------------
    @staticmethod
    def _conditions(params, problem):
        cls, c = problem.mechanism, problem.conditions
        rows = [Row(r.name, r.value, 0.0, casadi.inf) for r in cls.rules(CASADI, params, c.get("grashof"))]
        for coeffs, lo, hi in c.get("linear", ()):
            e = sum(v * params[k] for k, v in coeffs.items())
            rows.append(Row(f"linear {dict(coeffs)}", e, lo, hi))
        for num, den, lo, hi in c.get("ratio", ()):
            rows.append(Row(f"ratio {num}/{den} >= {lo:g}", params[num] - lo * params[den], 0.0, casadi.inf))
            rows.append(Row(f"ratio {num}/{den} <= {hi:g}", params[num] - hi * params[den], -casadi.inf, 0.0))
        return rows

    def _objective(self, problem, params, sampled, exact, n_exact, at, start, length, working):
        obj = None if self.range_target else problem.objective
        epi = []
        if obj == "max_gamma_min":
            for out in exact:
                for j in range(n_exact):
                    epi += [(0, out[3][j]), (0, -out[3][j])]
            for out in sampled:
                for j in range(len(self.sampled_joints)):
                    epi += [(0, out[3][n_exact + j]), (0, -out[3][n_exact + j])]
            return ["max |cos gamma|"], epi
        if obj == "min_peak_accel":
            outs = [at(start + (self._fraction(k) * length)) for k in range(self.n_samples)] if working else sampled
            for out in outs:
                epi += [(0, out[2]), (0, -out[2])]
            return ["peak |d2x/dtheta2|"], epi
        if obj == "min_size" and problem.size == "longest":
            lengths = [params[k] for k in problem.mechanism.LENGTHS if k in params]
            return ["longest link"], [(0, r) for r in lengths]
        if obj == "min_size" and problem.size == "footprint":
            for out in sampled + exact:
                xy = out[5]
                for i in range(xy.shape[0] // 2):
                    epi += [(0, xy[2 * i]), (1, -xy[2 * i]), (2, xy[2 * i + 1]), (3, -xy[2 * i + 1])]
            return ["x_max", "-x_min", "y_max", "-y_min"], epi
        return [], []

    def _fraction(self, k):
        return self._W[k]

    def _objective_value(self, problem, params, Z, travel, span):
        if self.range_target == "time_ratio":
            tr = span / (TWO_PI - span) if self.orientation > 0 else (TWO_PI - span) / span
            return self.sense * tr
        if self.range_target in ("stroke", "swing"):
            return self.sense * travel
        obj = problem.objective
        if obj in ("max_gamma_min", "min_peak_accel") or (obj == "min_size" and problem.size == "longest"):
            return Z[0]
        if obj == "min_size" and problem.size == "footprint":
            return (Z[0] + Z[1]) * (Z[2] + Z[3])
        if obj == "min_size":
            return sum(params[k] for k in problem.mechanism.LENGTHS if k in params)
        return casadi.SX(0)

    # ---- numbers -------------------------------------------------------------
    def base_samples(self):
        """(angles, working-arc fractions): uniform in the base slots; the extra slots repeat the first."""
        angles = TWO_PI * np.arange(self.n_base) / self.n_base
        fractions = np.linspace(0.0, 1.0, self.n_base)
        pad = np.zeros(self.n_extra)
        return np.concatenate([angles, pad]), np.concatenate([fractions, pad])

    def pack(self, values: dict, th, z=None, phi=None):
        x = [values[k] for k in self.free] + list(th) + list(z if z is not None else np.zeros(self.nz))
        phi = list(phi if phi is not None else np.linspace(0.0, math.pi, self.n_lift))[: self.n_lift]
        phi += [0.0] * (self.n_lift - len(phi))
        return np.array(x + phi, float)

    def param_vector(self, targets: dict, samples, fractions, fixed=None):
        fixed = self.problem.fixed if fixed is None else fixed
        pf = [fixed[k] for k in self.fixed]
        pt = [targets[k] for k in self.targets]
        return np.concatenate([pf, pt, samples, fractions]).astype(float)

    def epigraph_start(self, w0, p):
        """z values that make every epigraph row feasible at w0."""
        if not self.nz:
            return w0
        e = np.array(self.epi_fun(w0, p)).ravel()[: self.epi_index.size]
        z = np.full(self.nz, -np.inf)
        np.fmax.at(z, self.epi_index, e)
        z = np.where(np.isfinite(z), z, 0.0)
        w = w0.copy()
        w[self.nx + 2 : self.nx + 2 + self.nz] = z + 1e-9 * np.maximum(1.0, np.abs(z))
        return w

    def bounds(self):
        lo = [self.problem.free[k][0] for k in self.free] + [-2 * TWO_PI, -2 * TWO_PI]
        hi = [self.problem.free[k][1] for k in self.free] + [2 * TWO_PI, 3 * TWO_PI]
        lo += [-np.inf] * self.nz + [-2 * TWO_PI] * self.n_lift
        hi += [np.inf] * self.nz + [3 * TWO_PI] * self.n_lift
        return np.array(lo, float), np.array(hi, float)

    def solve(self, w0, p):
        """One IPOPT run: (w, objective, constraint values, stats)."""
        lbx, ubx = self.bounds()
        w0 = np.clip(w0, lbx, ubx)
        r = self.solver(x0=w0, p=p, lbx=lbx, ubx=ubx, lbg=self.lbg, ubg=self.ubg)
        st = self.solver.stats()
        return np.array(r["x"]).ravel(), float(r["f"]), np.array(r["g"]).ravel(), st

    @functools.cached_property
    def square_rows(self) -> np.ndarray | None:
        """Indices of the equality rows in the free parameters and dead centres (targets, zero velocity), if
        they are as many as those unknowns: the system a closed-form enumeration is polished on."""
        rows = [i for i, r in enumerate(self.rows) if r.lb == r.ub and not r.name.startswith("lifted")]
        return np.array(rows, int) if len(rows) == self.nx + 2 else None

    @functools.cached_property
    def square_system(self):
        """z = [w, p] -> [residual of the square rows, their Jacobian in (free, theta_max, theta_min)
        (column-major)], evaluated without conversions (see kernel.Batched)."""
        from qropt.kernel import Batched

        rows, n = self.square_rows, self.nx + 2
        r = self.g_sym[rows.tolist()] - casadi.DM(self.lbg[rows])
        jac = casadi.jacobian(r, self.w_sym[:n])
        z = casadi.SX.sym("z", self.w_sym.numel() + self.p_sym.numel())
        f = casadi.Function("sq", [self.w_sym, self.p_sym], [casadi.vertcat(r, casadi.vec(jac))])
        return Batched(casadi.Function("sqz", [z], [f(z[: self.w_sym.numel()], z[self.w_sym.numel() :])]))

    @functools.cached_property
    def constraint_values(self):
        """z = [w, p] -> g, evaluated without conversions."""
        from qropt.kernel import Batched

        z = casadi.SX.sym("z", self.w_sym.numel() + self.p_sym.numel())
        f = casadi.Function("g", [self.w_sym, self.p_sym], [self.g_sym])
        return Batched(casadi.Function("gz", [z], [f(z[: self.w_sym.numel()], z[self.w_sym.numel() :])]))

    def violations(self, g):
        """Named constraint violations (>= 0) of constraint values g."""
        v = np.maximum(np.maximum(self.lbg - g, g - self.ubg), 0.0)
        out = {}
        for row, val in zip(self.rows, v, strict=True):
            out[row.name] = max(out.get(row.name, 0.0), float(val))
        return out
