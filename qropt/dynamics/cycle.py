"""Cycle quantities of the inverse dynamics: exact extremes (peak torque, peak force at each joint, peak shaking
force), quadratures over the turn (RMS torque, the energy per stroke) and the flywheel.

Extremes: a grid of the turn (of each stroke, closed at its dead centres, where the loads switch there), a
sub-grid within a step of each grid maximum and of the least transmission angle's crank angle (a torque spike
near a toggle can be narrower than the grid step), then a bounded scalar search around the largest (to 1e-12
rad). Quadratures:
Gauss-Legendre on each stroke separately (the cutting force switches at the dead centres, so the integrand is
smooth only within a stroke). SI units.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq, minimize_scalar

from qropt.dynamics import applied
from qropt.dynamics.inverse import _solve, energy, pin_rest_angles, require_sense, system_of, working_way
from qropt.dynamics.model import Loads, Masses
from qropt.validate import LIMIT, number

GRID = 720  # crank angles of the search grid
GAUSS = 48  # Gauss-Legendre nodes per piece of a stroke
REFINED, NEAR = 3, 0.01  # a peak: the grid's local maxima refined, at most 3 and within 1 % of the grid's best
SUB = 32  # sub-grid points each side of a grid maximum, within a grid step (``CycleDynamics.peaks``)
TWO_PI = 2 * math.pi


@dataclass(frozen=True)
class Peak:
    """The largest value of a cycle quantity over the turn and the crank angle (rad) where it occurs."""

    value: float
    theta2: float


@dataclass(frozen=True)
class DynamicExtremes:
    """Peak |torque| (N m), RMS torque (N m, over the turn), mean torque (N m), the peak force magnitude at each
    joint (N), the peak shaking force (N) and shaking moment (N m); each Peak with its crank angle."""

    peak_torque: Peak
    rms_torque: float
    mean_torque: float
    peak_forces: dict
    peak_shaking_force: Peak
    peak_shaking_moment: Peak


@dataclass(frozen=True)
class Flywheel:
    """The flywheel for a coefficient of speed fluctuation ``cs`` at mean speed omega2 (rad/s): the energy
    fluctuation (J: the largest minus the smallest of integral (T - T_mean) dtheta2 over a turn), the added
    inertia (kg m^2) ``energy_fluctuation / (cs omega2^2)``, the mean torque (N m), the energy per turn (J) and
    the energy the motor delivers on the working and on the return stroke (J)."""

    cs: float
    omega2: float
    energy_fluctuation: float
    inertia: float
    mean_torque: float
    energy_per_turn: float
    working_energy: float
    return_energy: float


@dataclass(frozen=True)
class StrokeWork:
    """The energy over a stroke (or a turn), J: ``input`` the crank's work (the integral of T omega2 dt), ``output``
    what the loads absorb (the cutting force, the follower's torque, the forces and torques: negative where they
    drive on balance), ``friction`` what friction dissipates (the pins' and the slide's, >= 0), ``pins``: joint ->
    J, each pin's share of it, ``stored`` the change of the energy the mechanism stores over it (kinetic and
    gravity's potential, 0 over a turn at constant speed): input = output + friction + stored exactly.

    ``efficiency``: the output over the input net of the stored energy, output / (output + friction), where the
    crank drives the loads (``driven_by == "crank"``, output > 0); where the loads deliver energy on balance
    (``driven_by == "loads"``, output < 0: a driving load) it is read the other way, the energy that reaches the
    crank over the energy the loads deliver, (output + friction) / output, so that it is in (-inf, 1] both ways and
    1 without friction (negative where the friction takes more than the loads deliver: the crank drives after
    all). NaN where the loads do no work (output = 0: ``driven_by`` None)."""

    input: float
    output: float
    friction: float
    pins: dict
    stored: float
    efficiency: float
    driven_by: str | None


@dataclass(frozen=True)
class Efficiency:
    """The mechanical efficiency of the working stroke, the return stroke and the turn at a constant omega2
    (``StrokeWork`` each; ``CycleDynamics.efficiency``)."""

    working: StrokeWork
    return_stroke: StrokeWork
    turn: StrokeWork


def _stroke_work(w_in: float, w_f: float, pins: dict, stored: float) -> StrokeWork:
    out = w_in - w_f - stored
    net = out + w_f
    if out > 0:
        eff, by = out / net, "crank"
    elif out < 0:
        eff, by = net / out, "loads"
    else:
        eff, by = math.nan, None
    return StrokeWork(w_in, out, w_f, pins, stored, eff, by)


class CycleDynamics:
    """The dynamics of one mechanism, masses and loads at omega2 and alpha2, evaluated at any crank angles."""

    def __init__(self, m, omega2: float, alpha2: float = 0.0, masses=None, loads=None):
        from qropt.errors import InvalidParameter

        self.m = m
        self.omega2, self.alpha2 = number("omega2", omega2, limit=LIMIT), number("alpha2", alpha2, limit=LIMIT)
        self.loads = Loads() if loads is None else loads
        if not isinstance(self.loads, Loads):
            raise InvalidParameter(f"loads is a qropt.Loads, got {type(self.loads).__name__}")
        require_sense(self.omega2, self.loads)
        self.system = system_of(m, Masses() if masses is None else masses)
        d = m.dead_centres()
        a, _ = m.stroke_angles()
        self.pieces = [(d.theta_max, d.theta_max + a), (d.theta_max + a, d.theta_max + TWO_PI)]
        way = working_way(m, self.loads, self.omega2 or 1.0)
        first = _first_is_working(m, self.omega2 or 1.0, way)
        self.working_pieces = (first, not first)
        self.switching = self.loads.jumps and way is not None
        self.edges = applied.edges(m, self.loads)  # a window's ends, a table's corners: the quadrature splits there
        if self.loads.pin_friction is not None:  # and where a pin's friction moment turns with its relative rotation
            self.edges = sorted({*self.edges, *pin_rest_angles(m, self.system, self.loads.pin_friction)})

    def at(self, theta2, working=None):
        """The dynamics at crank angles theta2 (rad); ``working`` forces the cutting force on or off."""
        t = np.atleast_1d(np.asarray(theta2, float))
        return _solve(self.m, self.system, t, self.omega2, self.alpha2, self.loads, working)

    def quadrature(self, f, pieces=None):
        """integral of f(Dynamics) over the pieces (default: the two strokes, i.e. a turn), Gauss-Legendre on each
        piece split at the loads' edges within it."""
        x, w = np.polynomial.legendre.leggauss(GAUSS)
        total = 0.0
        for piece in pieces or self.pieces:
            for lo, hi in self._split(*piece):
                t = 0.5 * (hi - lo) * x + 0.5 * (hi + lo)
                total += 0.5 * (hi - lo) * float(np.dot(w, f(self.at(t % TWO_PI))))
        return total

    def _split(self, lo: float, hi: float) -> list[tuple]:
        cuts = sorted(c for c in (lo + (e - lo) % TWO_PI for e in self.edges) if lo < c < hi)
        ends = [lo, *cuts, hi]
        return list(zip(ends, ends[1:], strict=False))

    def peak(self, f, jumps: bool = False) -> Peak:
        """The largest f(Dynamics) over the turn: the largest of the grid's local maxima within NEAR of its best
        (a minimax design has several equal peaks), each refined (``peaks``)."""
        return self.peaks(f, REFINED, NEAR, jumps)[0]

    def peaks(self, f, n: int, near: float | None = None, jumps: bool = False) -> list[Peak]:
        """The n largest local maxima of f(Dynamics) over the turn, largest first (``near``: only those within that
        fraction of the largest). Each maximum of the grid, and the crank angle of the least transmission angle
        (where a torque spike near a toggle lives), is searched on a sub-grid of SUB points each side within a
        grid step (one vectorised call: a spike narrower than the grid step, which the grid samples low, is seen)
        and refined by a bounded search to 1e-12 rad. A quantity that ``jumps`` where the loads switch (a joint
        force, at the dead centres) is searched over each stroke closed at its ends with its own load: such a
        quantity may peak at a dead centre, on the working side."""
        found = []
        split = jumps and self.switching
        pieces = zip(self.pieces, self.working_pieces, strict=True) if split else [((0.0, TWO_PI), None)]
        toggle = self.m.gamma_min().theta2
        for (lo, hi), on in pieces:
            k = max(8, math.ceil(GRID * (hi - lo) / TWO_PI))
            closed = on is not None
            t = np.linspace(lo, hi, k + 1) if closed else np.linspace(lo, hi, k, endpoint=False)
            h = (hi - lo) / k
            v = f(self.at(t % TWO_PI, on))
            left, right = np.roll(v, 1), np.roll(v, -1)  # a turn's grid wraps round; a stroke's ends have one side
            if closed:
                left[0] = right[-1] = -np.inf
            sites = t[(v >= left) & (v >= right)].tolist()
            at = lo + (toggle - lo) % TWO_PI
            toggled = not closed or at <= hi
            if toggled:
                sites.append(at)
            sub = np.linspace(-h, h, 2 * SUB + 1)
            grid = np.array(sites)[:, None] + sub[None, :]
            if closed:
                grid = np.clip(grid, lo, hi)
            w = f(self.at(grid.ravel() % TWO_PI, on)).reshape(grid.shape)
            best = np.argmax(w, axis=1)
            seen = set()
            for j, b in enumerate(best):
                key, x = round(float(grid[j, b]) / (h / SUB)), float(grid[j, b])
                if j == len(sites) - 1 and toggled and b in (0, 2 * SUB) and not (closed and x in (lo, hi)):
                    continue  # the toggle's window rises out of it: no maximum inside (a grid site holds it)
                if key not in seen:
                    seen.add(key)
                    found.append((float(w[j, b]), x, lo, hi, h / SUB, closed, on))
        found.sort(key=lambda c: -c[0])
        if near is not None:
            found = [c for c in found if c[0] >= found[0][0] - near * abs(found[0][0])]
        out = []
        for value, t0, lo, hi, h, closed, on in found[:n]:
            a, b = (max(lo, t0 - h), min(hi, t0 + h)) if closed else (t0 - h, t0 + h)
            r = minimize_scalar(
                lambda th, on=on: -float(f(self.at(th % TWO_PI, on))[0]),
                bounds=(a, b),
                method="bounded",
                options={"xatol": 1e-12},
            )
            out.append(Peak(-float(r.fun), float(r.x % TWO_PI)) if -r.fun >= value else Peak(value, t0 % TWO_PI))
        return sorted(out, key=lambda p: -p.value)

    def extremes(self) -> DynamicExtremes:
        t = np.linspace(0.0, TWO_PI, GRID, endpoint=False)
        joints = list(self.at(t[:1]).joint_forces)
        mean = self.quadrature(lambda d: d.torque) / TWO_PI
        rms = math.sqrt(self.quadrature(lambda d: d.torque**2) / TWO_PI)
        return DynamicExtremes(
            peak_torque=self.peak(lambda d: np.abs(d.torque)),
            rms_torque=rms,
            mean_torque=mean,
            peak_forces={j: self.peak(lambda d, j=j: np.hypot(*d.joint_forces[j].T), jumps=True) for j in joints},
            peak_shaking_force=self.peak(lambda d: np.hypot(*d.shaking_force.T)),
            peak_shaking_moment=self.peak(lambda d: np.abs(d.shaking_moment)),
        )

    def efficiency(self) -> Efficiency:
        """The mechanical efficiency of the working stroke, the return stroke and the turn (``Efficiency``,
        ``StrokeWork``): the crank's work and the friction's (the pins' and the slide's) by Gauss-Legendre on each
        stroke, split where the loads switch and where a pin's relative rotation turns; the loads' work from the
        power balance, input - friction - the stored energy's change (kinetic and gravity's, exact at the
        strokes' ends). At a constant, nonzero omega2."""
        return _efficiency(self)

    def flywheel(self, cs: float) -> Flywheel:
        """See ``Flywheel``: the energy's extremes where T = T_mean, each root refined by brentq."""
        from qropt.errors import InvalidParameter

        if isinstance(cs, bool) or not isinstance(cs, (int, float)) or not 0 < cs < 2:
            raise InvalidParameter(f"cs, the coefficient of speed fluctuation, is a number in (0, 2), got {cs!r}")
        if self.omega2 == 0 or self.alpha2 != 0:
            raise InvalidParameter("the flywheel is sized at a constant, nonzero omega2 (alpha2 = 0)")
        mean = self.quadrature(lambda d: d.torque) / TWO_PI
        t0 = self.pieces[0][0]
        t = t0 + np.linspace(0.0, TWO_PI, GRID + 1)

        def excess(th):
            return float(self.at(th % TWO_PI).torque[0]) - mean

        v = self.at(t % TWO_PI).torque - mean
        roots = [t0]
        for i in range(GRID):
            if v[i] == 0.0:
                roots.append(float(t[i]))
            elif v[i] * v[i + 1] < 0:
                roots.append(brentq(excess, t[i], t[i + 1], xtol=1e-13))
        roots.append(t0 + TWO_PI)
        cuts = sorted({*roots, self.pieces[0][1]})  # the dead centre splits the integrand's smooth pieces
        energy, e = [0.0], 0.0
        for lo, hi in zip(cuts, cuts[1:], strict=False):
            if hi - lo > 0:
                e += self.quadrature(lambda d: d.torque - mean, [(lo, hi)])
                energy.append(e)
        delta = max(energy) - min(energy)
        work = self.quadrature(lambda d: d.torque, [self.pieces[0]])
        back = self.quadrature(lambda d: d.torque, [self.pieces[1]])
        w, r = (work, back) if self.working_pieces[0] else (back, work)
        sense = math.copysign(1.0, self.omega2)  # energy delivered: the integral of T omega2 dt = sign * T dtheta2
        w, r = sense * w, sense * r
        inertia = delta / (cs * self.omega2**2)
        return Flywheel(cs, self.omega2, delta, inertia, mean, sense * TWO_PI * mean, w, r)


def _efficiency(cd: CycleDynamics) -> Efficiency:
    from qropt.errors import InvalidParameter

    if cd.omega2 == 0 or cd.alpha2 != 0:
        raise InvalidParameter("the efficiency is taken at a constant, nonzero omega2 (alpha2 = 0)")
    x, w = np.polynomial.legendre.leggauss(GAUSS)
    rate = abs(cd.omega2)
    sense = math.copysign(1.0, cd.omega2)
    kinks = _kinks(cd)
    strokes = []
    for lo, hi in cd.pieces:
        w_in, w_f, pins = 0.0, 0.0, {}
        cuts = sorted(c for c in (lo + (e - lo) % TWO_PI for e in kinks) if lo < c < hi)
        pieces = [p for a, b in zip([lo, *cuts], [*cuts, hi], strict=True) for p in cd._split(a, b)]
        for a, b in pieces:
            t = (0.5 * (b - a) * x + 0.5 * (b + a)) % TWO_PI
            d = cd.at(t)
            h = 0.5 * (b - a) * w
            w_in += sense * float(np.dot(h, d.torque))  # T omega2 dt = sign(omega2) T dtheta2
            lost = d.pin_friction_power
            if "slide" in d.joint_forces and cd.loads.friction:
                lost = lost + np.abs(d.joint_forces["slide"][:, 0] * energy(cd.m, cd.system, t, cd.omega2, cd.loads)[1])
            w_f += float(np.dot(h, lost)) / rate  # P dt = P dtheta2 / |omega2|
            for j, v in (d.pin_power_loss or {}).items():
                pins[j] = pins.get(j, 0.0) + float(np.dot(h, v)) / rate
        ends = energy(cd.m, cd.system, np.array([lo, hi]) % TWO_PI, cd.omega2, cd.loads)[0]
        strokes.append((w_in, w_f, pins, float(ends[1] - ends[0])))
    first, second = (_stroke_work(*v) for v in strokes)
    turn = _stroke_work(
        first.input + second.input,
        first.friction + second.friction,
        {j: first.pins[j] + second.pins[j] for j in first.pins},
        0.0,  # a turn at constant speed stores nothing
    )
    working, back = (first, second) if cd.working_pieces[0] else (second, first)
    return Efficiency(working, back, turn)


def _kinks(cd: CycleDynamics) -> list[float]:
    """The crank angles (rad) where a force that friction reads passes through zero (the friction's |F| has a kink
    there: a massless block's pin force along its slot's normal, the guide's normal force), inside the strokes:
    a grid's sign changes of F(theta) . F(theta_i), refined by brentq."""
    if cd.loads.pin_friction is None and not cd.loads.friction:
        return []
    out = []
    for lo, hi in cd.pieces:
        t = np.linspace(lo, hi, GRID // 2 + 1)[1:-1]
        forces = cd.at(t % TWO_PI).joint_forces
        for name, f in forces.items():
            if name == "slide":
                f = f * np.array([0.0, 1.0])
            dots = np.einsum("nd,nd->n", f[:-1], f[1:])
            for i in np.flatnonzero(dots < 0):
                ref = f[i]

                def along(th, name=name, ref=ref):
                    v = cd.at(np.array([th % TWO_PI])).joint_forces[name][0]
                    return float(v[1] * ref[1] if name == "slide" else v @ ref)

                out.append(brentq(along, t[i], t[i + 1], xtol=1e-13) % TWO_PI)
    return out


def _first_is_working(m, omega2, way=None) -> bool:
    """Whether the crank interval theta_max -> theta_min (counter-clockwise) is the working stroke (``way``: its
    direction, default the slow stroke's)."""
    from qropt.dynamics.inverse import _working

    d = m.dead_centres()
    a, _ = m.stroke_angles()
    return bool(_working(m, np.array([(d.theta_max + a / 2) % TWO_PI]), omega2, way)[0])


__all__ = ["CycleDynamics", "DynamicExtremes", "Efficiency", "Flywheel", "Peak", "StrokeWork"]
