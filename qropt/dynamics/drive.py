"""The drive: a motor turning the crank through a gearbox, and the figures a designer sizes it by.

SI throughout (N m, rad/s, W, kg m^2, s). A ``Drive`` of ratio i and efficiency eta: the motor turns at
``i * omega2``; the gearbox's and the rotor's inertias count at the crank as ``i^2 * J`` (lossless: the efficiency
applies to the motor's torque, not to the inertias' own torques). Signs follow the contract: a crank torque T is
what the drive applies to the crank (``T * omega2`` the power it delivers), a motor torque T_m what the motor
applies to its shaft (``T_m * i * omega2`` the motor's power). Where the motor drives (``T * omega2 > 0``) it
supplies the gearbox's losses, ``T_m = T / (i eta)``; where the crank drives the motor (it brakes),
``T_m = T eta / i``. A ``Motor``'s own numbers (its line, its ratings) are in the sense of rotation at the motor
shaft, as ``simulate`` reads them.

``drive_check`` reports the drive at constant crank speed (the torque over the turn, its peak and RMS, the peak
and mean power, all at the motor) and, with a motor, the steady motion under the motor's torque-speed line with a
flywheel (given, or sized for a coefficient of speed fluctuation Cs), found and confirmed by ``simulate``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import casadi
import numpy as np
from scipy.optimize import brentq

from qropt.dynamics.forward import Motor, Simulation, simulate
from qropt.dynamics.inverse import generalised
from qropt.dynamics.model import Masses, _real
from qropt.errors import InvalidParameter

TWO_PI = 2 * math.pi
GRID = 720  # crank angles of the reported torque curve, and of the search for the torque's zeros
PERIODIC = 1e-6  # a steady turn: its end speed equals its start speed to this, relative
CS_RTOL = 1e-3  # the sized flywheel's simulated Cs equals the Cs asked to this, relative
SIZING_STEPS = 12  # at most this many flywheels tried
START_FROM = 1e-3  # start-up from rest: integrated from this fraction of the steady mean speed (0 cannot start)
SETTLED = 0.02  # start-up ends when the crank's speed first reaches (1 - SETTLED) times the steady mean speed
START_CHUNK, START_TURNS = 8, 200  # start-up simulated 1, 2, 4, then this many turns at a time, up to this many


@dataclass(frozen=True)
class Drive:
    """A gearbox of ``ratio`` i (> 0: motor speed = i * crank speed) and ``efficiency`` eta (0 < eta <= 1),
    ``gearbox_inertia`` (kg m^2, at the motor shaft) and an optional ``motor`` (``qropt.Motor``: its line,
    ratings and rotor inertia at the motor shaft)."""

    ratio: float
    efficiency: float = 1.0
    gearbox_inertia: float = 0.0
    motor: Motor | None = None

    def __post_init__(self):
        object.__setattr__(
            self, "ratio", _real("the drive's ratio (motor speed / crank speed)", self.ratio, positive=True)
        )
        eta = _real("the drive's efficiency", self.efficiency)
        if not 0 < eta <= 1:
            raise InvalidParameter(f"the drive's efficiency must lie in (0, 1], got {eta:g}")
        object.__setattr__(self, "efficiency", eta)
        j = _real("the drive's gearbox_inertia (kg m^2, at the motor shaft)", self.gearbox_inertia, nonneg=True)
        object.__setattr__(self, "gearbox_inertia", j)
        if self.motor is not None and not isinstance(self.motor, Motor):
            raise InvalidParameter(f"the drive's motor is a qropt.Motor or None, got {type(self.motor).__name__}")

    def to_dict(self) -> dict:
        """Its numbers as plain data (the motor's by ``Motor.to_dict``)."""
        out = {"ratio": self.ratio, "efficiency": self.efficiency, "gearbox_inertia": self.gearbox_inertia}
        return out | ({} if self.motor is None else {"motor": self.motor.to_dict()})

    @classmethod
    def from_dict(cls, d) -> Drive:
        """The Drive of ``to_dict``; InvalidParameter naming what is wrong."""
        keys = ("ratio", "efficiency", "gearbox_inertia", "motor")
        if not isinstance(d, dict) or "ratio" not in d or set(d) - set(keys):
            raise InvalidParameter(f"a drive is a table of {list(keys)} (ratio required), got {d!r:.160}")
        motor = d.get("motor")
        return cls(**{**d, "motor": None if motor is None else Motor.from_dict(motor)})

    @property
    def reflected_inertia(self) -> float:
        """The gearbox's and the rotor's inertia at the crank: ``i^2 (gearbox_inertia + motor.inertia)`` kg m^2."""
        rotor = 0.0 if self.motor is None else self.motor.inertia
        return self.ratio**2 * (self.gearbox_inertia + rotor)

    def motor_torque(self, crank_torque, omega2: float):
        """The motor's torque (N m) for crank torques T (N m, a number, an array or a CasADi expression) at crank
        speed omega2 (rad/s): ``T / (i eta)`` where the motor drives (``T * omega2 > 0``), ``T eta / i`` where it
        brakes."""
        i, eta = self.ratio, self.efficiency
        if isinstance(crank_torque, casadi.SX | casadi.MX):
            t = crank_torque
            return casadi.if_else(t * omega2 > 0, t / (i * eta), t * eta / i)
        t = np.asarray(crank_torque, float)
        out = np.where(t * omega2 > 0, t / (i * eta), t * eta / i)
        return float(out) if out.ndim == 0 else out

    def crank_torque(self, omega):
        """The motor's torque-speed line seen at the crank: the torque (N m) on the crank at crank speed omega
        (rad/s; a number or an array), both in the sense of rotation. With T_m the motor's torque at ``i * omega``:
        ``i eta T_m`` where it drives (``T_m * omega >= 0``), ``i T_m / eta`` where it brakes. A callable
        ``simulate`` takes as its motor."""
        if self.motor is None:
            raise InvalidParameter("the drive has no motor: give Drive(..., motor=qropt.Motor(...))")
        w = np.asarray(omega, float)
        tm = np.asarray(self.motor.torque(self.ratio * w), float)
        i, eta = self.ratio, self.efficiency
        out = np.where(tm * w >= 0, i * eta * tm, i * tm / eta)
        return float(out) if out.ndim == 0 else out


@dataclass(frozen=True)
class DriveCheck:
    """The drive at constant crank speed ``omega2`` (rad/s), at the motor: ``theta2`` (rad, GRID + 1 angles over
    the turn), ``crank_torque`` and ``motor_torque`` there (N m, signed as in the module), ``peak_torque`` (the
    largest |T_m|, a ``Peak`` with its crank angle), ``rms_torque`` and ``mean_torque`` (over the turn: at constant
    speed, over time), ``peak_power`` (W, the largest power the motor delivers, ``max(T_m * i * omega2)``, with
    its crank angle) and ``mean_power`` (W, the motor's mean power: the crank's mean power plus the gearbox's
    losses), ``motor_speed`` (rad/s, ``i * omega2``) and ``reflected_inertia`` (kg m^2 at the crank).

    Against the motor's ratings (None where it has none): ``peak_ok`` (``peak_torque <= motor.peak_torque``),
    ``rms_ok`` (``rms_torque <= motor.rated_torque``), ``speed_ok`` (``|motor_speed| <= motor.rated_speed``).

    The steady motion under the motor (None without a motor): ``flywheel`` (kg m^2 on the crank shaft, beyond the
    mechanism's and the reflected inertia; sized for ``cs`` when it is given), ``steady`` (``simulate``'s run of
    one steady turn from theta2 = 0 with that flywheel plus the reflected inertia; its ``motor_torque`` is the
    torque on the crank), ``speed_fluctuation`` and ``mean_speed`` (rad/s, the crank's) of that turn, ``stalled``
    (the crank stopped: the motor cannot carry the turn, or cannot start it from rest at theta2 = 0) and
    ``startup_time`` (s: from rest at theta2 = 0 until the crank's speed first reaches 98 % of ``mean_speed``;
    None for a constant-torque motor, or where the start-up stalls or takes over 200 turns). ``sizing_steps``: the
    flywheels tried."""

    drive: Drive
    omega2: float
    theta2: np.ndarray
    crank_torque: np.ndarray
    motor_torque: np.ndarray
    peak_torque: object
    rms_torque: float
    mean_torque: float
    peak_power: object
    mean_power: float
    motor_speed: float
    reflected_inertia: float
    peak_ok: bool | None
    rms_ok: bool | None
    speed_ok: bool | None
    cs: float | None = None
    flywheel: float | None = None
    steady: Simulation | None = None
    speed_fluctuation: float | None = None
    mean_speed: float | None = None
    stalled: bool | None = None
    startup_time: float | None = None
    sizing_steps: int = 0


def drive_check(m, drive: Drive, omega2: float, *, masses=None, loads=None, flywheel: float = 0.0, cs=None):
    """The drive's figures for mechanism m at crank speed omega2 (rad/s, nonzero; its sign the sense of rotation),
    with ``masses`` and ``loads`` (``qropt.Masses``, ``qropt.Loads``), a ``flywheel`` (kg m^2) on the crank
    shaft or ``cs``, the coefficient of speed fluctuation to size one for (``DriveCheck``).

    Constant speed: the exact crank torque (``CycleDynamics``), reflected; the RMS and mean are Gauss-Legendre
    quadratures on each stroke split where the crank torque changes sign (where the efficiency switches) and the
    peaks exact (``CycleDynamics.peak``).

    The steady motion, with a torque-speed line (``Motor.line``, ``Motor.induction``): the turn from theta2 = 0
    whose end speed is its start speed (a secant on the start speed, each step one turn of ``simulate`` with the
    line reflected, ``Drive.crank_torque``); its mean speed is where the motor's line meets the load, not omega2.
    The flywheel for ``cs``: a secant on 1 / Cs (nearly linear in the flywheel) over simulated steady turns, from
    the constant-speed energy method (``CycleDynamics.flywheel``) less the reflected inertia, until the simulated
    Cs is within 0.1 % of ``cs`` (or zero flywheel, when the mechanism and the drive alone keep Cs below it).
    With a constant-torque motor the motion's mean speed is set by its start: the check runs the motor at the torque
    the turn needs at omega2 (its own ``stall`` is not used), on the turn whose mean speed is omega2, and has no
    start-up time."""
    if not isinstance(drive, Drive):
        raise InvalidParameter(f"drive is a qropt.Drive, got {type(drive).__name__}")
    omega2 = _real("omega2 (rad/s)", omega2, nonzero=True)
    fw = _real("flywheel (kg m^2)", flywheel, nonneg=True)
    if cs is not None:
        if isinstance(cs, bool) or not isinstance(cs, (int, float)) or not 0 < cs < 2:
            raise InvalidParameter(f"cs, the coefficient of speed fluctuation, is a number in (0, 2), got {cs!r:.60}")
        cs = float(cs)
        if fw:
            raise InvalidParameter("give a flywheel or cs (to size one), not both")
        if drive.motor is None:
            raise InvalidParameter("sizing the flywheel for cs needs the drive's motor (Drive(..., motor=...))")
    from qropt.dynamics.cycle import CycleDynamics

    masses = Masses() if masses is None else masses
    cd = CycleDynamics(m, omega2, 0.0, masses, loads)
    i, motor = drive.ratio, drive.motor

    def reflect(d):
        return drive.motor_torque(d.torque, omega2)

    pieces = _split_at_zeros(cd)
    mean_t = cd.quadrature(reflect, pieces) / TWO_PI
    rms = rms_motor_torque(cd, drive, pieces)
    peak = cd.peak(lambda d: np.abs(reflect(d)))
    wm = i * omega2
    top = cd.peak(lambda d: reflect(d) * wm)
    theta = np.linspace(0.0, TWO_PI, GRID + 1)
    crank = cd.at(theta).torque
    rated = motor is not None
    out = {
        "drive": drive,
        "omega2": omega2,
        "theta2": theta,
        "crank_torque": crank,
        "motor_torque": drive.motor_torque(crank, omega2),
        "peak_torque": peak,
        "rms_torque": rms,
        "mean_torque": mean_t,
        "peak_power": top,
        "mean_power": mean_t * wm,
        "motor_speed": wm,
        "reflected_inertia": drive.reflected_inertia,
        "peak_ok": None if not rated or motor.peak_torque is None else peak.value <= motor.peak_torque,
        "rms_ok": None if not rated or motor.rated_torque is None else rms <= motor.rated_torque,
        "speed_ok": None if not rated or motor.rated_speed is None else abs(wm) <= motor.rated_speed,
        "cs": cs,
    }
    if motor is None:
        return DriveCheck(**out)
    need = cd.quadrature(lambda d: d.torque) / TWO_PI  # the crank's mean torque at omega2
    motion = _Motion(m, drive, masses, cd.loads, omega2, need)
    out |= motion.check(cd, fw, cs)
    return DriveCheck(**out)


def rms_motor_torque(cd, drive: Drive, pieces=None, *, split: bool = True) -> float:
    """The RMS of the motor's torque over the turn (N m) for a cycle's dynamics ``cd`` (``CycleDynamics`` at its
    constant omega2): Gauss-Legendre on each stroke's pieces, ``split`` where the crank torque changes sign (the
    motor turns from driving to braking, a kink of its torque's square), else on the cycle's own pieces (the
    strokes, split at the loads' edges: the synthesis NLP's rule); ``pieces``: the split pieces if already found."""
    if split and pieces is None:
        pieces = _split_at_zeros(cd)
    return math.sqrt(cd.quadrature(lambda d: drive.motor_torque(d.torque, cd.omega2) ** 2, pieces) / TWO_PI)


def _split_at_zeros(cd) -> list[tuple]:
    """The two strokes, each split where the crank torque changes sign (brentq between grid angles; each stroke
    closed at its dead centres with its own load)."""
    out = []
    for (lo, hi), working in zip(cd.pieces, cd.working_pieces, strict=True):
        on = working if cd.switching else None

        def f(th, on=on):
            return float(cd.at(th % TWO_PI, on).torque[0])

        t = np.linspace(lo, hi, max(8, math.ceil(GRID * (hi - lo) / TWO_PI)) + 1)
        v = cd.at(t % TWO_PI, on).torque
        cuts = [lo]
        for a, b, va, vb in zip(t[:-1], t[1:], v[:-1], v[1:], strict=True):
            if va * vb < 0:
                cuts.append(brentq(f, a, b, xtol=1e-13))
        cuts.append(hi)
        out += [(a, b) for a, b in zip(cuts, cuts[1:], strict=False) if b > a]
    return out


class _Motion:
    """The steady turn and the start-up under the drive's motor (see ``drive_check``); speeds in the sense of
    rotation."""

    def __init__(self, m, drive: Drive, masses, loads, omega2: float, need: float):
        self.m, self.drive, self.masses, self.loads = m, drive, masses, loads
        self.sense = math.copysign(1.0, omega2)
        self.omega = abs(omega2)
        self.reflected = drive.reflected_inertia
        grid = np.linspace(0.0, TWO_PI, 64, endpoint=False)
        self.base = self.reflected + float(np.mean(generalised(m, grid, masses=masses).M))  # the crank's own (mean)
        motor = drive.motor
        self.constant = motor.is_constant
        tau = self.sense * need  # the torque the turn needs on the crank, in the sense of rotation
        if self.constant:
            self.torque, self.guess = Motor.constant(tau), self.omega
        else:
            self.torque = drive.crank_torque
            self.guess = _operating_speed(drive, tau)

    def run(self, flywheel: float, w0: float, turns: int = 1) -> Simulation:
        return simulate(
            self.m,
            self.torque,
            masses=self.masses,
            loads=self.loads,
            flywheel=flywheel + self.reflected,
            omega0=self.sense * w0,
            turns=turns,
        )

    def steady(self, flywheel: float, w0: float) -> tuple[Simulation | None, float]:
        """The steady turn with this flywheel (None where the crank stalls) and its start speed: a secant on the
        start speed w0 for end speed = w0 (a line motor) or mean speed = omega2 (a constant torque)."""

        def residual(w):
            s = self.run(flywheel, w)
            if s.stalled:
                return s, None
            end = self.sense * float(s.omega2[-1])
            r = s.turn_speeds(0).mean - self.omega if self.constant else end - w
            return s, r

        a = w0
        s, ra = residual(a)
        if ra is None:
            return None, a
        if abs(ra) <= PERIODIC * a:
            return s, a
        b = a - ra if self.constant else a + ra / (1 - self._contraction(flywheel, a))  # then the secant
        b = max(b, 0.1 * a)
        for _ in range(20):
            s, rb = residual(b)
            if rb is None:
                return None, b
            if abs(rb) <= PERIODIC * b:
                return s, b
            if rb == ra:
                break
            a, b, ra = b, b - rb * (b - a) / (rb - ra), rb
            b = max(b, 0.1 * a)
        return s, b

    def _contraction(self, flywheel: float, w: float) -> float:
        """The end speed's change per unit start speed over a turn (a first estimate of the secant's slope): a
        deviation decays as exp(-k t / J) with k the line's slope at the crank and J its whole inertia."""
        h = 1e-6 * w
        k = (float(self.torque(w - h)) - float(self.torque(w + h))) / (2 * h)
        return math.exp(-max(k, 0.0) * TWO_PI / (w * (flywheel + self.base)))

    def check(self, cd, flywheel: float, cs: float | None) -> dict:
        if self.guess is None:  # the line cannot carry the turn's mean torque at any speed: it stalls
            out = {"flywheel": flywheel if cs is None else None}
            return out | self._startup(flywheel, None) | {"stalled": True}
        steps = 0
        if cs is None:
            s, w0 = self.steady(flywheel, self.guess)
        else:
            s, w0, flywheel, steps = self._size(cd, cs)
        out = {"flywheel": flywheel, "sizing_steps": steps}
        if s is None:
            return out | {"stalled": True}
        out |= {"steady": s, "speed_fluctuation": s.speed_fluctuation(0), "mean_speed": s.turn_speeds(0).mean}
        out["stalled"] = False
        return out | self._startup(flywheel, out["mean_speed"])

    def _size(self, cd, cs: float):
        """The flywheel whose steady turn has speed fluctuation cs: a secant on 1 / Cs against the flywheel."""
        w = self.guess
        energy = cd.flywheel(cs).energy_fluctuation
        base = self.base
        f0 = max(0.0, energy / (cs * w * w) - self.reflected)
        tried = []  # (flywheel, 1 / Cs)
        f, best = f0, None
        for step in range(1, SIZING_STEPS + 1):
            s, w0 = self.steady(f, w)
            if s is None:  # stalled: more flywheel
                f = 2 * (f + base) - base
                continue
            c = s.speed_fluctuation(0)
            best = (s, w0, f, step)
            if abs(c / cs - 1) <= CS_RTOL or (f == 0 and c <= cs):
                return best
            tried.append((f, 1 / c))
            if len(tried) == 1:
                nxt = (f + base) * c / cs - base  # 1 / Cs proportional to the crank's whole inertia
            else:
                (f1, h1), (f2, h2) = tried[-2], tried[-1]
                nxt = f2 + (1 / cs - h2) * (f2 - f1) / (h2 - h1) if h2 != h1 else f2 * c / cs
            f, mu = max(0.0, nxt), s.turn_speeds(0).mean
            w = mu + (w0 - mu) * (best[2] + base) / (f + base)  # the start's offset from the mean scales as 1 / J
            if f == 0.0 and tried[-1][0] == 0.0:
                return best
        if best is None:
            return None, w, f, SIZING_STEPS
        return best

    def _startup(self, flywheel: float, mean: float | None) -> dict:
        """From rest at theta2 = 0 (from START_FROM of the speed: 0 cannot be integrated) until the speed reaches
        (1 - SETTLED) * mean, START_CHUNK turns at a time."""
        if self.constant:
            return {"startup_time": None}
        start = START_FROM * (mean if mean is not None else self.omega)
        w0, t0, done, chunk = start, 0.0, 0, 1
        limit = START_TURNS if mean is not None else START_CHUNK  # no steady speed: only to see it stall
        while done < limit:
            s = self.run(flywheel, w0, chunk)
            done, chunk = done + chunk, min(2 * chunk, START_CHUNK)
            w = self.sense * s.omega2
            if mean is not None:
                hit = np.flatnonzero(w >= (1 - SETTLED) * mean)
                if hit.size:
                    k = int(hit[0])
                    goal = (1 - SETTLED) * mean
                    t = s.t[k] if k == 0 else np.interp(goal, [w[k - 1], w[k]], [s.t[k - 1], s.t[k]])
                    return {"startup_time": t0 + float(t), "stalled": False}
            if s.stalled:
                return {"startup_time": None, "stalled": True}
            w0, t0 = float(w[-1]), t0 + float(s.t[-1])
        return {"startup_time": None, "stalled": False}


def _operating_speed(drive: Drive, tau: float) -> float | None:
    """The crank speed (rad/s, in the sense of rotation) where the motor's line reflected to the crank gives the
    torque tau (N m): the steady mean speed's first estimate; None where no positive speed does."""

    def excess(w):
        return float(drive.crank_torque(w)) - tau

    top = drive.motor.free_speed / drive.ratio
    if excess(0.0) <= 0:
        return None
    hi = top
    for _ in range(60):
        if excess(hi) < 0:
            return brentq(excess, 0.0, hi, xtol=1e-12 * top)
        hi *= 2
    return None


__all__ = ["Drive", "DriveCheck", "drive_check", "rms_motor_torque"]
