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

from qropt.errors import QroptError
from qropt.kinematics.closures import RIGHT_ANGLE, transmission_cos
from qropt.kinematics.ops import CASADI
from qropt.mechanisms import FourBar, FourBarSlider
from qropt.synthesis.criteria import BOUNDS, in_nlp_terms, measured

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

WARM = {"ipopt.bound_push": 1e-8, "ipopt.bound_frac": 1e-8}


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
            [lp.x, dx, ddx, casadi.vertcat(*cos_all, 0), casadi.vertcat(*margins, 0), casadi.vertcat(*coords), dddx,
             casadi.jacobian(casadi.vertcat(*cos_all, 0), t), casadi.jacobian(casadi.vertcat(*coords), t)],
        )  # fmt: skip
        self.n_coords = len(coords)
        moving = [i for i, c in enumerate(coords) if casadi.depends_on(casadi.SX(c), t)]
        # a box side's default coordinate (before a design names the one that reaches it): the first moving x, y
        self._default_coord = [next((i for i in moving if i % 2 == a), moving[0]) for a in (0, 0, 1, 1)]
        n_exact = len(self.exact_joints)

        def at(theta):
            return kin(theta, X, PF)

        self._dead = [at(TH[0]), at(TH[1])]  # the output's extremes: two sides of the path's box, exactly
        x_max, v_max, a_max, *_ = self._dead[0]
        x_min, v_min, a_min, *_ = self._dead[1]
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
        # sample angles: absolute, or fractions of the working arc (working-stroke acceleration, velocity)
        start = TH[0] if orientation > 0 else TH[1]
        length = span if orientation > 0 else TWO_PI - span
        self._sampled = [at(S[k]) for k in range(self.n_samples)]
        self._exact = [at(a) for a in (0.0, math.pi)]
        self._working = None
        self._at, self._start, self._length, self._n_exact, self._params = at, start, length, n_exact, params
        # criteria: the objective's epigraph group first (z[0]...), then those of the bound conditions
        self.z_names, self._groups, epi = [], {}, []
        obj = None if range_target else problem.objective
        if obj:
            self._group(measured(obj, problem.size), epi)
        self.bounds_used = [k for k in BOUNDS if k in problem.conditions]
        for k in self.bounds_used:
            self._group(BOUNDS[k][0], epi)
        Z = casadi.SX.sym("z", len(self.z_names))
        # lifted extremes, like the dead centres: peak acceleration's largest (d3x/dtheta3 = 0 there) for its objective
        # or bound, the working stroke's peak speeds (d2x/dtheta2 = 0) for theirs, and under a gamma_min bound each
        # sampled joint's worst transmission (d cos/dtheta2 = 0): their crank angles move with the design faster
        # than samples follow them
        self.lifts = []
        if "peak_accel" in self._groups:  # a four-bar-driven slider's acceleration has more extremes of note
            self.lifts += [("accel", None)] * (2 * LIFTED if issubclass(cls, FourBarSlider) else LIFTED)
        if obj == "min_peak_velocity":  # the objective only: as a bound, lifted speeds stall some footprint solves
            self.lifts += [("velocity", None)] * LIFTED
        if "gamma_min" in self.bounds_used:
            self.lifts += [("gamma", joint) for joint in self.sampled_joints for _ in range(LIFTED)]
        self.n_lift = len(self.lifts)
        PHI = casadi.SX.sym("phi", self.n_lift)
        for k, (kind, joint) in enumerate(self.lifts):
            out = at(PHI[k])
            if kind == "gamma":
                j = n_exact + self.sampled_joints.index(joint)
                rows.append(Row("lifted transmission extreme: stationary", out[7][j], 0.0, 0.0))
                i0 = self._groups["gamma_min"]
                epi += [(i0, out[3][j]), (i0, -out[3][j])]
                continue
            if kind == "velocity":  # the working stroke's largest speeds (d2x/dtheta2 = 0 there)
                rows.append(Row("lifted velocity extreme: stationary", out[2], 0.0, 0.0))
                rows.append(Row("lifted velocity extreme: in the working stroke", (PHI[k] - start) / length, 0, 1))
                i0 = self._groups["peak_velocity"]
                epi += [(i0, out[1]), (i0, -out[1])]
                continue
            rows.append(Row("lifted acceleration extreme: stationary", out[6], 0.0, 0.0))
            i0 = self._groups["peak_accel"]
            epi += [(i0, out[2]), (i0, -out[2])]
            if problem.accel_over == "working":
                rows.append(Row("lifted acceleration extreme: in the working stroke", (PHI[k] - start) / length, 0, 1))
        # the footprint's box: each side lifted at the extreme of the coordinate that reaches it (parameters SEL pick
        # that coordinate, one-hot per side, from the last exact box), like the dead centres
        self.n_box = 4 if "box" in self._groups else 0
        PSI = casadi.SX.sym("psi", self.n_box)
        SEL = casadi.SX.sym("sel", self.n_box * self.n_coords)
        for s in range(self.n_box):
            out, pick = at(PSI[s]), SEL[s * self.n_coords : (s + 1) * self.n_coords]
            rows.append(Row(f"lifted box side {self.z_names[self._groups['box'] + s]}: stationary",
                            casadi.dot(pick, out[8]), 0.0, 0.0))  # fmt: skip
            epi.append((self._groups["box"] + s, (1 if s % 2 == 0 else -1) * casadi.dot(pick, out[5])))
        for zi, e in epi:
            rows.append(Row(f"epigraph {self.z_names[zi]}", e - Z[zi], -casadi.inf, 0.0))
        for k in range(self.n_samples):
            for m in range(len(margins)):
                rows.append(Row(f"rod assembly at sample {k}", self._sampled[k][4][m], 0.0, casadi.inf))
        PB = casadi.SX.sym("pb", len(self.bounds_used))
        for i, k in enumerate(self.bounds_used):
            rows.append(Row(f"{k} bound", self._measure(BOUNDS[k][0], Z) - PB[i], -casadi.inf, 0.0))
        f = self._objective_value(problem, Z, travel, span)
        self.rows = rows
        w = casadi.vertcat(X, TH, Z, PHI, PSI)
        p = casadi.vertcat(PF, PT, S, W, PB, SEL)
        g = casadi.vertcat(*[r.expr for r in rows])
        self.w_sym, self.p_sym, self.g_sym = w, p, g
        self._nlp, self._ipopt = {"x": w, "p": p, "f": f, "g": g}, {**IPOPT, **(ipopt or {})}
        self.solver = casadi.nlpsol("qropt", "ipopt", self._nlp, self._ipopt)
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

    def _group(self, quantity, epi):
        """The epigraph variables of one criterion (created once): z >= each sampled |value|."""
        kind = {"sum": None, "footprint": "box"}.get(quantity, quantity)
        if kind is None or kind in self._groups:
            return
        i0 = self._groups[kind] = len(self.z_names)
        n_exact, sampled, exact = self._n_exact, self._sampled, self._exact
        if kind == "gamma_min":
            self.z_names.append("max |cos gamma|")
            if not n_exact and not self.sampled_joints:  # every joint at a right angle (cos 0)
                epi.append((i0, casadi.SX(0)))
            for out in exact:
                epi += [e for j in range(n_exact) for e in ((i0, out[3][j]), (i0, -out[3][j]))]
            for out in sampled:
                epi += [e for j in range(len(self.sampled_joints))
                        for e in ((i0, out[3][n_exact + j]), (i0, -out[3][n_exact + j]))]  # fmt: skip
        elif kind == "peak_accel":
            self.z_names.append("peak |d2x/dtheta2|")
            outs = self._working_outs() if self.problem.accel_over == "working" else sampled
            epi += [e for out in outs for e in ((i0, out[2]), (i0, -out[2]))]
        elif kind == "peak_velocity":
            self.z_names.append("peak working |dx/dtheta2|")
            epi += [e for out in self._working_outs() for e in ((i0, out[1]), (i0, -out[1]))]
        elif kind == "longest":
            self.z_names.append("longest link")
            epi += [(i0, self._params[k]) for k in self.problem.mechanism.LENGTHS if k in self._params]
        else:  # the bounding box of every joint's path
            self.z_names += ["x_max", "-x_min", "y_max", "-y_min"]
            for out in sampled + exact + self._dead:
                xy = out[5]
                for i in range(xy.shape[0] // 2):
                    epi += [(i0, xy[2 * i]), (i0 + 1, -xy[2 * i]), (i0 + 2, xy[2 * i + 1]), (i0 + 3, -xy[2 * i + 1])]

    def _working_outs(self):
        if self._working is None:
            self._working = [self._at(self._start + self._W[k] * self._length) for k in range(self.n_samples)]
        return self._working

    def _measure(self, quantity, Z):
        """A criterion in the NLP's terms: cos gamma_min, size, |d2x/dtheta2|, |dx/dtheta2| (omega2 = 1)."""
        if quantity == "sum":
            return sum(self._params[k] for k in self.problem.mechanism.LENGTHS if k in self._params)
        if quantity == "footprint":
            i = self._groups["box"]
            return (Z[i] + Z[i + 1]) * (Z[i + 2] + Z[i + 3])
        return Z[self._groups[quantity]]

    def _objective_value(self, problem, Z, travel, span):
        if self.range_target == "time_ratio":
            tr = span / (TWO_PI - span) if self.orientation > 0 else (TWO_PI - span) / span
            return self.sense * tr
        if self.range_target in ("stroke", "swing"):
            return self.sense * travel
        if problem.objective:
            return self._measure(measured(problem.objective, problem.size), Z)
        return casadi.SX(0)

    def bound_values(self, problem=None) -> np.ndarray:
        """The bound conditions' values in the NLP's terms (cos of the gamma_min bound; accelerations and
        velocities per omega2^2 and |omega2|)."""
        problem = problem or self.problem
        return np.array([in_nlp_terms(BOUNDS[k][0], problem.conditions[k], problem.omega2) for k in self.bounds_used],
                        float)  # fmt: skip

    # ---- numbers -------------------------------------------------------------
    def base_samples(self):
        """(angles, working-arc fractions): uniform in the base slots; the extra slots repeat the first."""
        angles = TWO_PI * np.arange(self.n_base) / self.n_base
        fractions = np.linspace(0.0, 1.0, self.n_base)
        pad = np.zeros(self.n_extra)
        return np.concatenate([angles, pad]), np.concatenate([fractions, pad])

    def pack(self, values: dict, th, z=None, phi=None, box=None):
        """w from parameter values, dead-centre angles, epigraph values and the lifted angles: ``phi`` (peak
        acceleration or transmission) and ``box`` (the sides' angles in BoundingBox order)."""
        x = [values[k] for k in self.free] + list(th) + list(z if z is not None else np.zeros(self.nz))
        phi = list(phi if phi is not None else np.linspace(0.0, math.pi, self.n_lift))[: self.n_lift]
        phi += [0.0] * (self.n_lift - len(phi))
        return np.array(x + phi + self.box_angles(box), float)

    def lifted_start(self, values: dict, build=None) -> tuple:
        """(phi, box): the lifted angles' start at the design with free parameters ``values`` on this branch
        (built by ``build(problem, values, branch)``, default ``Problem.build``; None where it does not build or
        turn): its largest |d2x/dtheta2| (in the working stroke when asked), its working stroke's largest speeds
        and each sampled joint's smallest transmission angles, spread over the turn where it has too few; and
        its bounding box (the lifted sides' angles and coordinates)."""
        if not (self.n_lift or self.n_box):
            return None, None
        try:
            m = (build or type(self.problem).build)(self.problem, values, self.branch)
            box = m.bounding_box() if self.n_box else None
            if not self.n_lift:
                return None, box
            kinds = dict.fromkeys(self.lifts)
            minima = m.transmission_minima_by_joint() if any(k == "gamma" for k, _ in kinds) else {}
            phi = []
            for kind, joint in kinds:
                if kind == "accel":
                    worst = self._largest(m, m.acceleration_extremes(), self.problem.accel_over == "working")
                elif kind == "velocity":
                    worst = self._largest(m, m.velocity_extremes(), True)
                else:
                    t, v = minima.get(joint, (np.zeros(0), np.zeros(0)))
                    worst = [float(a) for a, _ in sorted(zip(t.tolist(), v.tolist(), strict=True), key=lambda q: q[1])]
                n = self.lifts.count((kind, joint))
                phi += (worst + [float(a) for a in np.linspace(0.0, math.pi, n)])[:n]
            return phi, box
        except QroptError:
            return None, None

    @staticmethod
    def _largest(m, extremes, working: bool) -> list:
        """Crank angles of extremes (maxima, minima), largest magnitude first; only the working stroke's,
        measured from its start (inside its lifted interval), if ``working``."""
        ts = np.concatenate([extremes.maxima[0], extremes.minima[0]])
        vs = np.concatenate([extremes.maxima[1], extremes.minima[1]])
        order = np.argsort(-np.abs(vs))
        if not working:
            return [float(ts[i]) for i in order]
        lo, length = m.working_arc()
        return [lo + (ts[i] - lo) % TWO_PI for i in order if (ts[i] - lo) % TWO_PI <= length]

    def box_angles(self, box=None) -> list:
        """The lifted box sides' angles (z order: x_max, -x_min, y_max, -y_min) from a BoundingBox's angles."""
        if not self.n_box:
            return []
        if box is None:
            return [0.0, math.pi, 0.5 * math.pi, -0.5 * math.pi]
        return [box.angles[i] for i in (1, 0, 3, 2)]

    def box_select(self, box=None) -> np.ndarray:
        """SEL: per side (z order), one-hot over the loop's coordinates: the one that reaches it in ``box``."""
        if not self.n_box:
            return np.zeros(0)
        which = [box.coords[i] for i in (1, 0, 3, 2)] if box is not None and box.coords else self._default_coord
        sel = np.zeros((4, self.n_coords))
        sel[np.arange(4), which] = 1.0
        return sel.ravel()

    def param_vector(self, targets: dict, samples, fractions, fixed=None, box=None):
        """p: fixed values, targets, sample angles and working-arc fractions, bound values and the box sides'
        coordinates (from ``box``, a BoundingBox of the design the solve is at)."""
        fixed = self.problem.fixed if fixed is None else fixed
        pf = [fixed[k] for k in self.fixed]
        pt = [targets[k] for k in self.targets]
        return np.concatenate([pf, pt, samples, fractions, self.bound_values(), self.box_select(box)]).astype(float)

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
        lo += [-np.inf] * self.nz + [-2 * TWO_PI] * (self.n_lift + self.n_box)
        hi += [np.inf] * self.nz + [3 * TWO_PI] * (self.n_lift + self.n_box)
        return np.array(lo, float), np.array(hi, float)

    @functools.cached_property
    def warm_solver(self):
        """The same NLP for re-solves from a converged point (more samples, or IPOPT's iteration limit): its
        start moves off a bound by 1e-8 only. IPOPT's default push (0.01, absolute for lengths below 1) can
        move a small link across a Grashof or assembly limit, where the loop has no real solution."""
        return casadi.nlpsol("qropt_warm", "ipopt", self._nlp, {**WARM, **self._ipopt})

    def solve(self, w0, p, warm: bool = False):
        """One IPOPT run: (w, objective, constraint values, stats); warm: a re-solve (see ``warm_solver``)."""
        lbx, ubx = self.bounds()
        w0 = np.clip(w0, lbx, ubx)
        solver = self.warm_solver if warm else self.solver
        r = solver(x0=w0, p=p, lbx=lbx, ubx=ubx, lbg=self.lbg, ubg=self.ubg)
        st = solver.stats()
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
        from qropt.kinematics.kernel import Batched

        rows, n = self.square_rows, self.nx + 2
        r = self.g_sym[rows.tolist()] - casadi.DM(self.lbg[rows])
        jac = casadi.jacobian(r, self.w_sym[:n])
        z = casadi.SX.sym("z", self.w_sym.numel() + self.p_sym.numel())
        f = casadi.Function("sq", [self.w_sym, self.p_sym], [casadi.vertcat(r, casadi.vec(jac))])
        return Batched(casadi.Function("sqz", [z], [f(z[: self.w_sym.numel()], z[self.w_sym.numel() :])]))

    @functools.cached_property
    def constraint_values(self):
        """z = [w, p] -> g, evaluated without conversions."""
        from qropt.kinematics.kernel import Batched

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
