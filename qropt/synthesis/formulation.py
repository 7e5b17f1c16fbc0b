"""Problem structure -> CasADi NLP, built once and immutable; a problem's numbers travel with each solve.

Decision variables (named blocks, see ``Point``): the free parameters, the dead-centre crank angles (theta_max,
theta_min), the criteria's epigraph variables z, their lifted crank angles phi and the footprint's box sides psi.
The dead centres are lifted: the output velocity vanishes there and its curvature has the right sign, so TR is
the linear equality ``theta_min - theta_max = 2 pi TR / (TR + 1)`` (or ``2 pi / (TR + 1)``, by orientation) and
the stroke a difference of two positions. A guarded NLP (a type whose output can reverse more than once a turn)
lifts the output's turn-backs too: crank angles inside each stroke where the output velocity is stationary and
keeps the stroke's sign. Continuous-cycle quantities enter through sample angles that are CasADi
parameters, so the exchange loop adds angles without a rebuild; a type's exact transmission hints
(``Mechanism.SYNTHESIS.exact_transmission``) are evaluated where they are. Parameters (named blocks too): fixed
values, targets, sample angles, working-arc fractions, bound values and the box sides' coordinate picks. Each
criterion states its own terms (``qropt.synthesis.criteria``).
"""

from __future__ import annotations

import enum
import functools
import math
from dataclasses import dataclass
from typing import NamedTuple

import casadi
import numpy as np

from qropt.dynamics.cycle import GAUSS
from qropt.errors import QroptError
from qropt.kinematics.closures import RIGHT_ANGLE, transmission_cos
from qropt.kinematics.ops import CASADI
from qropt.synthesis import criteria
from qropt.synthesis.certificate import angle_gap
from qropt.synthesis.criteria import Role

TWO_PI = 2.0 * math.pi
BASE_SAMPLES = 8  # uniform sample angles of the epigraphs; the exchange loop adds what binds
EXTRA_SAMPLES = 8  # slots for the exchange loop's angles
EXTREME_SLACK = 1e-6  # of the travel: how far the output may pass a dead centre's in the NLP (the certifier: 0)
COVERED = 0.05  # rad: a lifted angle this near an extreme is at it (``relifted``)
MONOTONE = 2  # lifted turn-back angles per stroke of a guarded NLP (placed where the certifier finds a turn-back)
TURN_GRID = 362  # points per stroke where a design's turn-backs are looked for (the start of the lifted angles)
TURN_NEAR = 0.05  # rad: a turn-back found this close to a lifted one is that one, moved
BOX_SIDES = ("x_max", "-x_min", "y_max", "-y_min")  # the footprint's epigraph order (BoundingBox order differs)


def strokes(theta_max, theta_min) -> tuple[tuple, tuple]:
    """((start, end, arc) of the falling stroke, the same of the rising one), rad, for dead centres theta_max <
    theta_min (unwrapped): the output falls from theta_max to theta_min (ccw) and rises on the rest of the turn.
    Numbers or CasADi expressions alike."""
    fall = theta_min - theta_max
    return (theta_max, theta_min, fall), (theta_min, theta_max + TWO_PI, TWO_PI - fall)


def slow_interval(time_ratio, orientation):
    """theta_min - theta_max (rad): the slow interval if orientation = +1, else the fast one."""
    return TWO_PI * (time_ratio if orientation > 0 else 1.0) / (time_ratio + 1.0)


class RowKind(enum.Enum):
    """What a constraint row states; residuals report every kind but EPIGRAPH and LIFT."""

    DEAD_CENTRE = "dead centre"
    TARGET = "target"
    ORIENTATION = "orientation"
    CONDITION = "condition"
    LIFT = "lift"
    EPIGRAPH = "epigraph"
    ASSEMBLY = "assembly"
    BOUND = "bound"


INTERNAL = (RowKind.EPIGRAPH, RowKind.LIFT)  # rows of the formulation's own variables, not of the design


@dataclass(frozen=True)
class Row:
    name: str
    kind: RowKind
    expr: object
    lb: float
    ub: float


class Kin(NamedTuple):
    """The kinematic function's outputs at one crank angle (derivatives in theta2, i.e. at omega2 = 1): output x and
    its first three derivatives (v, a, j), the transmission cosines of the exact-hint joints then the sampled
    ones (cos, dcos), the assembly margins, and every joint's coordinates (coords, dcoords)."""

    x: object
    v: object
    a: object
    j: object
    cos: object
    dcos: object
    margins: object
    coords: object
    dcoords: object
    ddcoords: object  # second derivatives of the coordinates where a criterion needs them (dynamics), else 0
    theta2: object = None  # the crank angle (rad)


class Blocks:
    """Named contiguous blocks of a vector: ``split`` a vector into them, ``join`` them into one."""

    def __init__(self, **sizes: int):
        self.sizes, self.slices, at = dict(sizes), {}, 0
        for k, n in sizes.items():
            self.slices[k] = slice(at, at + n)
            at += n
        self.size = at

    def split(self, vec) -> dict:
        vec = np.asarray(vec, float).ravel()
        return {k: vec[s] for k, s in self.slices.items()}

    def join(self, **parts) -> np.ndarray:
        out = np.zeros(self.size)
        for k, v in parts.items():
            out[self.slices[k]] = v
        return out


class Point(NamedTuple):
    """A point of the NLP: free parameter values (dict), the dead centres (theta_max, theta_min), epigraph
    values z, lifted angles phi, box-side angles psi and a guarded NLP's turn-back angles (arrays)."""

    values: dict
    theta: np.ndarray
    z: np.ndarray
    phi: np.ndarray
    psi: np.ndarray
    turn: np.ndarray


IPOPT = {
    "ipopt.print_level": 0,
    "ipopt.sb": "yes",
    "print_time": 0,
    "record_time": True,
    "ipopt.tol": 1e-12,
    "ipopt.acceptable_tol": 1e-9,
    "ipopt.max_iter": 60,
    "ipopt.max_refinement_steps": 3,  # IPOPT's default 10 (and 5): a near-singular KKT system's refinement can
    # overflow, make the barrier parameter NaN and keep IPOPT from ending; after three it is found singular
    "ipopt.mu_strategy": "adaptive",
    "ipopt.bound_relax_factor": 0.0,
    "show_eval_warnings": False,
    "calc_lam_p": False,
}


def coarse_nodes(problem, coarse: int, range_target=None) -> int:
    """The nodes a stroke of the coarse rule an NLP of ``problem`` states: ``coarse`` where one of its criteria has
    one (``Criterion.coarse``), it is coarser than the certifier's rule and the NLP is no reachable range's, else 0
    (the certifier's)."""
    if range_target is not None or not 0 < coarse < GAUSS:
        return 0
    return coarse if any(c.coarse for c in criteria.used(problem)) else 0


class Formulation:
    """The NLP of one problem structure (type, free/fixed/target names, conditions' structure, objective, size,
    accel_over, branch signs, TR orientation; optionally a target to range). Nothing of a problem's numbers is
    kept: bounds, fixed values, targets and bound values are passed to each call that needs them.

    ``range_target``: drop that target's equality and make its value the objective (``sense`` +1 minimises, -1
    maximises); used for reachable ranges.
    """

    def __init__(
        self,
        problem,
        branch: dict,
        orientation: int,
        range_target: str | None = None,
        sense: int = 1,
        base_samples: int = BASE_SAMPLES,
        extra_samples: int = EXTRA_SAMPLES,
        guarded: bool = False,
        coarse: int = 0,
    ):
        cls = self.mechanism = problem.mechanism
        self.guarded = guarded  # with rows that keep the output's reversals at its dead centres (``_guard_rows``)
        self.branch, self.orientation = dict(branch), orientation
        self.range_target, self.sense, self.accel_over = range_target, sense, problem.accel_over
        self.ccw = problem.omega2 > 0  # the crank's sense: a criterion that reads it says so (``Criterion.baked``)
        self.free, self.fixed = list(problem.free), list(problem.fixed)
        self.targets = [k for k in problem.targets if k != range_target]
        self.lengths = [k for k in cls.LENGTHS if k in problem.free or k in problem.fixed]
        self.n_base, self.n_extra = base_samples, extra_samples
        self.n_samples = n = base_samples + extra_samples
        self.objective = None if range_target else criteria.of_problem(problem)
        self.bound_keys = [k for k in criteria.bounds() if k in problem.conditions]
        used = criteria.used(problem, objective=not range_target)
        self.coarse = coarse_nodes(problem, coarse, range_target)  # nodes a stroke of its quadratures' coarse rule
        self.box = any(isinstance(c, criteria.Footprint) for c in used)
        self.dynamic = any(
            c.needs_masses for c in used
        )  # the body accelerations: masses, loads and omega2 are baked in
        if self.dynamic:
            self.masses, self.loads, self.omega2 = problem.masses, problem.loads, problem.omega2
            self.drive = problem.drive
            self.units = problem.units
        self.rows: list[Row] = []

        X, TH = casadi.SX.sym("x", len(self.free)), casadi.SX.sym("th", 2)
        PF, PT = casadi.SX.sym("pf", len(self.fixed)), casadi.SX.sym("pt", len(self.targets))
        S, W = casadi.SX.sym("s", n), casadi.SX.sym("w", n)  # sample angles; fractions of the working arc
        params = {k: X[i] for i, k in enumerate(self.free)} | {k: PF[i] for i, k in enumerate(self.fixed)}
        self.params = params | self.branch
        self._kinematics(X, PF)
        self.dead = [self.at(TH[0]), self.at(TH[1])]  # the output's extremes
        self.sampled = [self.at(S[k]) for k in range(n)]
        self.exact = [self.at(a) for a in sorted({a for v in cls.SYNTHESIS.exact_transmission.values() for a in v})]
        self._start = TH[0] if orientation > 0 else TH[1]
        self._length = (TH[1] - TH[0]) if orientation > 0 else TWO_PI - (TH[1] - TH[0])
        self._W, self._working, self._returning, self._strokes = W, None, None, None
        self._turn_rows = range(0)  # the rows of the lifted turn-back angles (``_guard_rows``)
        TURN = casadi.SX.sym("turn", 2 * MONOTONE if guarded else 0)  # turn-back angles: falling, rising strokes
        travel, span = self._core_rows(TH, PT)
        if guarded:
            self._guard_rows(TH, TURN)
        self._condition_rows(problem)

        # auxiliary variables first (the epigraph groups may use them), each above its expressions
        aux = {}
        for c in used:
            for name, exprs, start, capped in c.auxiliaries(self):
                aux.setdefault(name, (exprs, start, capped))
        ZA = casadi.SX.sym("za", len(aux))
        self.aux = {name: ZA[i] for i, name in enumerate(aux)}
        self.aux_index = {name: i for i, name in enumerate(aux)}
        self.n_aux = len(aux)  # the first z: auxiliary variables; the criteria's epigraph variables follow
        self.aux_start = np.array([start for _, start, _ in aux.values()], float)
        # a capped one is at most a sum of its expressions that parameters CAP pick: all of them (loose), or the one
        # that is the largest at the design the solve is at (one-hot, like the box sides'; see ``caps``)
        capped = [exprs for exprs, _, cap in aux.values() if cap]
        self.cap_sizes = [len(e) for e in capped]
        self._capped_index = [i for i, (_, _, cap) in enumerate(aux.values()) if cap]
        CAP = casadi.SX.sym("cap", sum(self.cap_sizes))
        k = 0
        for i, (name, (exprs, _, cap)) in enumerate(aux.items()):
            if cap:
                pick = CAP[k : k + len(exprs)]
                self.row(
                    f"{name}: its largest",
                    ZA[i] - casadi.dot(pick, casadi.vertcat(*exprs)),
                    -casadi.inf,
                    0.0,
                    RowKind.EPIGRAPH,
                )
                k += len(exprs)
        self._capped = casadi.vertcat(*[e for exprs in capped for e in exprs])
        # lifted extremes, like the dead centres: crank angles of a criterion's worst values that move with the design
        # faster than samples follow them (each criterion says how many, and their rows); made before the epigraph
        # groups, which may use them (``lifted``: criterion name -> its lifted angles)
        self.lifts = []
        for c in used:
            role = Role.OBJECTIVE if c is self.objective else Role.BOUND
            if not any(l0 is c for l0, _ in self.lifts):
                self.lifts += [(c, k) for k in range(c.lifts(self, role))]
        PHI = casadi.SX.sym("phi", len(self.lifts))
        self.lifted = {}
        for i, (c, _) in enumerate(self.lifts):
            self.lifted.setdefault(c.name, []).append(PHI[i])
        # the criteria: the objective's epigraph group first, then each bound's (each criterion's group once)
        self.z_names, self._z_of = list(aux), {}
        epi = [(i, e) for i, (exprs, _, _) in enumerate(aux.values()) for e in exprs]
        for c in used:
            if c.name not in self._z_of:
                groups = c.epigraph(self)
                self._z_of[c.name] = list(range(len(self.z_names), len(self.z_names) + len(groups)))
                for name, exprs in groups:
                    epi += [(len(self.z_names), e) for e in exprs]
                    self.z_names.append(name)
        Z = casadi.vertcat(ZA, casadi.SX.sym("z", len(self.z_names) - len(aux)))
        for i, (c, k) in enumerate(self.lifts):
            exprs = c.lift_terms(self, k, PHI[i], self.at(PHI[i]))
            epi += [(self._z_of[c.name][0], e) for e in exprs]
        # the footprint's box: each side lifted at the extreme of the coordinate that reaches it (parameters SEL pick
        # that coordinate, one-hot per side, from the last exact box), like the dead centres
        n_box = 4 if self.box else 0
        PSI, SEL = casadi.SX.sym("psi", n_box), casadi.SX.sym("sel", n_box * self.n_coords)
        for s in range(n_box):
            out, pick = self.at(PSI[s]), SEL[s * self.n_coords : (s + 1) * self.n_coords]
            zi = self._z_of[criteria.Footprint.name][s]
            self.row(
                f"lifted box side {self.z_names[zi]}: stationary", casadi.dot(pick, out.dcoords), 0.0, 0.0, RowKind.LIFT
            )
            epi.append((zi, (1 if s % 2 == 0 else -1) * casadi.dot(pick, out.coords)))
        for zi, e in epi:
            self.row(f"epigraph {self.z_names[zi]}", e - Z[zi], -casadi.inf, 0.0, RowKind.EPIGRAPH)
        for k in range(n):
            for m in range(self.n_margins):
                self.row(f"rod assembly at sample {k}", self.sampled[k].margins[m], 0.0, casadi.inf, RowKind.ASSEMBLY)
        PB = casadi.SX.sym("pb", len(self.bound_keys))
        for i, key in enumerate(self.bound_keys):
            c = criteria.bounds()[key]
            self.row(f"{key} bound", self._measure(c, Z) - PB[i], -casadi.inf, 0.0, RowKind.BOUND)
        f = self._objective(Z, travel, span)

        self.w_blocks = Blocks(
            free=len(self.free), theta=2, z=len(self.z_names), phi=len(self.lifts), psi=n_box, turn=TURN.numel()
        )
        self.p_blocks = Blocks(
            fixed=len(self.fixed),
            targets=len(self.targets),
            samples=n,
            fractions=n,
            bounds=len(self.bound_keys),
            select=n_box * self.n_coords,
            caps=CAP.numel(),
        )
        self.w_sym = casadi.vertcat(X, TH, Z, PHI, PSI, TURN)
        self.p_sym = casadi.vertcat(PF, PT, S, W, PB, SEL, CAP)
        self.caps_fun = casadi.Function("caps", [self.w_sym, self.p_sym], [self._capped])
        self.g_sym, self.f_sym = casadi.vertcat(*[r.expr for r in self.rows]), f
        self.design_sym = casadi.vertcat(X, TH)  # the free parameters and the dead centres
        self.design = slice(0, self.w_blocks.slices["theta"].stop)  # where design_sym sits in w
        self.nlp = {"x": self.w_sym, "p": self.p_sym, "f": f, "g": self.g_sym}
        self.epi_fun = casadi.Function("epi", [self.w_sym, self.p_sym], [casadi.vertcat(*[e for _, e in epi], 0)])
        self.epi_index = np.array([zi for zi, _ in epi], int)
        # the rows of the design alone (free parameters, dead centres): all but the turn-backs' (a family's curve)
        turn_rows = set(self._turn_rows)
        self.design_rows = np.array([i for i in range(len(self.rows)) if i not in turn_rows], int)
        self.lbg = np.array([r.lb for r in self.rows], float)
        self.ubg = np.array([r.ub for r in self.rows], float)
        self.nx, self.nz, self.n_lift, self.n_box = len(self.free), len(self.z_names), len(self.lifts), n_box
        del (
            self.params,
            self.dead,
            self.sampled,
            self.exact,
            self._working,
            self._returning,
            self._strokes,
            self.aux,
            self._capped,
            self.lifted,
        )  # the build's

    # ---- the build -----------------------------------------------------------------------------------
    def _kinematics(self, X, PF):
        """The type's loop as one CasADi function of (theta2, free, fixed) with named outputs (``Kin``)."""
        cls, t = self.mechanism, casadi.SX.sym("t")
        lp = cls.loop(CASADI, t, self.params)
        self.exact_joints = [j for j in cls.SYNTHESIS.exact_transmission if lp.transmission.get(j) is not RIGHT_ANGLE]
        self.sampled_joints = [
            j for j, v in lp.transmission.items() if v is not RIGHT_ANGLE and j not in self.exact_joints
        ]
        margins = [m for what, m in lp.margins if what not in cls.SYNTHESIS.ruled_margins]
        self.n_margins = len(margins)
        v = casadi.jacobian(lp.x, t)
        a = casadi.jacobian(v, t)
        cos = casadi.vertcat(
            *[transmission_cos(CASADI, lp.transmission[j]) for j in self.exact_joints + self.sampled_joints], 0
        )
        coords = casadi.vertcat(*[c for pt in lp.points.values() for c in pt])
        self.joint_index = {j: 2 * i for i, j in enumerate(lp.points)}  # joint -> its x row in coords (y next)
        dcoords = casadi.jacobian(coords, t)
        outs = [
            lp.x,
            v,
            a,
            casadi.jacobian(a, t),
            cos,
            casadi.jacobian(cos, t),
            casadi.vertcat(*margins, 0),
            coords,
            dcoords,
            casadi.jacobian(dcoords, t) if self.dynamic else casadi.SX(0),
        ]
        kin = casadi.Function("kin", [t, X, PF], outs, ["theta2", "free", "fixed"], list(Kin._fields)[:-1])
        self.n_coords = coords.shape[0]
        moving = [i for i in range(self.n_coords) if casadi.depends_on(casadi.SX(coords[i]), t)]
        # a box side's default coordinate (before a design names the one that reaches it): the first moving x, y
        self._default_coord = [next((i for i in moving if i % 2 == a), moving[0]) for a in (0, 0, 1, 1)]
        self.at = lambda theta: Kin(*kin(theta, X, PF), theta)

    def row(self, name, expr, lb, ub, kind=RowKind.CONDITION) -> Row:
        """Add a constraint row lb <= expr <= ub (kind: a RowKind or its value)."""
        r = Row(name, RowKind(kind), expr, lb, ub)
        self.rows.append(r)
        return r

    def working(self) -> list[Kin]:
        """The outputs at the working-arc fractions (the working stroke's samples)."""
        if self._working is None:
            self._working = [self.at(self._start + self._W[k] * self._length) for k in range(self.n_samples)]
        return self._working

    def returning(self) -> list[Kin]:
        """The outputs at the same fractions of the return arc (the return stroke's samples)."""
        if self._returning is None:
            lo, arc = self._start + self._length, TWO_PI - self._length
            self._returning = [self.at(lo + self._W[k] * arc) for k in range(self.n_samples)]
        return self._returning

    def strokes(self, nodes) -> list[tuple[Kin, float, float]]:
        """(outputs, weight, arc) at Gauss-Legendre ``nodes`` (on [-1, 1]) of the working arc, then of the return
        arc: the crank angles move with the dead centres, so a quadrature over each stroke is the certifier's own;
        weight * arc / 2 is a node's share of its stroke."""
        if self._strokes is None:
            out = []
            for lo, arc in ((self._start, self._length), (self._start + self._length, TWO_PI - self._length)):
                out += [(self.at(lo + 0.5 * arc * (1 + x)), w, arc) for x, w in zip(*nodes, strict=True)]
            self._strokes = out
        return self._strokes

    def working_arc(self):
        """(counter-clockwise start, length) of the working arc: expressions of the dead centres."""
        return self._start, self._length

    def fractions(self) -> list:
        """The working-arc fractions (parameters): a criterion may read them as fractions of its own span."""
        return [self._W[k] for k in range(self.n_samples)]

    def in_working(self, phi):
        """A lifted angle's place in the working stroke (0..1 inside it)."""
        return (phi - self._start) / self._length

    def _core_rows(self, TH, PT):
        (x_max, v_max, a_max, *_), (x_min, v_min, a_min, *_) = self.dead
        self.row("dead centre theta_max: output velocity", v_max, 0.0, 0.0, RowKind.DEAD_CENTRE)
        self.row("dead centre theta_min: output velocity", v_min, 0.0, 0.0, RowKind.DEAD_CENTRE)
        self.row("dead centre theta_max: a maximum", a_max, -casadi.inf, 0.0, RowKind.DEAD_CENTRE)
        self.row("dead centre theta_min: a minimum", a_min, 0.0, casadi.inf, RowKind.DEAD_CENTRE)
        span = TH[1] - TH[0]
        tgt = {k: PT[i] for i, k in enumerate(self.targets)}
        if "time_ratio" in tgt:
            self.row("time_ratio", span - slow_interval(tgt["time_ratio"], self.orientation), 0.0, 0.0, RowKind.TARGET)
        elif self.orientation > 0:
            self.row("time_ratio orientation", span, math.pi, TWO_PI, RowKind.ORIENTATION)
        else:
            self.row("time_ratio orientation", span, 0.0, math.pi, RowKind.ORIENTATION)
        travel = x_max - x_min
        for k in ("stroke", "swing"):
            if k in tgt:
                self.row(k, travel - tgt[k], 0.0, 0.0, RowKind.TARGET)
        return travel, span

    def _guard_rows(self, TH, TURN):
        """The rows of a type whose output can reverse more than once a turn: at every sample angle the output is
        below its maximum and above its minimum (the certifier's extremes are sampled), and at each lifted
        turn-back angle TURN (MONOTONE in the falling stroke, theta_max to theta_min ccw, then MONOTONE in the
        rising one) the output velocity is stationary and keeps the stroke's sign. A lifted angle follows its
        turn-back as the design moves, so a design whose velocity touches zero inside a stroke is a regular
        point of the NLP (fixed angles there trade one turn-back for another, round after round)."""
        (x_max, *_), (x_min, *_) = self.dead
        slack = EXTREME_SLACK * (x_max - x_min)  # a sample at a dead centre: not an active row without a gradient
        for k, out in enumerate(self.sampled):
            self.row(f"sample {k}: output below its maximum", x_max - out.x + slack, 0, casadi.inf, RowKind.DEAD_CENTRE)
            self.row(f"sample {k}: output above its minimum", out.x - x_min + slack, 0, casadi.inf, RowKind.DEAD_CENTRE)
        first, spans = len(self.rows), strokes(TH[0], TH[1])
        for k in range(2 * MONOTONE):
            falling = k < MONOTONE
            lo, hi, _ = spans[k // MONOTONE]
            name, out = f"{'falling' if falling else 'rising'} stroke, turn-back {k % MONOTONE}", self.at(TURN[k])
            self.row(f"{name}: output velocity stationary", out.a, 0.0, 0.0, RowKind.LIFT)
            self.row(f"{name}: inside the stroke", TURN[k] - lo, 0.0, casadi.inf, RowKind.LIFT)
            self.row(f"{name}: inside the stroke", hi - TURN[k], 0.0, casadi.inf, RowKind.LIFT)
            if falling:
                self.row(f"{name}: output velocity <= 0", out.v, -casadi.inf, 0.0, RowKind.DEAD_CENTRE)
            else:
                self.row(f"{name}: output velocity >= 0", out.v, 0.0, casadi.inf, RowKind.DEAD_CENTRE)
        self._turn_rows = range(first, len(self.rows))

    def midstroke_rows(self) -> list[Row]:
        """A guarded NLP's output velocity mid-stroke, of the stroke's sign: rows of the design alone (free
        parameters, dead centres) that a family's curve checks; the NLP holds the lifted turn-backs instead."""
        if not self.guarded:
            return []
        (a, _, fall), (b, _, rise) = strokes(self.design_sym[self.nx], self.design_sym[self.nx + 1])
        down, up = self.at(a + 0.5 * fall).v, self.at(b + 0.5 * rise).v
        return [
            Row("falling stroke, mid-stroke: output velocity <= 0", RowKind.DEAD_CENTRE, down, -casadi.inf, 0.0),
            Row("rising stroke, mid-stroke: output velocity >= 0", RowKind.DEAD_CENTRE, up, 0.0, casadi.inf),
        ]

    def turn_start(self, m, theta, turned=(), now=None) -> np.ndarray:
        """The lifted turn-back angles (MONOTONE per stroke, falling then rising) at mechanism m for the NLP's
        dead centres ``theta``: in each stroke the velocity's worst turn back (its stationary point nearest to the
        wrong sign) and its fastest point (both where it has no turn back), and the
        certifier's turn-backs ``turned`` ((stroke, fraction along it), ``certificate.wrong_way``) in the slot
        whose angle in ``now`` (the current ones) is within TURN_NEAR of it, else in the slot of its stroke
        where m's velocity is farthest from turning back (the one that holds least)."""
        spans = strokes(float(theta[0]), float(theta[1]))

        def against(s, t):  # m's output velocity at crank angles t, > 0 against stroke s's way; nan where undefined
            return np.asarray(m.slider(t).v, float) * (1.0 if s == 0 else -1.0)

        def fastest(v):  # the index of the fastest finite velocity along the stroke
            return int(np.argmin(np.where(np.isfinite(v), v, np.inf)))

        if now is None:
            now = np.zeros(2 * MONOTONE)
            grid = np.linspace(0.0, 1.0, TURN_GRID)[1:-1]
            for s, (lo, _, arc) in enumerate(spans):
                t = lo + grid * arc
                v = against(s, t)
                k = fastest(v)
                v = np.where(np.isfinite(v), v, -np.inf)
                bumps = np.flatnonzero((v[1:-1] > v[:-2]) & (v[1:-1] >= v[2:])) + 1  # the velocity's turns back
                worst = int(bumps[np.argmax(v[bumps])]) if bumps.size else k
                now[s * MONOTONE : (s + 1) * MONOTONE] = t[worst], t[k]
        else:
            now = np.array(now, float)
        for s, fraction in turned:
            lo, _, arc = spans[s]
            t = lo + fraction * arc
            slots = np.arange(s * MONOTONE, (s + 1) * MONOTONE)
            gaps = angle_gap(now[slots], t)
            i = slots[int(np.argmin(gaps))]
            if gaps.min() > TURN_NEAR:  # a new turn-back: in place of the slot that holds least
                i = slots[fastest(against(s, now[slots]))]
            now[i] = t
        return now

    def _condition_rows(self, problem):
        p, c = self.params, problem.conditions
        for r in self.mechanism.rules(CASADI, p, c.get("grashof")):
            self.row(r.name, r.value, 0.0, casadi.inf)
        for coeffs, lo, hi in c.get("linear", ()):
            self.row(f"linear {dict(coeffs)}", sum(v * p[k] for k, v in coeffs.items()), lo, hi)
        for num, den, lo, hi in c.get("ratio", ()):
            self.row(f"ratio {num}/{den} >= {lo:g}", p[num] - lo * p[den], 0.0, casadi.inf)
            self.row(f"ratio {num}/{den} <= {hi:g}", p[num] - hi * p[den], -casadi.inf, 0.0)

    def _measure(self, c, Z):
        return c.measure(self, [Z[i] for i in self._z_of.get(c.name, [])])

    def _objective(self, Z, travel, span):
        if self.range_target == "time_ratio":
            tr = span / (TWO_PI - span) if self.orientation > 0 else (TWO_PI - span) / span
            return self.sense * tr
        if self.range_target in ("stroke", "swing"):
            return self.sense * travel
        return self._measure(self.objective, Z) if self.objective else casadi.SX(0)

    # ---- points ---------------------------------------------------------------------------------------
    def unpack(self, w) -> Point:
        """The named blocks of an NLP point."""
        b = self.w_blocks.split(w)
        values = dict(zip(self.free, b["free"].tolist(), strict=True))
        return Point(values, b["theta"], b["z"], b["phi"], b["psi"], b["turn"])

    def pack(self, values: dict, theta, z=None, phi=None, box=None, turn=None) -> np.ndarray:
        """w from free values, dead-centre angles, epigraph values and the lifted angles: ``phi`` (the criteria's
        lifted extremes, spread over the turn where missing), ``box`` (a BoundingBox, for the sides' angles) and
        ``turn`` (a guarded NLP's turn-back angles, ``turn_start``; mid-stroke where missing)."""
        phi = list(phi if phi is not None else np.linspace(0.0, math.pi, self.n_lift))[: self.n_lift]
        phi += [0.0] * (self.n_lift - len(phi))
        if turn is None:
            mid = [lo + 0.5 * arc for lo, _, arc in strokes(float(theta[0]), float(theta[1]))]
            turn = np.repeat(mid, MONOTONE) if self.guarded else []
        return self.w_blocks.join(
            free=[values[k] for k in self.free],
            theta=list(theta),
            z=np.concatenate([self.aux_start, np.zeros(self.nz - self.n_aux)]) if z is None else z,
            phi=phi,
            psi=self.box_angles(box),
            turn=turn,
        )

    def concrete(self, problem, z=None):
        """The problem as the design at epigraph values z fixes it: a free counterweight at the NLP's (at its
        start without z); the problem itself otherwise."""
        from qropt.synthesis.dynamic import CW_X, CW_Y

        if CW_X not in self.aux_index:
            return problem
        cw = problem.masses.counterweight
        if z is None:
            memo = self.__dict__.setdefault("_started", {})
            if problem not in memo:
                if len(memo) >= 64:  # a formulation serves every problem of its structure
                    memo.clear()
                memo[problem] = problem.replace(masses=problem.masses.started())
            return memo[problem]
        i, j = self.aux_index[CW_X], self.aux_index[CW_Y]
        return problem.replace(masses=problem.masses.replace(counterweight=cw.with_moment(z[i], z[j])))

    def with_turns(self, w, m, turned=()) -> np.ndarray:
        """w (of this NLP, or of its unguarded sibling: then the turn-back block is added) with the certifier's
        turn-backs at mechanism m placed (``turn_start``)."""
        w = np.asarray(w, float)
        if not self.guarded:
            return w
        fresh = w.size < self.w_blocks.size
        if fresh:
            w = np.concatenate([w, np.zeros(self.w_blocks.size - w.size)])
        b = self.w_blocks.split(w)
        b["turn"] = self.turn_start(m, b["theta"], turned, None if fresh else b["turn"])
        return self.w_blocks.join(**b)

    def with_box(self, w, box) -> np.ndarray:
        """w with its box sides moved to a BoundingBox's angles."""
        b = self.w_blocks.split(w)
        b["psi"] = self.box_angles(box)
        return self.w_blocks.join(**b)

    def with_lifts(self, w, phi) -> np.ndarray:
        """w with its lifted angles moved to phi (rad; ``lifted_start``'s first value)."""
        b = self.w_blocks.split(w)
        b["phi"] = np.asarray(phi[: self.n_lift], float)
        return self.w_blocks.join(**b)

    def lifted_start(self, problem, values: dict, build=None, theta=None) -> tuple:
        """(phi, box, turn): the lifted angles' start at the design with free parameters ``values`` on this branch
        (built by ``build(problem, values, branch)``, default ``Problem.build``; (None, None, None) where it does
        not build or turn): each lifting criterion's worst angles, the design's bounding box, and for a guarded
        NLP with dead centres at ``theta`` its turn-back angles (``turn_start``)."""
        guarded = self.guarded and theta is not None
        if not (self.n_lift or self.n_box or guarded):
            return None, None, None
        try:
            m = (build or type(problem).build)(problem, values, self.branch)
            box = m.bounding_box() if self.n_box else None
            phi = []
            for c, n in self._lift_groups():
                phi += criteria.repeated(c.lift_start(self, problem, m, n), n)
            return (phi or None), box, (self.turn_start(m, theta) if guarded else None)
        except QroptError:
            return None, None, None

    def _lift_groups(self) -> list:
        """(criterion, how many lifts) in the order of the lifted angles (each criterion's lifts are adjacent)."""
        return [(c, sum(1 for c2, _ in self.lifts if c2 is c)) for c in dict.fromkeys(c for c, _ in self.lifts)]

    def relifted(self, w, problem, values: dict, build=None) -> np.ndarray:
        """w with each lifting criterion's largest extremes at the design ``values`` lifted: a largest extreme no
        lifted angle is at (to COVERED rad) takes a lifted angle that is at none of them, largest first; the lifts at
        one stay (w unchanged where every largest extreme has a lift, or the design does not build). A lift the last
        round held at a lower extreme leaves a peak to the samples, which the next design slips past round after
        round; a lift at a lower peak that rises as the design moves keeps it."""
        wanted, _, _ = self.lifted_start(problem, values, build)
        if wanted is None:
            return w
        b = self.w_blocks.split(w)
        phi, i = np.array(b["phi"], float), 0
        for _, n in self._lift_groups():
            now, top = phi[i : i + n], list(dict.fromkeys(wanted[i : i + n]))
            near = angle_gap(now[:, None], np.array(top)[None, :]) < COVERED
            free = [k for k in range(n) if not near[k].any()]
            for j in (j for j in range(len(top)) if not near[:, j].any()):
                if free:
                    now[free.pop(0)] = top[j]
            i += n
        b["phi"] = phi
        return self.w_blocks.join(**b)

    def box_angles(self, box=None) -> list:
        """The lifted box sides' angles (BOX_SIDES order) from a BoundingBox's angles."""
        if not self.n_box:
            return []
        if box is None:
            return [0.0, math.pi, 0.5 * math.pi, -0.5 * math.pi]
        return [box.angles[i] for i in (1, 0, 3, 2)]

    def _box_select(self, box=None) -> np.ndarray:
        """Per side, one-hot over the loop's coordinates: the one that reaches it in ``box``."""
        if not self.n_box:
            return np.zeros(0)
        which = [box.coords[i] for i in (1, 0, 3, 2)] if box is not None and box.coords else self._default_coord
        sel = np.zeros((4, self.n_coords))
        sel[np.arange(4), which] = 1.0
        return sel.ravel()

    def base_samples(self):
        """(angles, working-arc fractions): uniform in the base slots; the extra slots repeat the first."""
        angles = TWO_PI * np.arange(self.n_base) / self.n_base
        fractions = np.linspace(0.0, 1.0, self.n_base)
        pad = np.zeros(self.n_extra)
        return np.concatenate([angles, pad]), np.concatenate([fractions, pad])

    def param_vector(self, problem, targets: dict, samples, fractions, box=None, caps=None) -> np.ndarray:
        """p from the problem's fixed values and bound values (in the NLP's terms), the targets, the sample angles
        and working-arc fractions, the box sides' coordinates (from ``box``, a BoundingBox of the design the
        solve is at) and ``caps`` (``Formulation.caps``; default loose)."""
        bounds = [criteria.bounds()[k].to_nlp(problem.conditions[k], problem.omega2) for k in self.bound_keys]
        return self.p_blocks.join(
            fixed=[problem.fixed[k] for k in self.fixed],
            targets=[targets[k] for k in self.targets],
            samples=samples,
            fractions=fractions,
            bounds=bounds,
            select=self._box_select(box),
            caps=np.ones(sum(self.cap_sizes)) if caps is None else caps,
        )

    def caps(self, w, p) -> np.ndarray:
        """The capped auxiliary variables' caps after NLP point w (p: its parameters). A cap starts loose (the
        sum of its expressions: a bar's length is then free above its farthest reach, which is where the optimum
        puts it whenever a heavier bar does not help, and the NLP stays smooth where two reaches cross); where
        the point has a variable above its largest expression, its cap becomes that expression (one-hot), and
        a tight cap follows the largest one from then on."""
        now = self.p_blocks.split(p)["caps"]
        if not self.cap_sizes:
            return now
        e = np.array(self.caps_fun(w, p)).ravel()
        z = self.w_blocks.split(w)["z"]
        out, k = [], 0
        for i, n in zip(self._capped_index, self.cap_sizes, strict=True):
            top = e[k : k + n]
            tight = np.sum(now[k : k + n]) == 1.0
            one = np.zeros(n)
            one[int(np.argmax(top))] = 1.0
            out.append(one if tight or z[i] > np.max(top) * (1 + 1e-7) + 1e-9 else now[k : k + n])
            k += n
        return np.concatenate(out)

    def epigraph_start(self, w0, p):
        """w0 with z values that make every epigraph row feasible."""
        if not self.nz:
            return w0
        b = self.w_blocks.split(w0)
        for _ in range(2 if self.n_aux else 1):  # the auxiliary variables first: the criteria's rows use them
            e = np.array(self.epi_fun(self.w_blocks.join(**b), p)).ravel()[: self.epi_index.size]
            z = np.full(self.nz, -np.inf)
            np.fmax.at(z, self.epi_index, e)
            z = np.where(np.isfinite(z), z, b["z"])  # a variable no row bounds (a free counterweight) keeps its value
            b["z"] = z + 1e-9 * np.maximum(1.0, np.abs(z))
        return self.w_blocks.join(**b)

    def bounds(self, problem):
        """(lower, upper) of w: the problem's free bounds; the angles within a few turns."""
        lo = self.w_blocks.join(
            free=[problem.free[k][0] for k in self.free],
            theta=[-2 * TWO_PI] * 2,
            z=-np.inf,
            phi=-2 * TWO_PI,
            psi=-2 * TWO_PI,
            turn=-2 * TWO_PI,
        )
        hi = self.w_blocks.join(
            free=[problem.free[k][1] for k in self.free],
            theta=[2 * TWO_PI, 3 * TWO_PI],
            z=np.inf,
            phi=3 * TWO_PI,
            psi=3 * TWO_PI,
            turn=4 * TWO_PI,
        )
        return lo, hi

    # ---- other views of the same NLP --------------------------------------------------------------------
    @functools.cached_property
    def functions(self):
        """The same NLP as plain functions (f, g, df, dg) with exact derivatives, for other backends."""
        w, p, f, g = self.w_sym, self.p_sym, self.f_sym, self.g_sym
        return casadi.Function(
            "fg", [w, p], [f, g, casadi.gradient(f, w), casadi.jacobian(g, w)], ["w", "p"], ["f", "g", "df", "dg"]
        )

    @functools.cached_property
    def objective_function(self):
        """[w, p] -> the NLP's objective."""
        return casadi.Function("f", [self.w_sym, self.p_sym], [self.f_sym])

    @functools.cached_property
    def square_rows(self) -> np.ndarray | None:
        """Indices of the equality rows in the free parameters and dead centres (targets, zero velocity), if
        they are as many as those unknowns: the system a closed-form enumeration is polished on."""
        rows = [i for i, r in enumerate(self.rows) if r.lb == r.ub and r.kind is not RowKind.LIFT]
        return np.array(rows, int) if len(rows) == self.nx + 2 else None

    @functools.cached_property
    def square_system(self):
        """[w, p] -> [residual of the square rows, their Jacobian in (free, theta_max, theta_min) (column-major)],
        evaluated without conversions (see kernel.Batched)."""
        rows = self.square_rows
        r = self.g_sym[rows.tolist()] - casadi.DM(self.lbg[rows])
        return self._batched("sq", casadi.vertcat(r, casadi.vec(casadi.jacobian(r, self.design_sym))))

    @functools.cached_property
    def constraint_values(self):
        """[w, p] -> g, evaluated without conversions."""
        return self._batched("g", self.g_sym)

    def _batched(self, name, expr):
        from qropt.kinematics.kernel import Batched

        z = casadi.SX.sym("z", self.w_sym.numel() + self.p_sym.numel())
        f = casadi.Function(name, [self.w_sym, self.p_sym], [expr])
        return Batched(
            casadi.Function(name + "z", [z], [f(z[: self.w_sym.numel()], z[self.w_sym.numel() :])]), compiled=False
        )

    def row_kind(self, name: str) -> RowKind | None:
        """The kind of the rows named ``name`` (None for a name that is no row of this NLP)."""
        return next((r.kind for r in self.rows if r.name == name), None)

    def violations(self, g) -> dict:
        """Named constraint violations (>= 0) of constraint values g, the formulation's own rows left out."""
        v = np.maximum(np.maximum(self.lbg - g, g - self.ubg), 0.0)
        out = {}
        for row, val in zip(self.rows, v, strict=True):
            if row.kind not in INTERNAL:
                out[row.name] = max(out.get(row.name, 0.0), float(val))
        return out

    def exchange(self, problem, m, z, f, gap_tol) -> criteria.Exchange | None:
        """The objective criterion's exchange at mechanism m (z: the NLP's epigraph values, f its objective)."""
        c = self.objective
        if c is None:
            return None
        return c.exchange(self, problem, m, [float(z[i]) for i in self._z_of.get(c.name, [])], f, gap_tol)
