"""The mechanism protocol: parameters, one closed-form loop per type, and the exact cycle quantities.

A type defines ``PARAMS`` (name -> default, ``REQUIRED`` for none), the names of
its ``LENGTHS`` (positive) and ``loop(xp, theta2, p) -> Loop`` written once over a
math namespace. Everything else (positions, rates, dead centres, time ratio,
stroke, transmission angles, gamma_min, the assembly check) is derived here.
Angles are radians; lengths in any consistent unit; theta2 counter-clockwise from +x.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any, ClassVar, NamedTuple

import numpy as np

from qropt import cycle
from qropt.closures import RIGHT_ANGLE, transmission_angle
from qropt.errors import AssemblyError, DegenerateMechanism, InvalidParameter, NoDeadCentres
from qropt.ops import JET, NUMPY, Jet

REQUIRED = object()
REGISTRY: dict[str, type[Mechanism]] = {}


class Loop(NamedTuple):
    """One evaluation of a mechanism's closed-form loop.

    points: joint name -> (x, y); angles: link angle name -> angle (direction
    from the first-named joint to the second, e.g. theta3 = A->B); x: the output
    (slider position along +x, or theta4 for FourBar); transmission: joint -> its
    lines (see ``closures``) or RIGHT_ANGLE; margins: (closure, margin >= 0 if it assembles).
    """

    points: dict
    angles: dict
    x: Any
    transmission: dict
    margins: list


@dataclass(frozen=True)
class Positions:
    """Joint coordinates (arrays of shape (n, 2)) and link angles (rad) at the crank angles theta2."""

    theta2: np.ndarray
    points: dict
    angles: dict
    x: np.ndarray


@dataclass(frozen=True)
class Motion:
    """Output position x, velocity v, acceleration a and every link's angle, omega, alpha.

    Units: length, length/s, length/s^2, rad, rad/s, rad/s^2 (for FourBar x is theta4 in rad).
    """

    theta2: np.ndarray
    x: np.ndarray
    v: np.ndarray
    a: np.ndarray
    angles: dict = field(default_factory=dict)
    omega: dict = field(default_factory=dict)
    alpha: dict = field(default_factory=dict)


class DeadCentres(NamedTuple):
    """Crank angles (rad, in [0, 2pi)) of the largest and smallest output, and those outputs.

    ``reversals`` counts the output's local maxima over a turn: 1 for a proper
    quick-return; more means the slider reverses inside a stroke and TR is ill-posed.
    """

    theta_max: float
    theta_min: float
    x_max: float
    x_min: float
    reversals: int = 1


class GammaMin(NamedTuple):
    """Smallest transmission angle over a full turn and every joint: value (rad), theta2 (rad), joint."""

    value: float
    theta2: float
    joint: str


class Mechanism:
    """Base of every quick-return type; instances are immutable."""

    PARAMS: ClassVar[dict[str, Any]] = {}
    LENGTHS: ClassVar[tuple[str, ...]] = ()
    REQUIRES_FULL_TURN: ClassVar[bool] = True
    OUTPUT: ClassVar[str] = "slider"

    def __init_subclass__(cls, **kw):
        super().__init_subclass__(**kw)
        if getattr(cls, "KIND", None):
            REGISTRY[cls.KIND] = cls

    def __init__(self, **params):
        name = type(self).__name__
        unknown = sorted(set(params) - set(self.PARAMS))
        if unknown:
            raise InvalidParameter(f"{name}: unknown parameter(s) {unknown}; it takes {list(self.PARAMS)}")
        values = {}
        for k, default in self.PARAMS.items():
            v = params.get(k, default)
            if v is REQUIRED:
                raise InvalidParameter(f"{name}: missing parameter {k!r}; it needs {self.required()}")
            if v is None:
                continue
            if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)):
                raise InvalidParameter(f"{name}: {k} must be a number, got {v!r}")
            v = float(v)
            if not math.isfinite(v):
                raise InvalidParameter(f"{name}: {k} must be finite, got {v}")
            if k in self.LENGTHS and v <= 0:
                raise InvalidParameter(f"{name}: length {k} must be positive, got {v:g}")
            if k.startswith("sigma") and v not in (-1.0, 1.0):
                raise InvalidParameter(f"{name}: branch sign {k} must be +1 or -1, got {v:g}")
            values[k] = v
        object.__setattr__(self, "params", values)
        self.validate()
        if self.REQUIRES_FULL_TURN:
            failures = self.assembly_failures()
            if failures:
                raise AssemblyError(name, self.params, failures)

    def __setattr__(self, k, v):
        # cached properties write to __dict__ directly, so only user assignments arrive here
        raise AttributeError(f"{type(self).__name__} is immutable")

    def __repr__(self):
        return f"{type(self).__name__}(" + ", ".join(f"{k}={v:g}" for k, v in self.params.items()) + ")"

    def __eq__(self, other):
        return type(self) is type(other) and self.params == other.params

    def __hash__(self):
        return hash((type(self).__name__, tuple(sorted(self.params.items()))))

    @classmethod
    def required(cls) -> list[str]:
        return [k for k, v in cls.PARAMS.items() if v is REQUIRED]

    def validate(self) -> None:
        """Type-specific checks beyond positive lengths (override)."""

    @staticmethod
    def loop(xp, theta2, p) -> Loop:  # pragma: no cover - abstract
        raise NotImplementedError

    # ---- evaluation -------------------------------------------------------
    def evaluate(self, xp, theta2) -> Loop:
        """The loop at theta2 in namespace xp with this mechanism's parameters."""
        with np.errstate(invalid="ignore", divide="ignore"):
            return self.loop(xp, theta2, self.params)

    def positions(self, theta2) -> Positions:
        """Every joint (n, 2) and link angle at crank angles theta2 (rad); nan where it cannot assemble."""
        t = np.atleast_1d(np.asarray(theta2, float))
        lp = self.evaluate(NUMPY, t)
        pts = {k: np.column_stack(np.broadcast_arrays(x, y, t)[:2]) for k, (x, y) in lp.points.items()}
        ang = {k: np.broadcast_to(v, t.shape).astype(float) for k, v in lp.angles.items()}
        return Positions(t, pts, ang, np.broadcast_to(lp.x, t.shape).astype(float))

    def motion(self, theta2, omega2: float = 1.0, alpha2: float = 0.0) -> Motion:
        """Exact output and link rates at theta2 (rad) for crank rate omega2 (rad/s) and alpha2 (rad/s^2)."""
        t = np.atleast_1d(np.asarray(theta2, float))
        lp = self.evaluate(JET, Jet.seed(t, omega2, alpha2))

        def parts(j):
            if isinstance(j, Jet):
                return [np.broadcast_to(c, t.shape).astype(float) for c in (j.v, j.d1, j.d2)]
            return [np.broadcast_to(float(j), t.shape).astype(float), np.zeros_like(t), np.zeros_like(t)]

        x, v, a = parts(lp.x)
        rates = {k: parts(j) for k, j in lp.angles.items()}
        return Motion(
            t,
            x,
            v,
            a,
            {k: r[0] for k, r in rates.items()},
            {k: r[1] for k, r in rates.items()},
            {k: r[2] for k, r in rates.items()},
        )

    def slider(self, theta2, omega2: float = 1.0, alpha2: float = 0.0) -> Motion:
        """Slider position x, velocity v, acceleration a (and link rates) at theta2; see ``motion``."""
        return self.motion(theta2, omega2, alpha2)

    def transmission_angles(self, theta2) -> dict[str, np.ndarray]:
        """Transmission angle (rad, in [0, pi/2]) of every transmitting joint at theta2."""
        t = np.atleast_1d(np.asarray(theta2, float))
        lp = self.evaluate(NUMPY, t)
        return {
            k: np.broadcast_to(transmission_angle(NUMPY, v), t.shape).astype(float) for k, v in lp.transmission.items()
        }

    # ---- exact cycle quantities -------------------------------------------
    @cached_property
    def _cycle(self) -> dict:
        """Slider extremes, transmission minima and assembly-margin minima from one refined grid pass."""
        lp0 = self.evaluate(NUMPY, np.zeros(1))
        varying = [j for j, g in lp0.transmission.items() if g is not RIGHT_ANGLE]
        n_margin = len(lp0.margins)

        def quantities(t):
            lp = self.evaluate(JET, t)
            qs = [lp.x] + [transmission_angle(JET, lp.transmission[j]) for j in varying]
            qs += [m for _, m in lp.margins]
            return cycle.stack(qs, np.shape(t.v))

        specs = [(0, "max"), (0, "min")] + [(1 + k, "min") for k in range(len(varying) + n_margin)]
        with np.errstate(invalid="ignore", divide="ignore"):
            res, on_grid = cycle.extremes_many(quantities, specs)
        gammas = {j: res[2 + k] for k, j in enumerate(varying)}
        right = [j for j, g in lp0.transmission.items() if g is RIGHT_ANGLE]
        gammas.update({j: (np.zeros(1), np.full(1, math.pi / 2)) for j in right})
        margins = []
        for k in range(n_margin):
            t, v = res[2 + len(varying) + k]
            grid_min = (
                np.nanmin(on_grid[1 + len(varying) + k]) if np.isfinite(on_grid[1 + len(varying) + k]).any() else 0.0
            )
            k_min = int(np.nanargmin(v)) if np.isfinite(v).any() else None
            refined = v[k_min] if k_min is not None else np.inf
            margins.append((min(grid_min, refined), float(t[k_min]) if k_min is not None else 0.0))
        return {"max": res[0], "min": res[1], "gamma": gammas, "margins": margins}

    def _require_full_turn(self):
        if not self.REQUIRES_FULL_TURN:
            failures = self.assembly_failures()
            if failures:
                raise AssemblyError(type(self).__name__, self.params, failures)

    @cached_property
    def _dead_centres(self) -> DeadCentres:
        self._require_full_turn()
        (tmax, xmax), (tmin, xmin) = self._cycle["max"], self._cycle["min"]
        if tmax.size == 0 or tmin.size == 0:
            raise NoDeadCentres(
                f"{self!r}: the output has no regular extremes over a crank turn (it turns fully, "
                "or a dead centre falls on a singular position such as a change point)"
            )
        i, j = int(np.argmax(xmax)), int(np.argmin(xmin))
        return DeadCentres(float(tmax[i]), float(tmin[j]), float(xmax[i]), float(xmin[j]), int(tmax.size))

    def dead_centres(self) -> DeadCentres:
        """Exact crank angles of the largest and smallest output (zero output velocity)."""
        return self._dead_centres

    def stroke_angles(self) -> tuple[float, float]:
        """(a, b): crank turn (rad) from theta_max to theta_min counter-clockwise, and the rest."""
        d = self.dead_centres()
        a = (d.theta_min - d.theta_max) % cycle.TWO_PI
        return a, cycle.TWO_PI - a

    def time_ratio(self) -> float:
        """TR = slow crank interval / fast crank interval (>= 1)."""
        a, b = self.stroke_angles()
        return max(a, b) / min(a, b)

    def stroke(self) -> float:
        """Output travel between the dead centres (length; rad for FourBar)."""
        d = self.dead_centres()
        return d.x_max - d.x_min

    def working_direction(self, omega2: float = 1.0) -> str | None:
        """'+x' or '-x': the way the output moves during the slow (working) stroke; None if TR = 1."""
        a, b = self.stroke_angles()
        if a == b:
            return None
        minus_is_slow = (a > b) == (omega2 > 0)
        return "-x" if minus_is_slow else "+x"

    @cached_property
    def _gamma_min(self) -> GammaMin:
        self._require_full_turn()
        best = None
        for joint, (t, v) in self._cycle["gamma"].items():
            ok = np.flatnonzero(np.isfinite(v))
            if ok.size:
                k = ok[np.argmin(v[ok])]
                if best is None or v[k] < best.value:
                    best = GammaMin(float(v[k]), float(t[k]), joint)
        if best is None:  # no finite refined minimum: a singular configuration; fall back to the grid
            th = cycle.grid()
            for joint, g in self.transmission_angles(th).items():
                if np.isfinite(g).any():
                    k = int(np.nanargmin(g))
                    if best is None or g[k] < best.value:
                        best = GammaMin(float(g[k]), float(th[k]), joint)
        if best is None:
            raise DegenerateMechanism(f"{self!r}: no transmission angle is defined over the turn")
        return best

    def transmission_minima(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """Every local minimum of every varying joint's transmission angle: [(theta2, value)] per joint (rad)."""
        self._require_full_turn()
        return [tv for j, tv in self._cycle["gamma"].items() if tv[0].size]

    def gamma_min(self) -> GammaMin:
        """Smallest transmission angle over the full turn and every joint, exact (not a grid sample)."""
        return self._gamma_min

    def peak_acceleration(self, omega2: float = 1.0, over: str = "cycle") -> tuple[float, float]:
        """Largest |slider acceleration| at constant omega2 (rad/s): (value, theta2 in rad).

        ``over="working"`` restricts it to the working (slow) stroke.
        """
        self._require_full_turn()

        def acc(th):
            return self.evaluate(JET, Jet.seed(th, 1.0, 0.0)).x.d2

        cand = []
        for t, v in self._acceleration_extremes:
            cand += list(zip(t.tolist(), v.tolist(), strict=True))
        if over == "working":
            lo, length = self.working_arc(omega2)
            inside = [(t, v) for t, v in cand if (t - lo) % cycle.TWO_PI <= length]
            ends = [lo % cycle.TWO_PI, (lo + length) % cycle.TWO_PI]
            cand = inside + list(zip(ends, acc(np.array(ends)).tolist(), strict=True))
        t, v = max(cand, key=lambda tv: abs(tv[1]))
        return abs(v) * omega2 * omega2, float(t)

    @cached_property
    def _acceleration_extremes(self):
        """Local maxima and minima of d2x/dtheta2 over a turn: [(theta2, values), (theta2, values)]."""

        def acc(th):
            return self.evaluate(JET, Jet.seed(th, 1.0, 0.0)).x.d2

        th = cycle.grid()
        a = acc(th)
        step = th[1] - th[0]
        prev, nxt = np.roll(a, 1), np.roll(a, -1)
        kinds = [(a >= prev) & (a > nxt), (a <= prev) & (a < nxt)]
        idx = [np.flatnonzero(k) for k in kinds]
        both = np.concatenate(idx)
        t = cycle.wrap(
            cycle.stationary(cycle.difference_jet(acc), th[both] - step, th[both] + step, xtol=cycle.FD_XTOL)
        )
        v = acc(t)
        n = idx[0].size
        return [(t[:n], v[:n]), (t[n:], v[n:])]

    def working_arc(self, omega2: float = 1.0) -> tuple[float, float]:
        """The crank interval of the working (slow) stroke as (counter-clockwise start, length), rad."""
        d = self.dead_centres()
        a, b = self.stroke_angles()
        return (d.theta_max, a) if a >= b else (d.theta_min, b)

    def bounding_box(self):
        """((x_min, x_max, y_min, y_max) of every joint's path over a turn, crank angles where they occur)."""
        self._require_full_turn()
        names = list(self.evaluate(NUMPY, np.zeros(1)).points)

        def coords(t):
            lp = self.evaluate(JET, t)
            return cycle.stack([c for k in names for c in lp.points[k]], np.shape(t.v))

        q = 2 * len(names)
        res, on_grid = cycle.extremes_many(coords, [(k, kind) for k in range(q) for kind in ("max", "min")])
        grid = cycle.grid()
        box, angles = [], []
        for axis in (0, 1):
            for kind, pick in (("min", np.argmin), ("max", np.argmax)):
                vals, ths = [], []
                for k in range(axis, q, 2):
                    t, v = res[2 * k + (kind == "min")]
                    vals += [*v.tolist(), *on_grid[k].tolist()]
                    ths += [*t.tolist(), *grid.tolist()]
                i = int(pick(vals))
                box.append(float(vals[i]))
                angles.append(float(ths[i]))
        return tuple(box), tuple(angles)

    def footprint(self) -> float:
        """Area of the bounding box of every joint's path over a turn (length^2), exact."""
        (x0, x1, y0, y1), _ = self.bounding_box()
        return float((x1 - x0) * (y1 - y0))

    def size(self, measure: str = "sum") -> float:
        """Size by ``measure``: 'sum' of link lengths (ground included), 'longest' link, or 'footprint'."""
        if measure == "footprint":
            return self.footprint()
        lengths = [self.params[k] for k in self.LENGTHS if k in self.params]
        return float(sum(lengths) if measure == "sum" else max(lengths))

    def assembly_failures(self) -> list[tuple[str, float, float]]:
        """(closure, theta2_from, theta2_to) intervals (rad) where the loop cannot close; [] if it turns fully."""
        lp = self.evaluate(NUMPY, np.zeros(1))
        for k, (what, _) in enumerate(lp.margins):
            least, at = self._cycle["margins"][k]
            if not least < -cycle.MARGIN_TOL:
                continue

            def margin(t, k=k):
                return np.asarray(self.evaluate(NUMPY, t).margins[k][1], float) + 0 * t

            found = cycle.negative_intervals(margin)
            if not found:  # a failure narrower than the check grid: at the refined minimum
                found = [(at, at)]
            return [(what, lo, hi) for lo, hi in found]
        return []
