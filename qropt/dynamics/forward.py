"""Forward dynamics: the crank's motion under a motor's torque, with the mechanism's own inertia and a flywheel.

SI throughout: time in s, angles in rad, speeds in rad/s, torques in N m, inertias in kg m^2 (the mechanism's
lengths are converted from its stated unit, as everywhere in ``qropt.dynamics``).

The crank's equation of motion (see ``qropt.dynamics.inverse.Generalised``) with a flywheel of inertia I_fw on the
crank shaft:

    T_motor(omega2) = (M(theta2) + I_fw) theta2'' + dM/dtheta2 omega2^2 / 2 + Q(theta2)

integrated from theta2 = 0, omega2 = omega0 with ``scipy.integrate.solve_ivp`` (DOP853, rtol = atol = 1e-10 on
the crank's angle and, relative to omega0, its speed). Q is the load for the sense of ``omega0`` (the cutting force
resists the working stroke, which depends on it); the integration is split at the dead centres, where Q jumps.

Signs: ``Simulation.theta2``, ``omega2`` and ``motor_torque`` follow the contract (counter-clockwise positive;
``motor_torque * omega2`` is the power the motor delivers). A ``Motor``'s numbers are given in the sense of
rotation: a positive torque drives the crank the way ``omega0`` turns it, and a line motor's speed is the crank's
speed in that sense. The crank stalls when its speed in that sense falls to zero (to ``STALL_FRACTION * |omega0|``):
the simulation then ends there with ``stalled=True``. Friction on the slide depends on the guide's force, which
depends on the crank's acceleration: with friction the acceleration comes from the Newton-Euler system instead
(``inverse.crank_acceleration``: affine in theta2'' on either side of where the guide's force vanishes).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from scipy.integrate import solve_ivp

from qropt.dynamics import applied
from qropt.dynamics.inverse import body_masses, crank_acceleration, generalised, system_of
from qropt.dynamics.model import Loads, Masses, _real
from qropt.errors import InvalidParameter, NoDeadCentres

TWO_PI = 2 * math.pi
RTOL = 1e-10  # solve_ivp's relative tolerance
ATOL = 1e-10  # its absolute tolerance on theta2 (rad) and on omega2 / |omega0|
STALL_FRACTION = 1e-9  # the crank has stalled when its speed in the sense of omega0 falls to this times |omega0|
MAX_SAMPLES = 2_000_000  # turns * points_per_turn at most
INERTIA_GRID = 720  # crank angles where M + I_fw is checked to be positive before integrating


def _count(what: str, v, lo: int, hi: int) -> int:
    if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or not lo <= v <= hi:
        raise InvalidParameter(f"{what} must be an integer in {lo}..{hi}, got {v!r}")
    return int(v)


@dataclass(frozen=True)
class Motor:
    """A motor's torque (N m) against its speed (rad/s), both in the sense of rotation: the line
    ``T = stall * (1 - omega / free_speed)``; ``free_speed = inf`` is a constant torque ``stall``. Build one with
    ``Motor.constant(torque)``, ``Motor.line(stall, free_speed)`` or ``Motor.induction(...)``. Driving the crank
    directly, its speed is the crank's; through a ``qropt.dynamics.drive.Drive``, the motor shaft's.

    Optional ratings (keyword-only; None: not rated): ``rated_torque`` (N m, continuous: the RMS torque it may
    carry), ``peak_torque`` (N m, >= rated: the line's torque is capped at +-peak_torque, a breakdown torque),
    ``rated_speed`` (rad/s) and ``inertia`` (the rotor's, kg m^2, default 0; it counts through a ``Drive``)."""

    stall: float
    free_speed: float = math.inf
    rated_torque: float | None = dataclasses.field(default=None, kw_only=True)
    peak_torque: float | None = dataclasses.field(default=None, kw_only=True)
    rated_speed: float | None = dataclasses.field(default=None, kw_only=True)
    inertia: float = dataclasses.field(default=0.0, kw_only=True)

    def __post_init__(self):
        object.__setattr__(self, "stall", _real("the motor's torque (N m)", self.stall))
        fs = _real("the motor's free speed (rad/s)", self.free_speed, positive=True, allow_inf=True)
        object.__setattr__(self, "free_speed", fs)
        for name, what in (
            ("rated_torque", "the motor's rated_torque (N m, continuous)"),
            ("peak_torque", "the motor's peak_torque (N m)"),
            ("rated_speed", "the motor's rated_speed (rad/s)"),
        ):
            v = getattr(self, name)
            if v is not None:
                object.__setattr__(self, name, _real(what, v, positive=True))
        object.__setattr__(
            self, "inertia", _real("the motor's inertia (kg m^2, the rotor's)", self.inertia, nonneg=True)
        )
        if self.rated_torque is not None and self.peak_torque is not None and self.peak_torque < self.rated_torque:
            raise InvalidParameter(
                f"the motor's peak_torque ({self.peak_torque:g} N m) must be at least its rated_torque "
                f"({self.rated_torque:g} N m)"
            )

    @classmethod
    def constant(cls, torque: float, **ratings) -> Motor:
        """A constant torque (N m; positive drives the crank the way it turns); ``ratings``: see the class."""
        return cls(torque, **ratings)

    @classmethod
    def line(cls, stall: float, free_speed: float, **ratings) -> Motor:
        """The torque-speed line: ``stall`` (N m) at rest, zero at ``free_speed`` (rad/s, finite, > 0)."""
        if isinstance(free_speed, (int, float)) and not isinstance(free_speed, bool) and free_speed == math.inf:
            raise InvalidParameter(
                "a line motor's free speed must be finite (use Motor.constant for a constant torque)"
            )
        return cls(stall, free_speed, **ratings)

    @classmethod
    def induction(
        cls, rated_torque: float, rated_speed: float, synchronous_speed: float, *, peak_torque=None, inertia=0.0
    ) -> Motor:
        """An induction motor near its operating point: the slip line through (``rated_speed``, ``rated_torque``)
        and zero torque at ``synchronous_speed`` (rad/s, > rated_speed), capped at ``peak_torque`` (N m) if given.
        The line's stall torque, ``rated_torque * synchronous_speed / (synchronous_speed - rated_speed)``, is far
        above a real motor's starting torque: cap it with the breakdown torque for a start-up."""
        tr = _real("the motor's rated_torque (N m, continuous)", rated_torque, positive=True)
        wr = _real("the motor's rated_speed (rad/s)", rated_speed, positive=True)
        ws = _real("the motor's synchronous_speed (rad/s)", synchronous_speed, positive=True)
        if not ws > wr:
            raise InvalidParameter(
                f"an induction motor's synchronous_speed ({ws:g} rad/s) must exceed its rated_speed ({wr:g} rad/s)"
            )
        return cls(tr * ws / (ws - wr), ws, rated_torque=tr, peak_torque=peak_torque, rated_speed=wr, inertia=inertia)

    @property
    def is_constant(self) -> bool:
        return self.free_speed == math.inf

    def to_dict(self) -> dict:
        """Its numbers as plain data (a constant torque without a free speed; unrated ratings left out)."""
        out = {"stall": self.stall} | ({} if self.is_constant else {"free_speed": self.free_speed})
        out |= {k: getattr(self, k) for k in ("rated_torque", "peak_torque", "rated_speed") if getattr(self, k)}
        return out | ({"inertia": self.inertia} if self.inertia else {})

    @classmethod
    def from_dict(cls, d) -> Motor:
        """The Motor of ``to_dict``; InvalidParameter naming what is wrong."""
        keys = ("stall", "free_speed", "rated_torque", "peak_torque", "rated_speed", "inertia")
        if not isinstance(d, dict) or "stall" not in d or set(d) - set(keys):
            raise InvalidParameter(f"a motor is a table of {list(keys)} (stall required), got {d!r:.160}")
        d = dict(d)
        if d.get("free_speed") is None:
            d["free_speed"] = math.inf
        return cls(**d)

    def torque(self, omega):
        """N m at speed omega (rad/s; a number or an array), both in the sense of rotation; within +-peak_torque
        when the motor has one."""
        w = np.asarray(omega, float)
        out = np.full(w.shape, self.stall) if self.is_constant else self.stall * (1.0 - w / self.free_speed)
        if self.peak_torque is not None:
            out = np.clip(out, -self.peak_torque, self.peak_torque)
        return float(out) if out.ndim == 0 else out


def _torque_of(motor):
    """The torque-speed function of a Motor or of a callable (its values checked to be finite numbers)."""
    if isinstance(motor, Motor):
        return motor.torque
    if not callable(motor) or isinstance(motor, type):
        raise InvalidParameter(
            "motor is a qropt Motor (Motor.constant or Motor.line) or a callable torque(omega), got "
            f"{type(motor).__name__}"
        )

    def torque(omega):
        try:
            out = np.asarray(motor(omega), float)
        except (TypeError, ValueError):
            out = np.array(math.nan)
        if out.shape != np.shape(omega) or not np.all(np.isfinite(out)):
            raise InvalidParameter(
                f"the motor's torque(omega) must give a finite number per speed, got {out!r:.80} at {omega!r:.80}"
            )
        return float(out) if out.ndim == 0 else out

    return torque


class TurnSpeeds(NamedTuple):
    """The crank's speeds over one turn (rad/s, magnitudes): the smallest and largest sampled, and the mean
    ``2 pi / (the turn's duration)``."""

    min: float
    max: float
    mean: float


@dataclass(frozen=True)
class Simulation:
    """The crank's motion: ``t`` (s), ``theta2`` (rad, unwrapped, from 0), ``omega2`` (rad/s) and ``motor_torque``
    (N m, signed as in the contract), sampled at ``points_per_turn`` equal steps of theta2 per turn; if the crank
    stalled, the last sample is where it stopped (at ``stall_time`` s). ``evaluations``: how many times the
    equation of motion was evaluated."""

    t: np.ndarray
    theta2: np.ndarray
    omega2: np.ndarray
    motor_torque: np.ndarray
    stalled: bool
    stall_time: float | None
    turns: int
    points_per_turn: int
    flywheel: float
    evaluations: int

    @property
    def turns_completed(self) -> int:
        """Whole crank turns made (``turns`` unless the crank stalled)."""
        return (len(self.t) - (1 if self.stalled else 0) - 1) // self.points_per_turn

    def _turn(self, k) -> int:
        n = self.turns_completed
        if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or not -n <= k < n:
            stop = f" (the crank stalled at t = {self.stall_time:.6g} s)" if self.stalled else ""
            if n == 0:
                raise InvalidParameter(f"no turn was completed{stop}: there is no turn {k!r}")
            raise InvalidParameter(
                f"turn k must be an integer in {-n}..{n - 1}: {n} turns were completed{stop}; got {k!r}"
            )
        return int(k) % n

    def turn_speeds(self, k: int = -1) -> TurnSpeeds:
        """The smallest, largest and mean speed (rad/s, magnitudes) over turn k (0 the first; -1 the last)."""
        k = self._turn(k)
        p = self.points_per_turn
        w = np.abs(self.omega2[k * p : (k + 1) * p + 1])
        return TurnSpeeds(float(w.min()), float(w.max()), TWO_PI / float(self.t[(k + 1) * p] - self.t[k * p]))

    def speed_fluctuation(self, k: int = -1) -> float:
        """``(omega_max - omega_min) / omega_mean`` over turn k (default the last completed turn)."""
        s = self.turn_speeds(k)
        return (s.max - s.min) / s.mean


def steady_mean_torque(m, omega2: float, masses=None, loads=None) -> float:
    """The motor's mean torque (N m, signed as in the contract) over a turn at constant speed omega2 (rad/s): the
    torque of a constant-torque motor that keeps the mean speed (``m.flywheel(...).mean_torque``)."""
    from qropt.dynamics.cycle import CycleDynamics

    omega2 = _real("omega2 (rad/s)", omega2, nonzero=True)
    return CycleDynamics(m, omega2, 0.0, masses, loads).quadrature(lambda d: d.torque) / TWO_PI


def _breaks(m, loads: Loads, sense: float) -> list[float]:
    """The dead centres and the loads' edges (``applied.edges``) as progress (sense * theta2) in [0, 2 pi): where
    the load Q jumps or turns a corner."""
    cuts = {(sense * e) % TWO_PI for e in applied.edges(m, loads)}
    try:
        d = m.dead_centres()
    except NoDeadCentres:
        return sorted(cuts)
    return sorted(cuts | {(sense * d.theta_max) % TWO_PI, (sense * d.theta_min) % TWO_PI})


def simulate(
    m,
    motor: Motor,
    *,
    masses=None,
    loads=None,
    flywheel: float = 0.0,
    omega0: float,
    turns: int = 10,
    points_per_turn: int = 360,
) -> Simulation:
    """Integrate the crank's equation of motion (see the module) from theta2 = 0, omega2 = omega0 (rad/s, nonzero:
    its sign is the sense of rotation) over ``turns`` turns, under ``motor`` with a flywheel of ``flywheel`` kg m^2
    on the crank; masses, loads: ``qropt.Masses`` and ``qropt.Loads`` (default massless, none). ``motor`` is a
    ``Motor`` or a callable ``torque(omega)``: the torque (N m) on the crank at the crank's speed omega (rad/s),
    both in the sense of rotation, for a number and for an array of speeds (``Drive.crank_torque``: a motor seen
    through a gearbox)."""
    torque_of = _torque_of(motor)
    masses = Masses() if masses is None else masses
    loads = Loads() if loads is None else loads
    if not isinstance(masses, Masses):
        raise InvalidParameter(f"masses is a qropt.Masses, got {type(masses).__name__}")
    if not isinstance(loads, Loads):
        raise InvalidParameter(f"loads is a qropt.Loads, got {type(loads).__name__}")
    fw = _real("flywheel (kg m^2)", flywheel, nonneg=True)
    omega0 = _real("omega0 (rad/s)", omega0, nonzero=True)
    turns = _count("turns", turns, 1, 1000)
    ppt = _count("points_per_turn", points_per_turn, 16, 10_000)
    if turns * ppt > MAX_SAMPLES:
        raise InvalidParameter(f"turns * points_per_turn must be at most {MAX_SAMPLES:,}, got {turns * ppt:,}")
    sense = math.copysign(1.0, omega0)
    # every body's mass model once (the same numbers generalised() would derive at each call)
    resolved = Masses(bodies=body_masses(m, masses))

    plain = dataclasses.replace(loads, friction=0.0)  # M and Q (with friction the Newton-Euler system, in rhs)

    def gen(theta):
        return generalised(m, theta, masses=resolved, loads=plain, sense=sense)

    grid = np.linspace(0.0, TWO_PI, INERTIA_GRID, endpoint=False)
    try:
        d = m.dead_centres()
        grid = np.concatenate([grid, [d.theta_max, d.theta_min]])
    except NoDeadCentres:
        pass
    inertia = gen(grid).M + fw
    i = int(np.argmin(inertia))
    if not inertia[i] > 1e-12 * max(1.0, float(inertia.max())):
        raise InvalidParameter(
            f"the crank's inertia M(theta2) + flywheel is {inertia[i]:.3g} kg m^2 at theta2 = {grid[i]:.6g} rad: the "
            "motion cannot be integrated (a massless mechanism, or one whose only mass stops at a dead centre, "
            "with no flywheel); give the links masses or a flywheel > 0"
        )

    nfev = 0

    system = system_of(m, resolved) if loads.friction else None

    def rhs(_t, y):
        nonlocal nfev
        nfev += 1
        w = y[1]
        torque = sense * torque_of(sense * w)
        if system is not None:  # the slide's friction: from the Newton-Euler system (it depends on alpha2)
            return [w, crank_acceleration(m, system, y[0], w, loads, torque, fw)]
        g = gen(y[0])
        return [w, (torque - g.Q[0] - 0.5 * g.dM[0] * w * w) / (g.M[0] + fw)]

    def stall(_t, y):
        return sense * y[1] - STALL_FRACTION * abs(omega0)

    stall.terminal, stall.direction = True, -1
    end = TWO_PI * turns
    marks = sorted({*(b + TWO_PI * k for k in range(turns) for b in _breaks(m, loads, sense) if b > 0), end})
    marks = [p for p in marks if 0 < p <= end]
    atol = np.array([ATOL, ATOL * abs(omega0)])
    t0, y0 = 0.0, np.array([0.0, omega0])
    pieces = []  # (progress reached, OdeSolution, step times)
    stalled, stall_time = False, None
    for target in marks:

        def reach(_t, y, target=target):
            return sense * y[0] - target

        reach.terminal, reach.direction = True, 1
        while True:
            span = 100.0 * (target - sense * y0[0]) / max(abs(y0[1]), STALL_FRACTION * abs(omega0)) + 1.0
            r = solve_ivp(
                rhs,
                (t0, t0 + span),
                y0,
                method="DOP853",
                rtol=RTOL,
                atol=atol,
                events=[reach, stall],
                dense_output=True,
            )
            if r.status == -1:
                raise InvalidParameter(f"the integration failed at t = {r.t[-1]:.6g} s: {r.message}")
            if len(r.t_events[1]):
                stalled, stall_time = True, float(r.t_events[1][0])
                pieces.append((sense * float(r.y_events[1][0][0]), r.sol, r.t))
                t0, y0 = stall_time, r.y_events[1][0]
                break
            if len(r.t_events[0]):
                pieces.append((target, r.sol, r.t))
                t0, y0 = float(r.t_events[0][0]), np.array([sense * target, r.y_events[0][0][1]])
                break
            pieces.append((sense * float(r.y[0, -1]), r.sol, r.t))
            t0, y0 = float(r.t[-1]), r.y[:, -1].copy()
        if stalled:
            break
    t, th, w = _sample(pieces, ppt, sense, end)
    if stalled:
        t, th, w = np.append(t, stall_time), np.append(th, y0[0]), np.append(w, y0[1])
    torque = sense * torque_of(sense * w)
    return Simulation(t, th, w, np.asarray(torque, float), stalled, stall_time, turns, ppt, fw, nfev)


def _sample(pieces, ppt: int, sense: float, end: float):
    """t, theta2, omega2 at progress 2 pi j / ppt (j = 0, 1, ...) reached by the pieces of the integration: the
    time of each by a bracketed Newton iteration on the dense output."""
    ts, ths, ws = [], [], []
    j = 0
    for hi, sol, steps in pieces:
        n_hi = int(math.floor(hi * ppt / TWO_PI + 1e-9))
        if abs(hi - end) < 1e-9 * end:
            n_hi = int(round(end * ppt / TWO_PI))
        targets = TWO_PI * np.arange(j, n_hi + 1) / ppt
        targets = targets[targets <= hi + 1e-12]
        if targets.size == 0:
            continue
        j += targets.size
        y = sol(steps)
        prog = sense * y[0]
        k = np.clip(np.searchsorted(prog, targets), 1, len(steps) - 1)
        a, b = steps[k - 1].copy(), steps[k].copy()
        x = a + (b - a) * np.clip((targets - prog[k - 1]) / np.maximum(prog[k] - prog[k - 1], 1e-300), 0, 1)
        for _ in range(60):
            yx = sol(x)
            f = sense * yx[0] - targets
            a = np.where(f <= 0, x, a)
            b = np.where(f > 0, x, b)
            if np.max(np.abs(f)) <= 1e-13 * max(1.0, float(targets[-1])):
                break
            speed = sense * yx[1]
            with np.errstate(divide="ignore", invalid="ignore"):
                newton = x - f / speed
            mid = 0.5 * (a + b)
            x = np.where(np.isfinite(newton) & (newton > a) & (newton < b), newton, mid)
        yx = sol(x)
        ts.append(x)
        ths.append(yx[0])
        ws.append(yx[1])
    return np.concatenate(ts), np.concatenate(ths), np.concatenate(ws)


__all__ = ["Motor", "Simulation", "TurnSpeeds", "simulate", "steady_mean_torque"]
