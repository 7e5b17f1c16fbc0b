"""The mechanism protocol: parameters, one closed-form loop per type, and the exact cycle quantities.

A type defines ``PARAMS`` (name -> default, ``REQUIRED`` for none), the names of
its ``LENGTHS`` (positive) and ``loop(xp, theta2, p) -> Loop`` written once over a
math namespace. Everything else (positions, rates, dead centres, time ratio,
stroke, transmission angles, gamma_min, the assembly check) is derived here.
Angles are radians; lengths are numbers in the mechanism's stated unit (``units="mm"``, a keyword that is not a
parameter; metres by default, see ``qropt.units``); theta2 counter-clockwise from +x. The values it answers with
are in ``qropt.mechanisms.values``, the registry of types in ``qropt.mechanisms.registry`` and the exact
sensitivities in ``qropt.mechanisms.sensitivity``.
"""

from __future__ import annotations

import functools
import math
from types import MappingProxyType
from typing import Any, ClassVar

import numpy as np

from qropt import units as units_
from qropt.errors import AssemblyError, DegenerateMechanism, InvalidParameter, NoDeadCentres
from qropt.kinematics import cycle
from qropt.kinematics.closures import Loop, transmission_angle
from qropt.kinematics.kernel import kernel, resolved_spectrum, spectral_derivative, spectrum
from qropt.kinematics.ops import NUMPY
from qropt.mechanisms.hints import OLD_NAMES, SynthesisHints
from qropt.mechanisms.registry import register
from qropt.mechanisms.values import (
    AccelerationExtremes,
    Body,
    BoundingBox,
    DeadCentres,
    GammaMin,
    Motion,
    PeakAcceleration,
    PeakVelocity,
    Positions,
    Rule,
    Sensitivity,
    cached_property,
)
from qropt.validate import MAGNITUDE, branch_sign, number

REQUIRED = object()  # a PARAMS default: the parameter has none and must be given
PARAMETER_KINDS = ("length", "offset", "angle", "branch")  # what ``Mechanism.kinds()`` says of each parameter
MAX_ANGLES = 10_000_000  # crank angles evaluated in one call


@functools.cache
def _scalable(cls) -> tuple[str, ...]:
    return tuple(k for k, kind in cls.kinds().items() if kind in ("length", "offset"))


def working_sign(max_to_min_is_slow: bool, omega2: float) -> float:
    """-1.0 or +1.0: the way along x the output moves in its slow (working) stroke, where the crank's turn from
    theta_max to theta_min counter-clockwise is the slow one or not, for the crank's sense (omega2's sign). The one
    rule of ``Mechanism.working_direction`` and of the synthesis NLP's loads (its TR orientation)."""
    return -1.0 if bool(max_to_min_is_slow) == (omega2 > 0) else 1.0


def crank_angles(theta2) -> np.ndarray:
    """Crank angles (rad) from the API as a 1-D float array: real, finite, at most MAX_ANGLES of them."""
    if (
        isinstance(theta2, (str, bytes))
        or np.asarray(theta2).dtype.kind not in "biuf"
        or (np.asarray(theta2).dtype.kind == "b")
    ):
        raise InvalidParameter(f"theta2 must be real numbers in radians, got {theta2!r}")
    t = np.atleast_1d(np.asarray(theta2, float)).ravel()
    if t.size > MAX_ANGLES:
        raise InvalidParameter(f"theta2 has {t.size} angles; at most {MAX_ANGLES} in one call")
    if not np.isfinite(t).all():
        raise InvalidParameter("theta2 must be finite (got nan or inf)")
    return t


def _rebuilt(cls, params: dict, units: str) -> Mechanism:
    return cls(**params, units=units)


def _check_declaration(cls) -> None:
    """InvalidParameter naming the type where its PARAMS is not a dict of parameter name -> default (a number, None
    for an optional parameter, or REQUIRED), where it declares a synthesis hint by an old name (``TIES``, ...: they
    are ``SYNTHESIS`` fields) or where its SYNTHESIS is not a ``SynthesisHints``."""
    params = cls.PARAMS
    if not isinstance(params, dict):
        raise InvalidParameter(
            f"{cls.__name__}: PARAMS is a dict of parameter name -> default (a number, None or REQUIRED), "
            f"got {type(params).__name__} {params!r:.80}"
        )
    for k, v in params.items():
        if not isinstance(k, str) or not k.isidentifier():
            raise InvalidParameter(f"{cls.__name__}: a parameter is named by an identifier, got {k!r:.80} in PARAMS")
        if not (v is REQUIRED or v is None or (isinstance(v, (int, float)) and not isinstance(v, bool))):
            raise InvalidParameter(
                f"{cls.__name__}: parameter {k}'s default is a number, None or REQUIRED, got {v!r:.80}"
            )
    old = [name for name in OLD_NAMES if name in cls.__dict__]
    if old:
        spelled = ", ".join(f"{OLD_NAMES[name]}=..." for name in old)
        raise InvalidParameter(
            f"{cls.__name__}: {', '.join(old)} {'is' if len(old) == 1 else 'are'} now declared as "
            f"SYNTHESIS = SynthesisHints({spelled}) (qropt.mechanisms.hints; a subclass: "
            f"dataclasses.replace(Base.SYNTHESIS, {spelled}))"
        )
    if not isinstance(cls.SYNTHESIS, SynthesisHints):
        raise InvalidParameter(
            f"{cls.__name__}: SYNTHESIS is a qropt.mechanisms.hints.SynthesisHints, got "
            f"{type(cls.SYNTHESIS).__name__} {cls.SYNTHESIS!r:.80}"
        )


class Mechanism:
    """Base of every quick-return type; instances are immutable."""

    KIND: ClassVar[str] = ""  # the type's registered name (e.g. 'slider-crank'); '' for an unregistered type
    PARAMS: ClassVar[dict[str, Any]] = {}
    LENGTHS: ClassVar[tuple[str, ...]] = ()
    REQUIRES_FULL_TURN: ClassVar[bool] = True
    OUTPUT: ClassVar[str] = "slider"  # 'slider' (x in length along +x) or 'follower' (an angle in rad)
    TRAVEL: ClassVar[str] = "stroke"  # the output's travel target: 'stroke' (slider) or 'swing' (follower)
    BRANCHES: ClassVar[tuple[str, ...]] = ()  # branch-sign parameters (default: PARAMS named sigma...)
    ANGLES: ClassVar[tuple[str, ...]] = ()  # parameters that are angles (rad); the rest but lengths and branches
    # are offsets (lengths that may be negative or zero)
    FOUR_BAR: ClassVar[bool] = False  # driven by a four-bar whose Grashof class is a problem condition
    CLASS: ClassVar[str] = ""  # the Grashof class the type requires ('' any)
    BODIES: ClassVar[tuple[Body, ...]] = ()  # every moving body (see Body): pictures and the mass model read them
    GROUND: ClassVar[tuple[str, ...]] = ()  # the joints fixed to the frame (ground pivots)
    OUTPUT_JOINT: ClassVar[str | None] = None  # the joint whose x is a slider output; None for a follower angle
    SYNTHESIS: ClassVar[SynthesisHints] = SynthesisHints()  # what only the synthesis reads (qropt.mechanisms.hints)
    # a named option -> the optional parameters (PARAMS default None) it gives together (e.g. a rod: r6 and h)
    OPTIONS: ClassVar[dict[str, tuple[str, ...]]] = {}
    # a valid design of the type (parameter -> value), the app's first: a shipped slider's is its design for TR 1.5
    # and stroke 0.3 m (the drag-link slider's the paper's, the others' qropt.design's best gamma_min to 0.1 mm)
    EXAMPLE: ClassVar[dict[str, float]] = {}

    def __init_subclass__(cls, **kw):
        super().__init_subclass__(**kw)
        _check_declaration(cls)
        if "BRANCHES" not in cls.__dict__:
            cls.BRANCHES = tuple(k for k in cls.PARAMS if k.startswith("sigma"))
        linkage = Mechanism.linkage.__func__(cls, {})  # the linkage the type's own loop comes from, if any
        if linkage is not None:
            try:
                linkage.check(cls.PARAMS, cls.BRANCHES)
            except InvalidParameter as e:
                raise type(e)(f"{cls.__name__}: {e}") from None
        register(cls)

    @classmethod
    def kinds(cls) -> dict[str, str]:
        """Each parameter's kind, in PARAMS order: 'length' (LENGTHS, positive), 'angle' (ANGLES, rad), 'branch'
        (BRANCHES, a sign +1 or -1) or 'offset' (every other: a length that may be negative). Bounds, scaling,
        tolerances, starts and the command line's --param read them."""
        out = {}
        for k in cls.PARAMS:
            if k in cls.BRANCHES:
                out[k] = "branch"
            elif k in cls.LENGTHS:
                out[k] = "length"
            elif k in cls.ANGLES:
                out[k] = "angle"
            else:
                out[k] = "offset"
        return out

    @classmethod
    def scalable(cls) -> tuple[str, ...]:
        """The parameters that scale with the mechanism's size, in PARAMS order: its lengths and offsets (``kinds``;
        not the angles or branch signs). Kept per type."""
        return _scalable(cls)

    @classmethod
    def warm_starts(cls, problem):
        """Starting designs for a synthesis problem of this type (override): a ``WarmStarts`` of
        ``qropt.mechanisms.closed_forms`` (free-parameter dicts, their kind and how they were found), or None for
        the first of the type's ``SYNTHESIS.closed_forms`` that applies and otherwise a multi-start."""
        return None

    @classmethod
    def linkage(cls, params: dict):
        """The builder ``Linkage`` this type's loop comes from at these parameters (None for a hand-written loop)."""
        linkage = getattr(getattr(cls, "loop", None), "__self__", None)  # ``loop = staticmethod(L.loop)``
        return linkage if callable(getattr(linkage, "elements", None)) and not isinstance(linkage, type) else None

    def dynamics(self, theta2, omega2: float = 1.0, alpha2: float = 0.0, *, masses=None, loads=None):
        """Exact inverse dynamics at crank angles theta2 (rad), SI: the crank torque, every joint force, the
        shaking force and moment (``qropt.dynamics.Dynamics``); masses: ``qropt.Masses`` (default massless),
        loads: ``qropt.Loads`` (default none)."""
        from qropt.dynamics.inverse import inverse_dynamics

        return inverse_dynamics(self, theta2, omega2, alpha2, masses=masses, loads=loads)

    def dynamic_extremes(self, omega2: float = 1.0, alpha2: float = 0.0, *, masses=None, loads=None):
        """Peak and RMS torque, the peak force at every joint and the peak shaking force and moment over the
        turn, exact (``qropt.dynamics.cycle.DynamicExtremes``)."""
        from qropt.dynamics.cycle import CycleDynamics

        return CycleDynamics(self, omega2, alpha2, masses, loads).extremes()

    def flywheel(self, omega2: float, cs: float, *, masses=None, loads=None):
        """The flywheel inertia (kg m^2) that keeps the speed fluctuation (omega_max - omega_min) / omega2 at cs,
        from the constant-speed torque (``qropt.dynamics.cycle.Flywheel``)."""
        from qropt.dynamics.cycle import CycleDynamics

        return CycleDynamics(self, omega2, 0.0, masses, loads).flywheel(cs)

    def efficiency(self, omega2: float, *, masses=None, loads=None):
        """The work over the working stroke, the return stroke and the turn at constant crank speed omega2: the
        crank's input, what the loads absorb, what friction dissipates (the slide's and, with
        ``Loads(pin_friction=...)``, the pins'), and the mechanical efficiency
        (``qropt.dynamics.cycle.Efficiency``)."""
        from qropt.dynamics.cycle import CycleDynamics

        return CycleDynamics(self, omega2, 0.0, masses, loads).efficiency()

    def drive_check(self, drive, omega2: float, *, masses=None, loads=None, flywheel: float = 0.0, cs=None):
        """A motor and gearbox (``qropt.dynamics.drive.Drive``) at crank speed omega2: the torque, RMS, peak and
        power at the motor, the reflected inertia, and the steady motion under the motor's line with a flywheel
        (given, or sized for ``cs``) confirmed by ``simulate`` (``qropt.dynamics.drive.DriveCheck``)."""
        from qropt.dynamics.drive import drive_check

        return drive_check(self, drive, omega2, masses=masses, loads=loads, flywheel=flywheel, cs=cs)

    def body_masses(self, masses) -> dict:
        """Every moving body's mass, centre of mass (body frame, m) and inertia (kg m^2) under ``masses``."""
        from qropt.dynamics.inverse import body_masses

        return body_masses(self, masses)

    def relative_motion(self, theta2: float, omega2: float = 1.0, alpha2: float = 0.0):
        """Every vector term of the velocity and acceleration equations at one crank angle (rad), dyad by dyad
        (``qropt.mechanisms.relative_motion``): the paper's polygons, each term's magnitude and direction."""
        from qropt.mechanisms.relative_motion import relative_motion

        return relative_motion(self, theta2, omega2, alpha2)

    @classmethod
    def completed(cls, params: dict) -> dict:
        """Defaults that depend on which parameters are given (override; e.g. a rod's slide line at h = 0)."""
        return {}

    units: str = units_.DEFAULT  # the length unit (qropt.units): it names lengths, it is not a parameter

    def __init__(self, **params):
        name = type(self).__name__
        object.__setattr__(self, "units", units_.length_unit(params.pop("units", units_.DEFAULT)))
        if params.keys() - self.PARAMS.keys():
            unknown = sorted(params.keys() - self.PARAMS.keys())
            raise InvalidParameter(f"{name}: unknown parameter(s) {unknown}; it takes {list(self.PARAMS)}")
        values = {}
        for k, default, lo, hi in self._ranges():
            v = params.get(k, default)
            if type(v) is float and lo <= v <= hi:  # the common case: a float in its range
                values[k] = v
                continue
            if v is REQUIRED or (v is None and default is REQUIRED):
                raise InvalidParameter(f"{name}: missing parameter {k!r}; it needs {self.required()}")
            if v is None:
                continue
            if type(v) is not float or not -MAGNITUDE <= v <= MAGNITUDE:  # the name only where it is needed
                v = number(f"{name}: {k}", v)
            if k in self.LENGTHS and v <= 0:
                raise InvalidParameter(f"{name}: length {k} must be positive, got {v:g}")
            if abs(v) > MAGNITUDE or (k in self.LENGTHS and v < 1 / MAGNITUDE):
                raise InvalidParameter(f"{name}: {k} = {v:g} is out of range (|value| in [1e-100, 1e100])")
            if k in self.BRANCHES:
                v = branch_sign(f"{name}: branch sign {k}", v)
            values[k] = v
        object.__setattr__(self, "params", values)
        self.validate()
        object.__setattr__(self, "params", MappingProxyType(dict(self.params)))
        failures = self.assembly_failures()
        if failures and (self.REQUIRES_FULL_TURN or failures[0][1:] == (0.0, cycle.TWO_PI)):
            raise AssemblyError(name, self.params, failures)

    @classmethod
    def _ranges(cls) -> tuple:
        """(name, default, least, largest) of each parameter in PARAMS order: the floats taken without further
        checks (a branch sign never: its range is empty)."""
        r = cls.__dict__.get("_RANGES")
        if r is None:

            def span(k):
                if k in cls.BRANCHES:
                    return 1.0, -1.0
                return (1 / MAGNITUDE, MAGNITUDE) if k in cls.LENGTHS else (-MAGNITUDE, MAGNITUDE)

            r = cls._RANGES = tuple((k, d, *span(k)) for k, d in cls.PARAMS.items())
        return r

    def __reduce__(self):  # pickled as its type, parameters and unit; rebuilt (and checked) when loaded
        return (_rebuilt, (type(self), dict(self.params), self.units))

    def __setattr__(self, k, v):
        # cached properties write to __dict__ directly, so only user assignments arrive here
        raise AttributeError(f"{type(self).__name__} is immutable")

    def __repr__(self):
        given = [f"{k}={v:g}" for k, v in self.params.items()]
        given += [f"units={self.units!r}"] if self.units != units_.DEFAULT else []
        return f"{type(self).__name__}(" + ", ".join(given) + ")"

    def __eq__(self, other):
        return type(self) is type(other) and self.params == other.params and self.units == other.units

    def __hash__(self):
        return hash((type(self).__name__, tuple(sorted(self.params.items())), self.units))

    @classmethod
    def required(cls) -> list[str]:
        return [k for k, v in cls.PARAMS.items() if v is REQUIRED]

    def bodies(self) -> tuple[Body, ...]:
        """The moving bodies of this mechanism (BODIES; a type overrides it where they depend on its options)."""
        return self.BODIES

    def output_joint(self) -> str | None:
        """The joint whose x is the output (OUTPUT_JOINT; a type overrides it where it depends on its options)."""
        return self.OUTPUT_JOINT

    @classmethod
    def rules(cls, xp, p, grashof: str | None = None) -> list[Rule]:
        """The type's feasibility rules at parameters p (override); grashof: a four-bar class to require."""
        return []

    def broken_rules(self, grashof: str | None = None) -> list[str]:
        """Names of the rules these parameters break (beyond rounding)."""
        p = self.params
        scale = max([abs(p[k]) for k in self.scalable() if k in p], default=1.0)
        broken = [r.name for r in self.rules(NUMPY, self.params, grashof) if r.value < -1e-12 * scale]
        return list(dict.fromkeys(broken))

    def validate(self) -> None:
        """Type-specific checks beyond positive lengths: the type's rules (override for a richer message)."""
        broken = self.broken_rules()
        if broken:
            given = ", ".join(f"{k}={v:g}" for k, v in self.params.items())
            raise InvalidParameter(f"{type(self).__name__}({given}) breaks: {'; '.join(broken)}")

    @staticmethod
    def loop(xp, theta2, p) -> Loop:  # pragma: no cover - abstract
        raise NotImplementedError

    # ---- evaluation -------------------------------------------------------
    def evaluate(self, xp, theta2) -> Loop:
        """The loop at theta2 in namespace xp with this mechanism's parameters."""
        with np.errstate(invalid="ignore", divide="ignore"):
            return self.loop(xp, theta2, self.params)

    def _angles(self, theta2) -> np.ndarray:
        """Validated crank angles at which the mechanism assembles (AssemblyError naming the others)."""
        t = crank_angles(theta2)
        if not self.REQUIRES_FULL_TURN and self.assembly_failures():
            m = self.evaluate(NUMPY, t).margins
            bad = np.zeros(t.shape, bool)
            for _, v in m:
                bad |= np.broadcast_to(np.asarray(v) < -cycle.MARGIN_TOL, t.shape)
            if bad.any():
                raise AssemblyError(type(self).__name__, self.params, self.assembly_failures())
        return t

    def positions(self, theta2) -> Positions:
        """Every joint (n, 2) and link angle at crank angles theta2 (rad)."""
        t = self._angles(theta2)
        lp = self.evaluate(NUMPY, t)
        pts = {k: np.column_stack(np.broadcast_arrays(x, y, t)[:2]) for k, (x, y) in lp.points.items()}
        ang = {k: np.broadcast_to(v, t.shape).astype(float) for k, v in lp.angles.items()}
        return Positions(t, pts, ang, np.broadcast_to(lp.x, t.shape).astype(float))

    def motion(self, theta2, omega2: float = 1.0, alpha2: float = 0.0) -> Motion:
        """Exact output and link rates at theta2 (rad) for crank rate omega2 (rad/s) and alpha2 (rad/s^2)."""
        t = self._angles(theta2)
        return self._motion(t, number("omega2", omega2), number("alpha2", alpha2), "all")

    def slider(self, theta2, omega2: float = 1.0, alpha2: float = 0.0) -> Motion:
        """Slider position x, velocity v, acceleration a at theta2 (the link rates are computed if asked for);
        see ``motion``."""
        t = self._angles(theta2)
        return self._motion(t, number("omega2", omega2), number("alpha2", alpha2), "x")

    def _motion(self, t, omega2, alpha2, which) -> Motion:
        k = self._kernel
        r = k.rates(self.params, t, omega2, alpha2, which)
        if which == "x":
            links = lambda: self._motion(t, omega2, alpha2, "all")._rates  # noqa: E731
            return Motion(t, r[0].copy(), r[1].copy(), r[2].copy(), links)
        names = k.angle_names
        rates = tuple({n: r[3 + 3 * i + j].copy() for i, n in enumerate(names)} for j in range(3))
        return Motion(t, r[0].copy(), r[1].copy(), r[2].copy(), lambda: rates)

    def transmission_angles(self, theta2) -> dict[str, np.ndarray]:
        """Transmission angle (rad, in [0, pi/2]) of every transmitting joint at theta2."""
        t = self._angles(theta2)
        lp = self.evaluate(NUMPY, t)
        return {
            k: np.broadcast_to(transmission_angle(NUMPY, v), t.shape).astype(float) for k, v in lp.transmission.items()
        }

    # ---- exact cycle quantities -------------------------------------------
    @cached_property
    def _kernel(self):
        return kernel(type(self), tuple(self.params))

    @cached_property
    def _vector(self) -> np.ndarray:
        """The parameters as the kernel's vector (``params`` order)."""
        p = np.array(list(self.params.values()))
        p.flags.writeable = False
        return p

    @cached_property
    def _sampled(self) -> tuple[np.ndarray, np.ndarray | None]:
        """Cycle quantities (x, cos^2 of each varying joint, margins) on the coarsest grid of GRIDS that
        resolves them (or shows an assembly failure): (Q, n) on ``cycle.grid(n)``; and their spectra (``spectrum``;
        None where not computed or not finite)."""
        k = self._kernel
        for n in cycle.GRIDS:
            q = k.grid_values(self._vector, cycle.grid(n))
            margins = q[1 + len(k.joints) :]
            least = np.minimum.reduce(margins, axis=None, initial=np.inf)
            if least != least:  # a nan sample: the least of the others
                least = np.nanmin(margins, initial=np.inf)
            if least < -cycle.MARGIN_TOL:
                return q, None
            c = spectrum(q)
            if c is not None and resolved_spectrum(c):
                break
        return q, c

    @cached_property
    def _grid(self) -> np.ndarray:
        """The cycle quantities on the coarsest grid that resolves them: (Q, n) (``_sampled``)."""
        return self._sampled[0]

    @cached_property
    def _cycle(self) -> dict:
        """Slider extremes, transmission minima and assembly-margin minima, refined in one compiled call."""
        k, q = self._kernel, self._grid
        nj, nm = len(k.joints), len(k.margin_names)
        margins_grid = q[1 + nj :]
        least = np.fmin.reduce(margins_grid, axis=1, initial=np.inf).tolist()  # the least sample of each, nan left out
        least = [-math.inf if v == math.inf else v for v in least]  # no sample closes (every one nan): none anywhere
        if min(least, default=0.0) < -cycle.MARGIN_TOL:  # cannot assemble: nothing else is defined
            return {"margins": [(v, 0.0) for v in least]}
        res = k.refine("cycle", q, k.cycle_requests, self._vector)
        gammas = {j: (res[2 + i].theta, res[2 + i].value) for i, j in enumerate(k.joints)}
        gammas.update({j: (np.zeros(1), np.full(1, math.pi / 2)) for j in k.right_joints})
        margins = []
        for m in range(nm):
            e = res[2 + nj + m]
            values = e.value.tolist()
            if values and min(values) < least[m]:
                i = values.index(min(values))  # the first of equal ones
                margins.append((values[i], float(e.theta[i])))
            else:  # the least sample's crank angle
                at = int((margins_grid[m] == least[m]).argmax())
                margins.append((least[m], float(cycle.grid(q.shape[1])[at])))
        tmax, xmax, tmin, xmin = cycle.dwells(res[0].theta, res[0].value, res[1].theta, res[1].value)
        return {
            "dwells": res[0].theta.size - tmax.size,
            "max": (tmax, xmax),
            "min": (tmin, xmin),
            "gamma": gammas,
            "margins": margins,
        }

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
        i, j = int(xmax.argmax()), int(xmin.argmin())
        return DeadCentres(float(tmax[i]), float(tmin[j]), float(xmax[i]), float(xmin[j]), int(tmax.size))

    def dead_centres(self) -> DeadCentres:
        """Exact crank angles of the largest and smallest output (zero output velocity)."""
        return self._dead_centres

    def dwells(self) -> int:
        """How many times the output turns back inside a stroke by less than ``cycle.DWELL`` of its travel, which
        ``dead_centres`` takes as dwells, not reversals (0: it turns back nowhere)."""
        self.dead_centres()  # a full turn with regular extremes, or its error
        return self._cycle["dwells"]

    def stroke_angles(self) -> tuple[float, float]:
        """(a, b): crank turn (rad) from theta_max to theta_min counter-clockwise, and the rest.

        Raises NoDeadCentres if the output reverses more than once a turn (TR is then ill-posed)."""
        d = self.dead_centres()
        if d.reversals != 1:
            raise NoDeadCentres(
                f"{self!r}: the output reverses {d.reversals} times a turn, so the time ratio and the "
                "working stroke are ill-posed (dead_centres() gives the global extremes and the count)"
            )
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
        """'+x' or '-x': the way the output moves during the slow (working) stroke; None if TR = 1.

        omega2 (rad/s, nonzero): its sign is the crank's sense of rotation."""
        if number("omega2", omega2) == 0.0:
            raise InvalidParameter("omega2 must be nonzero: its sign sets the working direction")
        a, b = self.stroke_angles()
        if a == b:
            return None
        return "-x" if working_sign(a > b, omega2) < 0 else "+x"

    @cached_property
    def _gamma_min(self) -> GammaMin:
        self._require_full_turn()
        best = None
        for joint, (t, v) in self._cycle["gamma"].items():
            finite = [(g, th) for g, th in zip(v.tolist(), t.tolist(), strict=True) if math.isfinite(g)]
            if finite:
                g, th = min(finite, key=lambda gt: gt[0])  # the least; of equal ones, the first
                if best is None or g < best.value:
                    best = GammaMin(g, th, joint)
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
        return [tv for tv in self.transmission_minima_by_joint().values() if tv[0].size]

    def transmission_minima_by_joint(self) -> dict[str, tuple[np.ndarray, np.ndarray]]:
        """Every local minimum of each joint's transmission angle: joint -> (theta2, value) arrays (rad)."""
        self._require_full_turn()
        return dict(self._cycle["gamma"])

    def gamma_min(self) -> GammaMin:
        """Smallest transmission angle over the full turn and every joint, exact (not a grid sample)."""
        return self._gamma_min

    def peak_acceleration(self, omega2: float = 1.0, over: str = "cycle") -> PeakAcceleration:
        """Largest |slider acceleration| at constant omega2 (rad/s) over the turn ('cycle') or the working
        (slow) stroke ('working'), exact: the extremes of d2x/dtheta2 refined with exact derivatives."""
        omega2 = number("omega2", omega2)
        if over not in ("cycle", "working"):
            raise InvalidParameter(f"peak_acceleration: over is 'cycle' or 'working', got {over!r}")
        self._require_full_turn()
        ex = self.acceleration_extremes()
        cand = list(zip(ex.maxima[0].tolist(), ex.maxima[1].tolist(), strict=True))
        cand += list(zip(ex.minima[0].tolist(), ex.minima[1].tolist(), strict=True))
        if over == "working":
            lo, length = self.working_arc(omega2)
            inside = [(t, v) for t, v in cand if (t - lo) % cycle.TWO_PI <= length]
            ends = np.array([lo % cycle.TWO_PI, (lo + length) % cycle.TWO_PI])
            acc = self._kernel.group("accel")[0].at(ends, self._vector)[0]
            cand = inside + list(zip(ends.tolist(), acc.tolist(), strict=True))
        t, v = max(cand, key=lambda tv: abs(tv[1]))
        return PeakAcceleration(abs(v) * omega2 * omega2, float(t))

    def acceleration_extremes(self) -> AccelerationExtremes:
        """Local maxima and minima of d2x/dtheta2 over a turn (length/rad^2), exact."""
        self._require_full_turn()
        return self._acceleration_extremes

    @cached_property
    def _acceleration_extremes(self) -> AccelerationExtremes:
        return AccelerationExtremes(*self._derivative_extremes("accel", 2))

    def velocity_extremes(self) -> AccelerationExtremes:
        """Local maxima and minima of dx/dtheta2 over a turn (length/rad), exact."""
        self._require_full_turn()
        return self._velocity_extremes

    @cached_property
    def _velocity_extremes(self) -> AccelerationExtremes:
        return AccelerationExtremes(*self._derivative_extremes("velocity", 1))

    def _derivative_extremes(self, group: str, order: int):
        # bracketed on the coarsest grid whose spectral derivative is resolved (exactly evaluated on the
        # finest grid otherwise), refined by Newton with exact higher derivatives
        k, p = self._kernel, self._vector
        sampled, spectra = self._sampled
        for n in cycle.GRIDS:
            c = spectra if sampled.shape[1] == n else None
            if c is None:
                c = spectrum(k.grid_values(p, cycle.grid(n))[:1])
            if c is None:
                continue
            c = c[:1] * spectral_derivative(n, order)
            if resolved_spectrum(c):
                d = np.fft.irfft(c[0], n)
                break
        else:
            d = k.group(group)[0].at(cycle.grid(), p)[0]
        mx, mn = k.refine(group, d[None, :], [(0, "max"), (0, "min")], p)
        return (mx.theta, mx.value), (mn.theta, mn.value)

    def peak_velocity(self, omega2: float = 1.0) -> PeakVelocity:
        """Largest |slider velocity| over the working (slow) stroke at constant omega2 (rad/s), exact, with the
        crank angle and the peak crank torque per newton of a constant cutting force, |dx/dtheta2| (length)."""
        omega2 = number("omega2", omega2)
        lo, length = self.working_arc(omega2)
        ex = self.velocity_extremes()
        ts = np.concatenate([ex.maxima[0], ex.minima[0]])
        vs = np.concatenate([ex.maxima[1], ex.minima[1]])
        inside = (ts - lo) % cycle.TWO_PI <= length
        if not inside.any():  # no interior extreme: the largest of a fine grid over the arc (not expected)
            ts = lo + length * np.linspace(0.0, 1.0, 721)
            vs = self._kernel.group("velocity")[0].at(ts, self._vector)[0]
            inside = np.ones(ts.size, bool)
        i = np.flatnonzero(inside)[np.argmax(np.abs(vs[inside]))]
        v = abs(float(vs[i]))
        return PeakVelocity(v * abs(omega2), float(ts[i]) % cycle.TWO_PI, v)

    def working_arc(self, omega2: float = 1.0) -> tuple[float, float]:
        """The crank interval of the working (slow) stroke as (counter-clockwise start, length), rad."""
        d = self.dead_centres()
        a, b = self.stroke_angles()
        return (d.theta_max, a) if a >= b else (d.theta_min, b)

    def bounding_box(self) -> BoundingBox:
        """Extremes of every joint's path over a turn (exact), with the crank angles where they occur."""
        self._require_full_turn()
        return self._bounding_box

    @cached_property
    def _bounding_box(self) -> BoundingBox:
        k = self._kernel
        c = k.grid_coords(self.params, cycle.grid())
        q = c.shape[0]
        res = k.refine("coords", c, [(i, kind) for i in range(q) for kind in ("max", "min")], self._vector)
        grid = cycle.grid()
        box, angles, coords = [], [], []
        for axis in (0, 1):
            for kind, pick in (("min", np.argmin), ("max", np.argmax)):
                best = None  # (value, angle, coordinate): the first of equal extremes, coordinates in order
                for i in range(axis, q, 2):
                    e = res[2 * i + (kind == "min")]
                    vals, ths = np.concatenate([e.value, c[i]]), np.concatenate([e.theta, grid])
                    j = int(pick(vals))
                    if best is None or (vals[j] < best[0] if kind == "min" else vals[j] > best[0]):
                        best = (float(vals[j]), float(ths[j]), i)
                box.append(best[0])
                angles.append(best[1])
                coords.append(best[2])
        return BoundingBox(*box, tuple(angles), tuple(coords))

    def footprint(self) -> float:
        """Area of the bounding box of every joint's path over a turn (length^2), exact."""
        b = self.bounding_box()
        return float((b.x_max - b.x_min) * (b.y_max - b.y_min))

    def size(self, measure: str = "sum") -> float:
        """Size by ``measure``: 'sum' of link lengths (ground included), 'longest' link, or 'footprint'."""
        if measure not in ("sum", "longest", "footprint"):
            raise InvalidParameter(f"size measure is 'sum', 'longest' or 'footprint', got {measure!r}")
        if measure == "footprint":
            return self.footprint()
        lengths = [self.params[k] for k in self.LENGTHS if k in self.params]
        return float(sum(lengths) if measure == "sum" else max(lengths))

    def assembly_failures(self) -> list[tuple[str, float, float]]:
        """(closure, theta2_from, theta2_to) intervals (rad) where the loop cannot close; [] if it turns fully."""
        return list(self._failures)

    @cached_property
    def _failures(self) -> tuple:
        for k, what in enumerate(self._kernel.margin_names):
            least, at = self._cycle["margins"][k]
            if not least < -cycle.MARGIN_TOL:
                continue

            def margin(t, k=k):
                return np.asarray(self.evaluate(NUMPY, t).margins[k][1], float) + 0 * t

            found = cycle.negative_intervals(margin)
            if not found:  # a failure narrower than the check grid: at the refined minimum
                found = [(at, at)]
            return tuple((what, lo, hi) for lo, hi in found)
        return ()

    # ---- exact sensitivities, many nearby mechanisms at once (qropt.mechanisms.sensitivity) ---------------
    def sensitivity(self, quantity: str, omega2: float | None = None) -> Sensitivity:
        """Exact derivatives of 'time_ratio', 'stroke', 'gamma_min' (rad) or 'peak_acceleration' (over the turn,
        length/s^2 at omega2 rad/s) with respect to every parameter but the branch signs, in ``params`` order
        (``qropt.mechanisms.sensitivity.sensitivity``)."""
        from qropt.mechanisms import sensitivity

        return sensitivity.sensitivity(self, quantity, omega2)

    def nearby(self, P, quantities=("time_ratio", "stroke"), omega2: float | None = None) -> np.ndarray:
        """Exact 'time_ratio', 'stroke', 'gamma_min' and 'peak_acceleration' of many mechanisms of this type near
        this one, all at once: P holds one parameter set per row, (K, len(params)) in ``params`` order; returns
        (len(quantities), K), nan where one cannot be analysed (``qropt.mechanisms.sensitivity.nearby``)."""
        from qropt.mechanisms import sensitivity

        return sensitivity.nearby(self, P, quantities, omega2)

    # ---- the crank angle of an output position --------------------------------------------------------------
    def working_angle_at(self, x) -> np.ndarray:
        """Crank angles (rad, from ``working_arc()``'s start to its end, not reduced mod 2 pi) at which the output
        passes the positions x (length; rad for FourBar) on the working stroke, exact: Newton on the exact x and
        dx/dtheta2, safeguarded by bisection (the output is monotone between the dead centres)."""
        if isinstance(x, (str, bytes)) or np.asarray(x).dtype.kind not in "iuf" or not np.isfinite(x).all():
            raise InvalidParameter(f"working_angle_at: x must be finite positions, got {x!r}")
        target = np.atleast_1d(np.asarray(x, float))
        start, length = self.working_arc()
        d = self.dead_centres()
        lo_x, hi_x = d.x_min, d.x_max
        slack = 1e-12 * max(abs(lo_x), abs(hi_x), hi_x - lo_x)
        if np.any(target < lo_x - slack) or np.any(target > hi_x + slack):
            raise InvalidParameter(f"working_angle_at: x must lie within the stroke [{lo_x:.12g}, {hi_x:.12g}]")
        q, p = self._kernel.group("cycle")[0], self._vector
        x0, x1 = (d.x_max, d.x_min) if start == d.theta_max else (d.x_min, d.x_max)
        rising = x1 > x0
        a, b = np.full(target.shape, start), np.full(target.shape, start + length)
        t = start + length * np.clip((target - x0) / (x1 - x0), 0.0, 1.0)
        eps = 4 * np.finfo(float).eps
        for _ in range(100):
            v, dv, _ = q.at(t, p)
            g = (v - target) if rising else (target - v)  # increasing along the arc
            a, b = np.where(g < 0, t, a), np.where(g > 0, t, b)
            with np.errstate(divide="ignore", invalid="ignore"):
                tn = t - (v - target) / dv
            bad = ~np.isfinite(tn) | (tn < a) | (tn > b)
            tn = np.where(bad, 0.5 * (a + b), tn)
            done = (g == 0) | (np.abs(tn - t) <= eps * np.maximum(1.0, np.abs(t)))
            t = np.where(g == 0, t, tn)
            if done.all():
                break
        return t
