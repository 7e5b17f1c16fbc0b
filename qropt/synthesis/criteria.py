"""The design criteria: one object each, owning everything about it.

A :class:`Criterion` has a name (its ``quantities`` key), a sense, a unit, its objective and bound-condition
names, its exact value on a mechanism, its terms in the NLP (epigraph samples, lifted extremes) and the crank
angles the exchange loop adds where the exact value and the NLP disagree. Every consumer reads the registry
(``CRITERIA``): Problem validation, the Formulation, the certificate, design, pareto, family, chart, the CLI's
choices and flags, and Result's repr. A new criterion is one subclass registered with :func:`register`.

=============  ======================  ==============================  =====================
criterion      objective               bound condition                 unit
=============  ======================  ==============================  =====================
gamma_min      max_gamma_min           gamma_min (a lower bound)       rad
sum            min_size (size='sum')   max_sum                         length
longest        min_size ('longest')    max_longest                     length
footprint      min_size ('footprint')  max_footprint                   length^2
peak_accel     min_peak_accel          max_peak_accel                  length/s^2 at omega2
peak_velocity  min_peak_velocity       max_peak_velocity               length/s at omega2
=============  ======================  ==============================  =====================

The dynamic criteria are in ``qropt.synthesis.dynamic``; the cut window's speed variation (objective
``min_cut_speed_variation``, bound ``max_cut_speed_variation``, dimensionless) in ``qropt.synthesis.cut``.

Peak acceleration is over the problem's ``accel_over`` span ('cycle' or 'working'); peak velocity over the
working (slow) stroke, where it is also the peak crank torque per newton of a constant cutting force. The NLP
works at omega2 = 1: it states accelerations per omega2^2, velocities per |omega2| and gamma_min by its cosine.
"""

from __future__ import annotations

import enum
import math
from typing import ClassVar, NamedTuple

import numpy as np

from qropt.errors import ProblemError
from qropt.kinematics.closures import transmission_angle
from qropt.kinematics.ops import NUMPY

TWO_PI = 2.0 * math.pi
SIZES = ("sum", "longest", "footprint")


class Role(enum.Enum):
    """How a problem uses a criterion: as its objective or as a bound condition."""

    OBJECTIVE = "objective"
    BOUND = "bound"


class Exchange(NamedTuple):
    """What the exact evaluation says of an NLP point for one criterion: the NLP's and the exact value (the
    criterion's unit), their gap in the NLP's terms, and the crank angles (rad) and working-arc fractions the
    exchange loop adds."""

    nlp: float | None
    certified: float | None
    gap: float
    angles: list
    fractions: list


SIZE_OBJECTIVE = "min_size"  # the objective of every size measure (the measure is the problem's ``size``)
SIZE = "size"  # the quantities key of the problem's size measure


class Criterion:
    """Base of every criterion. Subclasses set the class attributes and implement ``value``; a criterion that
    needs samples over the turn also implements the NLP hooks (see GammaMin, PeakAcceleration)."""

    name: ClassVar[str]  # the quantities key
    unit: ClassVar[str]  # 'rad', 'length', 'length^2', 'length/s', 'length/s^2' or '1'
    label: ClassVar[str]  # a few words for tables and axes
    maximise: ClassVar[bool] = False
    slider_only: ClassVar[bool] = False  # needs a slider output (not FourBar's follower angle)
    size: ClassVar[str | None] = None  # a size measure: the objective is min_size with problem.size = this
    kinematic: ClassVar[bool] = True  # depends on the motion alone (not on the size or on masses)
    needs_masses: ClassVar[bool] = False  # a dynamic criterion: the problem's masses and loads, at its omega2
    # ---- capabilities the search reads (``qropt.synthesis.search``) ---------------------------------------
    guard: ClassVar[float | None] = None  # rad: a transmission angle below which the NLP does not see the criterion
    # well, so its landscape needs a global search: the guarded multi-start (gamma_min >= guard, its designs
    # continued to the problem) and, on a problem with free scale and crank, the differential evolution
    coarse: ClassVar[bool] = False  # its NLP measure is a Gauss-Legendre quadrature (``dynamic.quadrature_rule``): with
    # ``Settings.coarse_nodes`` below the certifier's, a local solve runs on that rule first (``Formulation.coarse``)
    reported: ClassVar[bool] = True  # in every Result's quantities where it applies; False: in those of a problem
    # that uses it alone (its objective or a bound), e.g. a criterion with a parameter of the problem's own
    quantity = None  # a peak over the turn: the quantity of the cycle's dynamics whose peak it is (the SQP on the
    # exact peak descends it, ``minimax``); None for any other criterion

    def grid_value(self, problem, loop, x, scale):
        """Its value for each design (row) of a grid screen, or None where it has none: ``loop`` the type's loop
        evaluated on the designs (``starts.grid_loops``), ``x`` the output at uniform crank angles (designs, angles),
        ``scale`` each design's factor to the stroke target. A screen's value chooses starts, never a result."""
        return None

    # ---- names -------------------------------------------------------------------------------------
    @property
    def objective(self) -> str:
        """The objective that optimises it."""
        if self.size:
            return SIZE_OBJECTIVE
        return ("max_" if self.maximise else "min_") + self.name

    @property
    def bound(self) -> str:
        """The condition that bounds it (a lower bound named as the criterion when maximised)."""
        return self.name if self.maximise else "max_" + self.name

    @property
    def flag(self) -> str:
        """The CLI flag of its bound condition."""
        return "--" + self.bound.replace("_", "-")

    def applies(self, cls) -> bool:
        """Whether a mechanism type has this criterion."""
        return not (self.slider_only and cls.OUTPUT != "slider")

    def why_not(self, cls) -> str:
        """Why a type this criterion does not apply to (``applies`` False) lacks it, in a clause."""
        return f"{cls.__name__} has no slider"

    def better(self, a, b) -> bool:
        """a beats b (None loses)."""
        if b is None:
            return a is not None
        if a is None:
            return False
        return a > b if self.maximise else a < b

    def __repr__(self):
        return f"<criterion {self.name} [{self.unit}]>"

    # ---- exact -------------------------------------------------------------------------------------
    def value(self, problem, m) -> float:
        """The exact value on mechanism m at the problem's omega2 (and accel_over)."""
        raise NotImplementedError

    def to_nlp(self, v: float, omega2: float) -> float:
        """A value as the NLP states it (at omega2 = 1), a quantity it minimises: negated where maximised."""
        return -v if self.maximise else v

    def from_nlp(self, y: float, omega2: float) -> float:
        """The inverse of ``to_nlp``."""
        return -y if self.maximise else y

    def baked(self, problem) -> tuple:
        """What of a problem's numbers its NLP states as constants (the NLP is built once per problem structure
        and these): () for none, the default."""
        return ()

    def check(self, problem) -> str | None:
        """Why a problem cannot use this criterion (None: it can)."""
        return None

    def violation(self, problem, m, bound: float) -> float:
        """How far m is past the bound (>= 0)."""
        v = self.value(problem, m)
        return max(0.0, bound - v if self.maximise else v - bound)

    # ---- NLP ---------------------------------------------------------------------------------------
    def epigraph(self, f) -> list[tuple[str, list]]:
        """Epigraph variables: (name, expressions each must bound from above), built from the Formulation f's
        named kinematic outputs. [] where the measure is an explicit expression."""
        return []

    def auxiliaries(self, f) -> list[tuple[str, list, float, bool]]:
        """Auxiliary NLP variables its epigraph and measure use (``f.aux[name]``), made before them: (name,
        expressions each bounds from above, its start where none does, whether it is also at most the largest of
        them). The largest of several smooth quantities (a bar as long as its farthest joint) is smooth this way;
        a free counterweight is two of them. Shared by name between criteria."""
        return []

    def expression(self, f):
        """The value as an expression of the Formulation f's parameters (``f.params``), for a criterion of the
        parameters alone (no epigraph)."""
        raise NotImplementedError(f"criterion {self.name!r} needs an expression or an epigraph")

    def measure(self, f, z: list):
        """The criterion in the NLP's terms (what it minimises): its first epigraph variable, or ``to_nlp`` of its
        expression."""
        if z:
            return z[0]
        e = self.expression(f)
        return -e if self.maximise else e

    def lifts(self, f, role: Role) -> int:
        """How many lifted crank angles (decision variables with a stationarity row) it takes in this role."""
        return 0

    def lift_terms(self, f, k: int, phi, out) -> list:
        """The rows of lifted angle k at phi (added with ``f.row``; out: f's outputs there), and the expressions
        its first epigraph variable bounds there."""
        return []

    def lift_start(self, f, problem, m, n: int) -> list:
        """Start angles (rad) of its n lifted angles at mechanism m, worst first: its extremes there, up to n (the
        Formulation repeats the worst where there are fewer, ``repeated``)."""
        return []

    def exchange(self, f, problem, m, z, value_nlp, gap_tol) -> Exchange:
        """As objective: the NLP value from z (or the NLP objective value_nlp), the exact one, and where to add
        samples when the gap exceeds gap_tol."""
        exact = self.value(problem, m)
        nlp = None if value_nlp is None else self.from_nlp(value_nlp, problem.omega2)
        return Exchange(nlp, exact, abs(exact - nlp) if nlp is not None else 0.0, [], [])

    def exceeded(self, problem, m) -> tuple[list, list]:
        """Where to add samples when m breaks its bound: (angles, working-arc fractions)."""
        return [], []


# ---- the built-in criteria -----------------------------------------------------------------------------
class GammaMin(Criterion):
    """The smallest transmission angle over the turn and every joint (rad); maximised."""

    name, unit, label, maximise = "gamma_min", "rad", "minimum transmission angle", True

    def value(self, problem, m):
        return m.gamma_min().value

    def to_nlp(self, v, omega2):
        return math.cos(v)

    def violation(self, problem, m, bound):
        return max(0.0, bound - self.value(problem, m))

    def grid_value(self, problem, loop, x, scale):
        value = -np.full(x.shape[0], np.pi / 2)
        for lines in loop.transmission.values():
            if lines is not None:
                g = np.broadcast_to(transmission_angle(NUMPY, lines), x.shape).min(axis=1)
                value = np.maximum(value, -g)
        return value

    def epigraph(self, f):
        exprs = []
        if not f.exact_joints and not f.sampled_joints:  # every joint at a right angle (cos 0)
            exprs.append(0)
        for out in f.exact:
            exprs += [s * out.cos[j] for j in range(len(f.exact_joints)) for s in (1, -1)]
        n = len(f.exact_joints)
        for out in f.sampled:
            exprs += [s * out.cos[n + j] for j in range(len(f.sampled_joints)) for s in (1, -1)]
        return [("max |cos gamma|", exprs)]

    def lifts(self, f, role):  # each sampled joint's two worst transmission minima, as objective or bound
        return 2 * len(f.sampled_joints)

    def lift_terms(self, f, k, phi, out):
        j = len(f.exact_joints) + k // 2
        f.row("lifted transmission extreme: stationary", out.dcos[j], 0.0, 0.0, kind="lift")
        return [out.cos[j], -out.cos[j]]

    def lift_start(self, f, problem, m, n):
        minima = m.transmission_minima_by_joint()
        out = []
        for joint in f.sampled_joints:
            t, v = minima.get(joint, (np.zeros(0), np.zeros(0)))
            worst = [float(a) for a, _ in sorted(zip(t.tolist(), v.tolist(), strict=True), key=lambda q: q[1])]
            out += (worst + [float(a) for a in np.linspace(0.0, math.pi, 2)])[:2]
        return out

    def exchange(self, f, problem, m, z, value_nlp, gap_tol):
        g = m.gamma_min()
        exact = math.cos(g.value)
        add = []
        if exact - z[0] > gap_tol:  # every local minimum of every joint below the NLP's value
            for t, v in m.transmission_minima():
                add += [float(a) for a, b in sorted(zip(t, v, strict=True), key=lambda q: q[1]) if math.cos(b) > z[0]]
        return Exchange(math.acos(min(1.0, z[0])), g.value, exact - z[0], add, [])

    def exceeded(self, problem, m):
        return [m.gamma_min().theta2], []


GUARDED = GammaMin.name  # the condition a transmission guard sets: a lower bound on the transmission angle


class SizeSum(Criterion):
    """The sum of the link lengths, ground included (length)."""

    name, unit, label, size = "sum", "length", "sum of link lengths", "sum"

    def value(self, problem, m):
        return m.size("sum")

    def expression(self, f):
        return sum(f.params[k] for k in f.lengths)


class SizeLongest(SizeSum):
    """The longest link (length)."""

    name, unit, label, size = "longest", "length", "longest link", "longest"

    def value(self, problem, m):
        return m.size("longest")

    def epigraph(self, f):
        return [("longest link", [f.params[k] for k in f.lengths])]


class Footprint(Criterion):
    """The area of the bounding box of every joint's path over the turn (length^2)."""

    name, unit, label, size = "footprint", "length^2", "footprint", "footprint"
    SIDES = ("x_max", "-x_min", "y_max", "-y_min")

    def value(self, problem, m):
        return m.size("footprint")

    def grid_value(self, problem, loop, x, scale):
        xs = np.concatenate([np.broadcast_to(q[0], x.shape) for q in loop.points.values()], axis=1)
        ys = np.concatenate([np.broadcast_to(q[1], x.shape) for q in loop.points.values()], axis=1)
        return np.ptp(xs, axis=1) * np.ptp(ys, axis=1) * scale**2

    def epigraph(self, f):
        groups = {s: [] for s in self.SIDES}
        for out in f.sampled + f.exact + f.dead:
            for i in range(out.coords.shape[0] // 2):
                x, y = out.coords[2 * i], out.coords[2 * i + 1]
                groups["x_max"].append(x)
                groups["-x_min"].append(-x)
                groups["y_max"].append(y)
                groups["-y_min"].append(-y)
        return list(groups.items())

    def measure(self, f, z):
        return (z[0] + z[1]) * (z[2] + z[3])

    def exchange(self, f, problem, m, z, value_nlp, gap_tol):
        box = m.bounding_box()
        exact = (box.x_max - box.x_min) * (box.y_max - box.y_min)
        nlp = (z[0] + z[1]) * (z[2] + z[3])
        add = list(box.angles) if exact - nlp > gap_tol * max(1.0, exact) else []
        return Exchange(nlp, exact, exact - nlp, add, [])

    def exceeded(self, problem, m):
        return list(m.bounding_box().angles), []


class PeakAcceleration(Criterion):
    """The largest |slider acceleration| over the cycle or the working stroke (length/s^2 at omega2)."""

    name, unit, label, slider_only = "peak_accel", "length/s^2", "peak slider acceleration", True

    def value(self, problem, m):
        return m.peak_acceleration(problem.omega2, problem.accel_over).value

    def grid_value(self, problem, loop, x, scale):  # over the whole turn, by the grid's spectral derivative
        wave = np.fft.rfftfreq(x.shape[1], 1.0 / x.shape[1]) ** 2
        d2 = np.fft.irfft(-wave * np.fft.rfft(x, axis=1), n=x.shape[1], axis=1)
        return np.abs(d2).max(axis=1) * scale * problem.omega2**2

    def to_nlp(self, v, omega2):
        return v / omega2**2

    def epigraph(self, f):
        outs = f.working() if f.accel_over == "working" else f.sampled
        return [("peak |d2x/dtheta2|", [s * out.a for out in outs for s in (1, -1)])]

    def lifts(self, f, role):  # its largest extremes (d3x/dtheta3 = 0 there), for its objective or bound
        return f.mechanism.SYNTHESIS.accel_extremes

    def lift_terms(self, f, k, phi, out):
        f.row("lifted acceleration extreme: stationary", out.j, 0.0, 0.0, kind="lift")
        if f.accel_over == "working":
            f.row("lifted acceleration extreme: in the working stroke", f.in_working(phi), 0, 1, kind="lift")
        return [out.a, -out.a]

    def lift_start(self, f, problem, m, n):
        return largest(m, m.acceleration_extremes(), f.accel_over == "working")

    def exchange(self, f, problem, m, z, value_nlp, gap_tol):
        peak = m.peak_acceleration(1.0, f.accel_over)
        w2 = problem.omega2**2
        add, frac = [], []
        if peak.value - z[0] > gap_tol:  # every local extreme of the acceleration above the NLP's bound
            ex = m.acceleration_extremes()
            ts = np.concatenate([ex.maxima[0], ex.minima[0]])
            vs = np.concatenate([ex.maxima[1], ex.minima[1]])
            worst = [float(a) for a, b in sorted(zip(ts, vs, strict=True), key=lambda q: -abs(q[1])) if abs(b) > z[0]]
            if f.accel_over == "working":
                frac += working_fractions(m, ex, z[0]) or working_fractions(m, None, peak.theta2)
            else:
                add += worst or [peak.theta2]
        return Exchange(z[0] * w2, peak.value * w2, (peak.value - z[0]) * w2, add, frac)

    def exceeded(self, problem, m):
        t = m.peak_acceleration(1.0, problem.accel_over).theta2
        return ([], working_fractions(m, None, t)) if problem.accel_over == "working" else ([t], [])


class PeakVelocity(Criterion):
    """The largest |slider velocity| over the working stroke (length/s at omega2); per newton of a constant
    cutting force, the peak crank torque."""

    name, unit, label, slider_only = "peak_velocity", "length/s", "peak working velocity", True

    def value(self, problem, m):
        return m.peak_velocity(problem.omega2).value

    def to_nlp(self, v, omega2):
        return v / abs(omega2)

    def epigraph(self, f):
        return [("peak working |dx/dtheta2|", [s * out.v for out in f.working() for s in (1, -1)])]

    def lifts(self, f, role):  # the objective only: as a bound, lifted speeds stall some footprint solves
        return 2 if role is Role.OBJECTIVE else 0

    def lift_terms(self, f, k, phi, out):
        f.row("lifted velocity extreme: stationary", out.a, 0.0, 0.0, kind="lift")
        f.row("lifted velocity extreme: in the working stroke", f.in_working(phi), 0, 1, kind="lift")
        return [out.v, -out.v]

    def lift_start(self, f, problem, m, n):
        return largest(m, m.velocity_extremes(), True)

    def exchange(self, f, problem, m, z, value_nlp, gap_tol):
        pv, w = m.peak_velocity(1.0), abs(problem.omega2)
        frac = []
        if pv.value - z[0] > gap_tol:  # every local extreme of the velocity in the working stroke above the bound
            frac += working_fractions(m, m.velocity_extremes(), z[0]) or working_fractions(m, None, pv.theta2)
        return Exchange(z[0] * w, pv.value * w, (pv.value - z[0]) * w, [], frac)

    def exceeded(self, problem, m):
        return [], working_fractions(m, None, m.peak_velocity().theta2)


# ---- helpers shared by the criteria --------------------------------------------------------------------
def repeated(angles: list, n: int) -> list:
    """n start angles (rad) of lifts from the extremes given, worst first: the worst again where there are
    fewer (a lift started where its quantity is not stationary holds the design where such a point is made, a
    fold), spread over [0, pi] where there are none."""
    if not angles:
        return [float(a) for a in np.linspace(0.0, math.pi, n)]
    return [angles[k % len(angles)] for k in range(n)]


def largest(m, extremes, working: bool) -> list:
    """Crank angles of extremes (maxima, minima), largest magnitude first; only the working stroke's, measured
    from its start (inside its lifted interval), if ``working``."""
    ts = np.concatenate([extremes.maxima[0], extremes.minima[0]])
    vs = np.concatenate([extremes.maxima[1], extremes.minima[1]])
    order = np.argsort(-np.abs(vs))
    if not working:
        return [float(ts[i]) for i in order]
    lo, length = m.working_arc()
    return [lo + (ts[i] - lo) % TWO_PI for i in order if (ts[i] - lo) % TWO_PI <= length]


def working_fractions(m, extremes, above) -> list:
    """Fractions of the working arc: of the extremes whose |value| exceeds ``above`` (extremes given), or of the
    crank angle ``above`` (extremes None)."""
    lo, length = m.working_arc()
    if extremes is None:
        return [((above - lo) % TWO_PI) / length]
    ts = np.concatenate([extremes.maxima[0], extremes.minima[0]])
    vs = np.concatenate([extremes.maxima[1], extremes.minima[1]])
    order = np.argsort(-np.abs(vs))
    return [((ts[i] - lo) % TWO_PI) / length for i in order if abs(vs[i]) > above and (ts[i] - lo) % TWO_PI <= length]


# ---- the registry --------------------------------------------------------------------------------------
CRITERIA: dict[str, Criterion] = {}


BUILT_IN: list[str] = []  # the shipped criteria's names (registered with built_in=True; they cannot be removed)


def register(criterion: Criterion, *, built_in: bool = False) -> Criterion:
    """Add a criterion (an instance); its name, objective and bound must be new. ``built_in``: one of qropt's own
    (here and in ``qropt.synthesis.dynamic``)."""
    if not isinstance(criterion, Criterion):
        raise ProblemError(f"register takes a Criterion instance, got {criterion!r}")
    for other in CRITERIA.values():
        clash = {criterion.name, criterion.bound} & {other.name, other.bound}
        if clash or (criterion.objective == other.objective and not (criterion.size and other.size)):
            raise ProblemError(f"criterion {criterion.name!r} clashes with {other.name!r}")
    CRITERIA[criterion.name] = criterion
    if built_in:
        BUILT_IN.append(criterion.name)
    return criterion


def unregister(name: str) -> None:
    """Remove a criterion added with ``register`` (the built-in ones stay)."""
    if name in BUILT_IN:
        raise ProblemError(f"{name!r} is built in")
    CRITERIA.pop(name, None)


for _c in (GammaMin(), SizeSum(), SizeLongest(), Footprint(), PeakAcceleration(), PeakVelocity()):
    register(_c, built_in=True)


def objectives() -> tuple:
    """Every objective name (None: a feasibility problem), in registry order."""
    return (None, *dict.fromkeys(c.objective for c in CRITERIA.values()))


def bounds() -> dict[str, Criterion]:
    """Bound-condition key -> its criterion."""
    return {c.bound: c for c in CRITERIA.values()}


def of(objective: str, size: str = "sum") -> Criterion:
    """The criterion an objective optimises (min_size: the problem's size measure)."""
    if objective == "min_size":
        return CRITERIA[size]
    for c in CRITERIA.values():
        if c.objective == objective:
            return c
    raise ProblemError(f"unknown objective {objective!r}; objectives are {objectives()}")


def of_problem(problem) -> Criterion | None:
    """The problem's objective criterion, or None."""
    return of(problem.objective, problem.size) if problem.objective else None


def used(problem, objective: bool = True) -> list[Criterion]:
    """The criteria a problem's NLP states: its objective's (unless ``objective`` is False, as in a reachable
    range's NLP) and its bound conditions', in that order."""
    own = [of_problem(problem)] if objective and problem.objective else []
    return own + [c for k, c in bounds().items() if k in problem.conditions]


def reported(problem, kind) -> list[Criterion]:
    """The registered criteria a problem's results report for a mechanism of class ``kind``: those that apply to
    it, every ``reported`` one and one that is not where the problem's objective or a bound of its conditions uses
    it; one that needs masses only where the problem has masses or loads."""
    stated = used(problem)
    dynamic = problem.masses is not None or problem.loads is not None
    return [
        c
        for c in CRITERIA.values()
        if (c.reported or c in stated) and c.applies(kind) and (dynamic or not c.needs_masses)
    ]


def grid_criterion(problem) -> Criterion | None:
    """The problem's objective criterion where a grid screen can value it (``Criterion.grid_value``), else None."""
    c = of_problem(problem)
    return c if c is not None and type(c).grid_value is not Criterion.grid_value else None


def maximises(objective: str | None) -> bool:
    """Whether the objective is maximised."""
    return bool(objective) and of(objective, "sum").maximise


def sense(objective: str | None) -> float:
    """+1.0 where the objective is maximised, -1.0 where it is minimised: sense * value is larger for a better
    design."""
    return 1.0 if maximises(objective) else -1.0


def violations(problem, m) -> dict:
    """Exact violation (>= 0) of each bound condition of the problem: '<condition> bound (exact)' -> value."""
    out = {}
    for key, c in bounds().items():
        bound = problem.conditions.get(key)
        if bound is not None:
            out[f"{key} bound (exact)"] = c.violation(problem, m, bound)
    return out


BINDS = 1e-6  # a bound met with less room than this (relative to the bound, absolute below 1) holds a design back


def binding(problem, m, names) -> list[str]:
    """The bound conditions among ``names`` that m meets with less room than ``BINDS``: those that can hold it
    back from a better design."""
    out = []
    for key in names:
        c, bound = bounds()[key], problem.conditions[key]
        room = BINDS * max(1.0, abs(bound))
        if c.violation(problem, m, bound + room if c.maximise else bound - room) > 0:
            out.append(key)
    return out


def objective_of(problem, m) -> float | None:
    """The problem's objective of a mechanism, exactly; None without one."""
    c = of_problem(problem)
    return None if c is None else c.value(problem, m)


def objective_value(problem, q) -> float | None:
    """The problem's objective read from a quantities dict."""
    if not problem.objective:
        return None
    return q["size"] if problem.objective == "min_size" else q.get(of_problem(problem).name)


def better(problem, a, b) -> bool:
    """Whether objective value a beats b for this problem (None loses)."""
    c = of_problem(problem)
    if c is not None:
        return c.better(a, b)
    return a is not None and (b is None or a < b)


def units(length: str = "length") -> dict:
    """Criterion name -> unit, with the length unit named (e.g. 'm')."""
    out = {c.name: c.unit.replace("length", length) for c in CRITERIA.values()}
    out["torque_per_newton"] = f"{length} (N m per N)"
    return out


def finite(v) -> bool:
    """A finite real number (not a bool)."""
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


__all__ = [
    "Criterion",
    "Role",
    "Exchange",
    "CRITERIA",
    "SIZES",
    "register",
    "unregister",
    "objectives",
    "bounds",
    "of",
    "of_problem",
    "maximises",
    "sense",
    "violations",
    "objective_of",
    "objective_value",
    "better",
    "units",
    "finite",
]
