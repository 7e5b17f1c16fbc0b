"""Servo-driven cranks: the fastest crank-speed profile omega2(theta2) > 0 under speed, acceleration,
cutting-speed and torque limits, a second-order cone program in b = omega2^2 (Verscheure et al.,
IEEE TAC 2009) solved with cvxpy and CLARABEL.

Discretisation: the turn is cut at the dead centres (and the ends of the cut window) into n cells
of about 2 pi / n; b is linear in theta2 on each cell, so alpha2 = b'/2 is constant on a cell and
the cell's time 2 h / (sqrt(b_k) + sqrt(b_k+1)) is exact and convex. The slider's v^2 = x'^2 b,
a = x'' b + x' alpha2 (x', x'' exact from ``motion`` at unit crank speed) and the torque are limited
at every node, on both sides of it (alpha2 jumps there). Between nodes a limited quantity q exceeds
its node values by at most h^2/8 max|q''| on the cell (linear interpolation error): O(h^2), about
1e-5..1e-4 relative at n = 720 in the examples; ``SpeedProfile.check`` measures it by exact sampling.

Units: SI (a mechanism's lengths are taken in metres): theta2 rad, omega2 rad/s, alpha2 rad/s^2, time s, slider
v m/s, a m/s^2, force N, inertia kg m^2 (constant, reduced to the crank), torque N m; the torque is
inertia alpha2 + force |dx/dtheta2| on the working stroke, or with a mass model and loads (``masses``, ``loads``)
the crank's full equation of motion M(theta2) alpha2 + M'(theta2) omega2^2 / 2 + Q(theta2), still linear in b.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from functools import cached_property
from typing import NamedTuple

import numpy as np
import scipy.sparse as sp

from qropt.errors import InvalidParameter, UnsupportedLoad
from qropt.mechanisms import Mechanism
from qropt.units import to_metres
from qropt.validate import MAGNITUDE, number

OBJECTIVES = ("min_cycle_time", "min_return_time")
MIN_CELLS, MAX_CELLS = 36, 100_000
BINDING_TOL = 1e-6  # a phase-one slack or dual above this (relative) names a limit as binding
SQUARED = ("omega_max", "v_max", "v_cut")  # limits stated on squares in b
BADLY_SCALED = 1e8  # a row coefficient above this: the limit allows changes of b below 1e-8 of omega_max^2


class ConstantSpeed(NamedTuple):
    """The same mechanism at constant omega2 = omega_max: cycle time (s), geometric time ratio and peak
    torque force * max |dx/dtheta2| over the working stroke (None without a force)."""

    cycle_time: float
    time_ratio: float
    peak_torque: float | None


class ServoMotion(NamedTuple):
    """A profile sampled exactly: time (s), theta2 (rad), omega2 (rad/s), alpha2 (rad/s^2), slider x, v, a
    and the motor torque; each cell has refine + 1 samples, so nodes appear twice (alpha2 jumps there)."""

    t: np.ndarray
    theta: np.ndarray
    omega: np.ndarray
    alpha: np.ndarray
    x: np.ndarray
    v: np.ndarray
    a: np.ndarray
    torque: np.ndarray


@dataclass(frozen=True, repr=False)
class SpeedProfile:
    """A crank-speed profile: nodes ``theta`` (n + 1, rad, from the working stroke's first dead centre to
    one turn later), ``omega`` there (rad/s), ``alpha`` on each cell (n, rad/s^2), ``time`` at the nodes (s).

    ``status`` is 'optimal', 'acceptable' (solver accuracy reduced), 'infeasible' (``binding`` names the
    limits that conflict) or 'failed'; arrays are None unless a profile was found.
    """

    status: str
    message: str
    mechanism: Mechanism
    limits: dict
    objective: str
    theta: np.ndarray | None = None
    omega: np.ndarray | None = None
    alpha: np.ndarray | None = None
    time: np.ndarray | None = None
    working_cells: int = 0
    cut_cells: tuple | None = None
    force: float = 0.0
    inertia: float = 0.0
    binding: tuple = field(default_factory=tuple)
    masses: object = None  # qropt.Masses: every link's inertia in the torque (with loads: their Q)
    loads: object = None

    def __repr__(self):
        if self.time is None:
            return f"SpeedProfile(status={self.status!r}, message={self.message!r})"
        tq = "" if self.peak_torque is None else f", peak_torque={self.peak_torque:.6g}"
        return (
            f"SpeedProfile(status={self.status!r}, cycle_time={self.cycle_time:.6g} s, "
            f"time_ratio={self.time_ratio:.6g}{tq}, n={self.alpha.size})"
        )

    @property
    def cycle_time(self) -> float | None:
        """Time of one crank turn (s)."""
        return None if self.time is None else float(self.time[-1])

    @property
    def working_time(self) -> float | None:
        """Time of the working stroke, dead centre to dead centre (s)."""
        return None if self.time is None else float(self.time[self.working_cells])

    @property
    def return_time(self) -> float | None:
        """Time of the return stroke (s)."""
        return None if self.time is None else self.cycle_time - self.working_time

    @property
    def time_ratio(self) -> float | None:
        """Achieved time ratio: the slower stroke's time over the faster one's (>= 1)."""
        if self.time is None:
            return None
        w, r = self.working_time, self.return_time
        return max(w, r) / min(w, r)

    @property
    def peak_torque(self) -> float | None:
        """Largest |motor torque| over the turn (from ``motion()``), None without force or inertia."""
        if self.time is None or (self.force == 0.0 and self.inertia == 0.0 and not self._dynamic):
            return None
        return float(np.abs(self.motion().torque).max())

    def constant_speed(self) -> ConstantSpeed:
        """The reference without a servo: the crank at constant omega_max."""
        m = self.mechanism
        peak = self.force * m.peak_velocity(1.0).torque_per_newton if self.force else None
        return ConstantSpeed(2 * math.pi / self.limits["omega_max"], m.time_ratio(), peak)

    def motion(self, refine: int = 10) -> ServoMotion:
        """The profile sampled on a grid ``refine`` times finer: b linear on each cell, times exact for it."""
        if isinstance(refine, bool) or not isinstance(refine, (int, np.integer)):
            raise InvalidParameter(f"refine must be an integer, got {refine!r}")
        return self._motion(int(refine))

    @cached_property
    def _cache(self) -> dict:
        return {}

    @property
    def _dynamic(self) -> bool:
        return self.masses is not None or self.loads is not None

    def _motion(self, refine: int) -> ServoMotion:
        if self.time is None:
            raise InvalidParameter(f"no profile to sample: status {self.status!r} ({self.message})")
        if not 1 <= refine <= 1000:
            raise InvalidParameter(f"refine must be in 1..1000, got {refine}")
        if refine in self._cache:
            return self._cache[refine]
        th, h = self.theta, np.diff(self.theta)
        b = self.omega**2
        u = np.linspace(0.0, 1.0, refine + 1)[None, :]
        bu = b[:-1, None] + u * (b[1:] - b[:-1])[:, None]
        wu = np.sqrt(bu)
        with np.errstate(divide="ignore", invalid="ignore"):
            dt = np.where(u > 0, 2 * u * h[:, None] / (wu[:, :1] + wu), 0.0)
        theta = th[:-1, None] + u * h[:, None]
        alpha = np.broadcast_to(self.alpha[:, None], theta.shape)
        mo = self.mechanism.motion(theta.ravel(), 1.0, 0.0)
        xp, xpp = mo.v.reshape(theta.shape), mo.a.reshape(theta.shape)
        working = (np.arange(h.size) < self.working_cells)[:, None]
        torque = self.inertia * alpha + self.force * np.abs(xp) * working
        if self._dynamic:  # the full inertia: M alpha2 + M' omega2^2 / 2 + Q
            gen = _generalised(
                self.mechanism, theta.ravel(), self.masses, self.loads, working.repeat(refine + 1, 1).ravel()
            )
            shape = theta.shape
            torque = torque + gen.M.reshape(shape) * alpha + 0.5 * gen.dM.reshape(shape) * bu + gen.Q.reshape(shape)
        out = ServoMotion(
            *(
                np.ascontiguousarray(q).ravel()
                for q in (
                    self.time[:-1, None] + dt,
                    theta,
                    wu,
                    alpha,
                    mo.x.reshape(theta.shape),
                    xp * wu,
                    xpp * bu + xp * alpha,
                    torque,
                )
            )
        )
        self._cache[refine] = out
        return out

    def check(self, refine: int = 10) -> dict[str, float]:
        """Largest relative excess of every given limit over ``motion(refine)`` (<= 0: respected); for v_cut
        the largest relative deviation of |v| from v_cut inside the cut window."""
        s, lim, out = self.motion(refine), self.limits, {}
        peaks = {"omega_max": s.omega, "alpha_max": s.alpha, "v_max": s.v, "a_max": s.a, "torque_max": s.torque}
        for name, q in peaks.items():
            if lim.get(name) is not None:
                out[name] = float(np.abs(q).max() / lim[name] - 1.0)
        if self.cut_cells is not None:
            lo, hi = self.cut_cells
            k = np.repeat(np.arange(self.alpha.size), refine + 1)
            inside = (k >= lo) & (k < hi)
            out["v_cut"] = float(np.abs(np.abs(s.v[inside]) / lim["v_cut"] - 1.0).max())
        return out


def in_metres(m: Mechanism) -> Mechanism:
    """The same mechanism with its lengths in metres (servo limits, forces and torques are SI)."""
    if getattr(m, "units", "m") == "m":
        return m
    k = to_metres(m.units)
    return type(m)(**{n: v if n in m.BRANCHES else v * k for n, v in m.params.items()}, units="m")


def _limit(name, value, *, required=False, zero_ok=False):
    """A servo limit: None (no limit) or a finite number > 0 (>= 0 with ``zero_ok``) in [1e-100, 1e100]."""
    if value is None:
        if required:
            raise InvalidParameter(f"{name} is required")
        return None
    v = number(name, value, limit=math.inf)
    if v < 0 or (v == 0 and not zero_ok):
        raise InvalidParameter(f"{name} must be {'>= 0' if zero_ok else 'positive'} and finite, got {v:g}")
    if v > MAGNITUDE or 0 < v < 1 / MAGNITUDE:
        raise InvalidParameter(
            f"{name} = {v:g} is out of range: limits lie in [1e-100, 1e100] (the program's variable is omega2^2 "
            "and its rows hold squares and products of the limits, which would overflow)"
        )
    return v


class _Grid(NamedTuple):
    theta: np.ndarray  # n + 1 nodes (rad)
    working_cells: int  # node index of the working stroke's second dead centre
    cut_cells: tuple | None  # node indices of the cut window's ends
    xp: np.ndarray  # dx/dtheta2 at the n nodes
    xpp: np.ndarray  # d2x/dtheta2^2 at the n nodes


def _grid(m: Mechanism, n: int, cut_fraction: float | None) -> _Grid:
    """Nodes splitting the turn at the dead centres and the cut window ends, about 2 pi / n apart."""
    start, length = m.working_arc()
    breaks = [start, start + length, start + 2 * math.pi]
    if cut_fraction is not None:
        x0, x1 = m.positions([start, start + length]).x
        f = np.array([(1 - cut_fraction) / 2, (1 + cut_fraction) / 2])
        breaks = [start, *m.working_angle_at(x0 + f * (x1 - x0)).tolist(), start + length, start + 2 * math.pi]
    lengths = np.diff(breaks)
    raw = n * lengths / (2 * math.pi)
    cells = np.maximum(2, np.floor(raw).astype(int))
    while cells.sum() < n:
        cells[np.argmax(raw - cells)] += 1
    while cells.sum() > n:
        cells[np.argmax(np.where(cells > 2, cells - raw, -np.inf))] -= 1
    pieces = [np.linspace(a, b, c, endpoint=False) for a, b, c in zip(breaks, breaks[1:], cells, strict=False)]
    theta = np.append(np.concatenate(pieces), breaks[-1])
    idx = np.concatenate([[0], np.cumsum(cells)])
    mo = m.motion(theta[:-1], 1.0, 0.0)
    cut = (int(idx[1]), int(idx[2])) if cut_fraction is not None else None
    return _Grid(theta, int(idx[-2]), cut, mo.v, mo.a)


def _generalised(m, theta, masses, loads, working):
    """M, M', Q of the crank's equation of motion at theta (crank turning counter-clockwise), SI, with the
    cutting force on the profile's working stroke (``working``: where theta is on it)."""
    import dataclasses

    from qropt.dynamics.inverse import generalised

    gravity = None if loads is None else dataclasses.replace(loads, cutting_force=0.0)
    gen = generalised(m, theta, masses=masses, loads=gravity, sense=1.0)
    if loads is not None:
        mo = m.motion(theta, 1.0, 0.0)
        gen = dataclasses.replace(gen, Q=gen.Q + loads.force_at(mo.x) * np.abs(mo.v) * working)
    return gen


def _groups(g: _Grid, lim: dict, force: float, inertia: float, gen=None):
    """Every limit as rows |G beta + c| <= 1 in beta = b / omega_max^2, and v_cut as rows G beta = 1; ``gen``
    (M, M', Q at the nodes) adds every link's inertia and the loads to the torque."""
    n = g.xp.size
    w2 = lim["omega_max"] ** 2
    h = np.diff(g.theta)
    eye = sp.eye(n, format="csr")
    nxt = sp.csr_matrix((np.ones(n), (np.arange(n), (np.arange(n) + 1) % n)), shape=(n, n))
    prev = nxt.T.tocsr()
    dalpha = sp.diags(w2 / (2 * h)) @ (nxt - eye)  # alpha2 on each cell (rad/s^2)
    zero = np.zeros(n)
    groups = [("omega_max", eye, zero)]
    if lim.get("alpha_max") is not None:
        groups.append(("alpha_max", dalpha / lim["alpha_max"], zero))
    if lim.get("v_max") is not None:
        groups.append(("v_max", sp.diags(g.xp**2 * w2 / lim["v_max"] ** 2), zero))
    if lim.get("a_max") is not None:
        base = sp.diags(g.xpp * w2)
        for side in (dalpha, prev @ dalpha):
            groups.append(("a_max", (base + sp.diags(g.xp) @ side) / lim["a_max"], zero))
    if lim.get("torque_max") is not None:
        work = np.arange(n) <= g.working_cells
        c = force * np.abs(g.xp) * work / lim["torque_max"]
        own = sp.csr_matrix((n, n))
        if gen is not None:  # M alpha2 + M' b / 2 + Q, linear in b
            c = c + gen.Q / lim["torque_max"]
            own = sp.diags(0.5 * gen.dM * w2)
        for side in (dalpha, prev @ dalpha):
            mass = sp.diags(inertia + (gen.M if gen is not None else 0.0) * np.ones(n))
            groups.append(("torque_max", (mass @ side + own) / lim["torque_max"], c))
    equal = None
    if g.cut_cells is not None:
        k = np.arange(g.cut_cells[0], g.cut_cells[1] + 1)
        equal = sp.csr_matrix((g.xp[k] ** 2 * w2 / lim["v_cut"] ** 2, (np.arange(k.size), k)), shape=(k.size, n))
    return groups, equal


def _solve(problem) -> str | None:
    """Solve with CLARABEL: the cvxpy status, or 'error: ...' if the solver raised."""
    import cvxpy as cp  # imported on use: it is slow to import

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # an inaccurate solution is reported as status 'acceptable'
            problem.solve(solver=cp.CLARABEL)
    except (cp.error.SolverError, ValueError, ArithmeticError) as exc:
        return f"error: {exc}"
    return problem.status


def _diagnose(groups, equal, n: int) -> tuple[tuple, str]:
    """Phase one: relax each limit by a relative slack, minimise their sum; the limits whose rows carry
    dual weight conflict, and the slacks say by how much relaxing them would do."""
    import cvxpy as cp  # imported on use: it is slow to import

    names = list(dict.fromkeys([name for name, _, _ in groups] + (["v_cut"] if equal is not None else [])))
    beta, s = cp.Variable(n, nonneg=True), cp.Variable(len(names), nonneg=True)
    cons, owner = [], []
    for name, G, c in groups:
        j = names.index(name)
        cons += [G @ beta + c <= 1 + s[j], G @ beta + c >= -1 - s[j]]
        owner += [name, name]
    if equal is not None:
        j = names.index("v_cut")
        cons += [equal @ beta <= 1 + s[j], equal @ beta >= 1 - s[j]]
        owner += ["v_cut", "v_cut"]
    problem = cp.Problem(cp.Minimize(cp.sum(s)), cons)
    status = _solve(problem)
    if status not in (cp.OPTIMAL, cp.OPTIMAL_INACCURATE):
        return (), f"the limits cannot all hold (naming them failed: {status})"
    weight = dict.fromkeys(names, 0.0)
    for name, con in zip(owner, cons, strict=True):
        weight[name] += float(np.abs(con.dual_value).sum())
    top = max(weight.values()) or 1.0
    binding = tuple(name for name in names if weight[name] > BINDING_TOL * top)
    change = []
    for j, name in enumerate(names):
        sj = float(s.value[j])
        if sj > BINDING_TOL and name != "v_cut":
            factor = math.sqrt(1 + sj) if name in SQUARED else 1 + sj
            change.append(f"{name} +{100 * (factor - 1):.3g}%")
    if equal is not None and "v_cut" in binding:
        off = np.abs(np.sqrt(np.maximum(equal @ beta.value, 0.0)) - 1).max()
        if off > BINDING_TOL:
            change.append(f"a cutting speed up to {100 * off:.3g}% off v_cut")
    how = f"; the smallest relaxation found: {', '.join(change)}" if change else ""
    return binding, f"the limits {', '.join(binding)} cannot all hold{how}"


def speed_profile(
    mechanism: Mechanism,
    *,
    omega_max: float,
    alpha_max: float | None = None,
    v_max: float | None = None,
    a_max: float | None = None,
    v_cut: float | None = None,
    cut_fraction: float = 0.8,
    force: float | None = None,
    inertia: float | None = None,
    torque_max: float | None = None,
    objective: str = "min_cycle_time",
    n: int = 720,
    masses=None,
    loads=None,
) -> SpeedProfile:
    """The fastest periodic crank-speed profile (crank turning counter-clockwise) within the limits.

    omega_max (rad/s) bounds omega2, alpha_max (rad/s^2) |alpha2|, v_max and a_max the slider's |v| and |a|
    over the turn; with v_cut the slider moves at exactly |v| = v_cut over the central ``cut_fraction`` of
    the working stroke's travel (the working stroke is ``mechanism.working_arc()``); torque_max bounds
    |inertia alpha2 + force |dx/dtheta2||, the force acting on the working stroke only. objective:
    'min_cycle_time', or 'min_return_time' (then the shortest cycle among the fastest returns).
    masses, loads (``qropt.Masses``, ``qropt.Loads``): the torque with every link's inertia,
    ``M(theta2) alpha2 + M'(theta2) omega2^2 / 2 + Q(theta2)`` (still linear in b = omega2^2); force= and
    inertia= are shorthands for a constant cutting force and a constant inertia on the crank, refused beside a
    cutting force in loads or a mass model (never counted twice); friction, which makes the load depend on b,
    stays out of the convex problem. Invalid input raises InvalidParameter; an infeasible set of limits
    returns status 'infeasible'.
    """
    import cvxpy as cp  # imported on use: it is slow to import

    if not isinstance(mechanism, Mechanism):
        raise InvalidParameter(f"speed_profile needs a qropt mechanism, got {mechanism!r}")
    if mechanism.OUTPUT != "slider":
        raise InvalidParameter(
            f"speed_profile needs a slider output: {type(mechanism).__name__}'s output is the follower angle "
            "theta4 (rad), to which the slider limits (v_max, a_max, v_cut in length/s) and the cutting-force "
            "torque do not apply; give the slider type it drives (crank-rocker-slider, drag-link-slider)"
        )
    mechanism = in_metres(mechanism)
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or not MIN_CELLS <= n <= MAX_CELLS:
        raise InvalidParameter(f"n (cells per turn) must be an integer in {MIN_CELLS}..{MAX_CELLS}, got {n!r}")
    if objective not in OBJECTIVES:
        raise InvalidParameter(f"objective must be one of {OBJECTIVES}, got {objective!r}")
    lim = {
        "omega_max": _limit("omega_max", omega_max, required=True),
        "alpha_max": _limit("alpha_max", alpha_max),
        "v_max": _limit("v_max", v_max),
        "a_max": _limit("a_max", a_max),
        "v_cut": _limit("v_cut", v_cut),
        "torque_max": _limit("torque_max", torque_max),
    }
    force, inertia = _limit("force", force, zero_ok=True) or 0.0, _limit("inertia", inertia, zero_ok=True) or 0.0
    gen = _check_dynamics(mechanism, masses, loads, force, inertia)
    if lim["torque_max"] is not None and force == 0.0 and inertia == 0.0 and gen is None:
        raise InvalidParameter(
            "torque_max needs a force or an inertia, or masses and loads (the torque is inertia alpha2 + force x')"
        )
    if lim["v_cut"] is not None and lim["v_max"] is not None and lim["v_cut"] > lim["v_max"]:
        raise InvalidParameter(f"v_cut = {lim['v_cut']:g} is above v_max = {lim['v_max']:g}")
    fraction = None
    if lim["v_cut"] is not None:
        fraction = _limit("cut_fraction", cut_fraction)
        if not fraction < 1.0:
            raise InvalidParameter(
                f"cut_fraction must be in (0, 1) (the slider stops at the dead centres), got {fraction:g}"
            )
    g = _grid(mechanism, int(n), fraction)
    on_working = np.arange(g.xp.size) <= g.working_cells  # as the force= shorthand: the nodes of the working stroke
    gen = None if gen is None else _generalised(mechanism, g.theta[:-1], masses, loads, on_working)
    groups, equal = _groups(g, lim, force, inertia, gen)
    base = dict(
        mechanism=mechanism, limits=lim, objective=objective, force=force, inertia=inertia, masses=masses, loads=loads
    )

    nc = g.xp.size
    h = np.diff(g.theta)
    top = _envelope(g, lim)
    if _meets(top, groups, equal):  # the pointwise fastest speeds meet every other limit: the optimum
        message = (
            f"{objective}: the speed limits' envelope omega2 = min(omega_max, v_max / |dx/dtheta2|) meets "
            f"every other limit, so it is the optimum ({nc} cells, no solver needed)"
        )
        return _profile("optimal", message, top, g, lim, base)
    beta = cp.Variable(nc, nonneg=True)
    G = sp.vstack([G for _, G, _ in groups], format="csr")
    c = np.concatenate([c for _, _, c in groups])
    cons = [G @ beta + c <= 1, G @ beta + c >= -1] + ([equal @ beta == 1] if equal is not None else [])
    root = cp.sqrt(beta)
    cell = cp.multiply(2 * h / lim["omega_max"], cp.inv_pos(root + root[(np.arange(nc) + 1) % nc]))
    total = cp.sum(cell)
    first = cp.sum(cell[g.working_cells :]) if objective == "min_return_time" else total
    problem = cp.Problem(cp.Minimize(first), cons)
    status = _solve(problem)
    if status in (cp.OPTIMAL, cp.OPTIMAL_INACCURATE) and objective == "min_return_time":
        bound = first.value * (1 + 1e-6)
        problem = cp.Problem(cp.Minimize(total), [*cons, cp.sum(cell[g.working_cells :]) <= bound])
        status = _solve(problem)
    if status in (cp.INFEASIBLE, cp.INFEASIBLE_INACCURATE):
        binding, message = _diagnose(groups, equal, nc)
        return SpeedProfile("infeasible", message, binding=binding, **base)
    if status not in (cp.OPTIMAL, cp.OPTIMAL_INACCURATE) or beta.value is None:
        why = _scaling(groups, top, lim)
        return SpeedProfile("failed", f"the conic solver did not solve the problem ({status})" + why, **base)
    word = "optimal" if status == cp.OPTIMAL else "acceptable"
    message = f"{objective} solved by CLARABEL with {nc} cells" + ("" if word == "optimal" else " (reduced accuracy)")
    return _profile(word, message, np.maximum(beta.value, 0.0), g, lim, base)


def _check_dynamics(m, masses, loads, force, inertia):
    """True where masses or loads are given (after checking them), None otherwise."""
    from qropt.dynamics.model import Loads, Masses

    if masses is None and loads is None:
        return None
    if masses is not None and not isinstance(masses, Masses):
        raise InvalidParameter(f"masses is a qropt.Masses, got {type(masses).__name__}")
    if loads is not None and not isinstance(loads, Loads):
        raise InvalidParameter(f"loads is a qropt.Loads, got {type(loads).__name__}")
    if loads is not None and loads.friction:
        raise InvalidParameter("friction makes the load depend on omega2^2: it stays out of the convex problem")
    if loads is not None and loads.pin_friction is not None:
        raise UnsupportedLoad(
            "the servo's convex problem (speed_profile) cannot apply pin friction: its moments depend on the joint "
            "forces, so the torque is not linear in omega2^2; inverse_dynamics applies it"
        )
    if force and loads is not None and (isinstance(loads.cutting_force, tuple) or loads.cutting_force):
        raise InvalidParameter("give the cutting force once: force= or loads=Loads(cutting_force=...), not both")
    if inertia and masses is not None:
        raise InvalidParameter("give the inertia once: inertia= (reduced to the crank) or masses=, not both")
    return True


def _profile(word, message, beta, g: _Grid, lim, base) -> SpeedProfile:
    """The SpeedProfile of beta = b / omega_max^2 at the n nodes (b linear on each cell)."""
    h = np.diff(g.theta)
    b = beta * lim["omega_max"] ** 2
    b = np.append(b, b[0])
    omega = np.sqrt(b)
    with np.errstate(divide="ignore"):
        time = np.concatenate([[0.0], np.cumsum(2 * h / (omega[:-1] + omega[1:]))])
    alpha = np.diff(b) / (2 * h)
    return SpeedProfile(
        word,
        message,
        theta=g.theta,
        omega=omega,
        alpha=alpha,
        time=time,
        working_cells=g.working_cells,
        cut_cells=g.cut_cells,
        **base,
    )


def _envelope(g: _Grid, lim) -> np.ndarray:
    """The largest beta = b / omega_max^2 each node allows under omega_max and v_max alone (every feasible
    profile lies below it, and each cell's time falls as b grows)."""
    top = np.ones(g.xp.size)
    if lim.get("v_max") is not None:
        with np.errstate(divide="ignore", over="ignore"):
            top = np.minimum(top, (lim["v_max"] / (np.abs(g.xp) * lim["omega_max"])) ** 2)
    return top


def _meets(beta, groups, equal, tol: float = 1e-12) -> bool:
    """Whether beta meets every limit's rows |G beta + c| <= 1 (and the cutting-speed rows, = 1)."""
    if equal is not None and not np.all(np.abs(equal @ beta - 1.0) <= tol):
        return False
    return all(np.all(np.abs(G @ beta + c) <= 1.0 + tol) for _, G, c in groups)


def _scaling(groups, top, lim) -> str:
    """Why a solver may fail on these limits: rows whose coefficients are extreme, or speeds spanning many
    orders of magnitude ('' if neither)."""
    notes = []
    for name in dict.fromkeys(name for name, _, _ in groups):
        big = max(float(np.abs(sp.csr_matrix(G).data).max(initial=0.0)) for nm, G, _ in groups if nm == name)
        if big > BADLY_SCALED and name != "omega_max":
            what = "changes of omega2^2 per cell" if name == "alpha_max" else "omega2^2 where it binds"
            notes.append(f"{name} = {lim[name]:g} bounds {what} by {1 / big:.2g} omega_max^2")
    if top.min() < 1 / BADLY_SCALED:
        notes.append(f"the speed limits allow omega2 down to {math.sqrt(top.min()):.2g} omega_max")
    if not notes:
        return ""
    return "; the program is badly scaled (" + "; ".join(notes) + "): relax the tiny limits or scale the units"


__all__ = ["speed_profile", "SpeedProfile", "ServoMotion", "ConstantSpeed", "OBJECTIVES"]
