"""Tolerance allocation: exact sensitivities of the time ratio, stroke, gamma_min and peak slider
acceleration to a mechanism's lengths and offsets, the largest tolerances that keep them within limits
(a convex program solved with cvxpy), and an exact Monte Carlo check of the allocation.

Sensitivities come from CasADi AD of the type's own ``loop``: a dead centre solves x'(theta*; p) = 0,
so d theta*/dp = -(dx'/dp) / x'' (implicit function theorem); the stroke, gamma_min and the peak
acceleration are values at stationary points, so their derivatives are partial derivatives at the fixed
crank angle (envelope theorem). Tolerances are symmetric, +/- t_i in the parameter's unit; gamma_min
is in rad, the peak acceleration in length/s^2 at the given omega2.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field

import casadi
import numpy as np
from tqdm import tqdm

from qropt.errors import DegenerateMechanism, InvalidParameter, QroptError
from qropt.kinematics.closures import RIGHT_ANGLE, transmission_angle
from qropt.kinematics.ops import CASADI, JET, NUMPY, Jet
from qropt.mechanisms import Mechanism

QUANTITIES = ("time_ratio", "stroke", "gamma_min", "peak_acceleration")
METHODS = ("worst-case", "rss")
OFFSETS = ("e", "h")
NEWTON_STEPS = 8  # from the nominal extremes, perturbed by tolerances: quadratic convergence to rounding
STEP_TOL = 1e-11  # rad: a last Newton step above this sends the sample to the per-mechanism analysis
FD_STEP = 1e-3  # rad: central-difference step for the third and fourth derivative of x (peak acceleration)
CHECK_GRID = 180  # crank angles on which every refined sample is checked to hold the global extremes
ACCEL_CHECK = 0.02  # the refined peak |x''| must reach the grid's second differences (error O(h^2)) within this
CHUNK = 2000  # samples analysed at once (bounded memory)
MAX_SAMPLES = 10_000_000
ROUNDING = 1e-12  # a sensitivity below this fraction of its row's largest is rounding: zero
TIE = 1e-9  # rad: transmission minima this close to gamma_min share it (gamma_min has a kink there)
_SYMBOLIC: dict = {}


class _Symbolic:
    """CasADi functions of (theta2, all parameters) from ``cls.loop``, built once per (type, names)."""

    def __init__(self, cls, names):
        t, P = casadi.SX.sym("t"), casadi.SX.sym("p", len(names))
        lp = cls.loop(CASADI, t, {k: P[i] for i, k in enumerate(names)})
        d = [casadi.SX(lp.x) + 0 * t]
        for _ in range(2):
            d.append(casadi.jacobian(d[-1], t))
        self.x = casadi.Function("x", [t, P], [*d[:3], *(casadi.jacobian(q, P) for q in d[:3])])
        self.gamma = {}
        for joint, lines in lp.transmission.items():
            if lines is not RIGHT_ANGLE:
                g = transmission_angle(CASADI, lines)
                self.gamma[joint] = casadi.Function(f"gamma_{joint}", [t, P], [g, casadi.jacobian(g, P)])


def _symbolic(cls, names) -> _Symbolic:
    key = (cls, tuple(names))
    if key not in _SYMBOLIC:
        _SYMBOLIC[key] = _Symbolic(cls, names)
    return _SYMBOLIC[key]


def _names(m: Mechanism, params) -> list[str]:
    if not isinstance(m, Mechanism):
        raise InvalidParameter(f"expected a qropt mechanism, got {m!r}")
    if params is None:
        return [k for k in (*type(m).LENGTHS, *OFFSETS) if k in m.params]
    names = [params] if isinstance(params, str) else list(params)
    allowed = [k for k in m.params if not k.startswith("sigma")]
    for k in names:
        if k not in allowed:
            why = "branch signs have no tolerance" if str(k).startswith("sigma") else "unknown parameter"
            raise InvalidParameter(f"{k!r}: {why}; {type(m).__name__} takes tolerances on {allowed}")
    if not names or len(set(names)) != len(names):
        raise InvalidParameter(f"params must name distinct parameters of {allowed}, got {names}")
    return names


def _quantities(qs, omega2) -> list[str]:
    for q in qs:
        if q not in QUANTITIES:
            raise InvalidParameter(f"unknown quantity {q!r}; tolerances limit {list(QUANTITIES)}")
    if "peak_acceleration" in qs and omega2 is None:
        raise InvalidParameter("a peak_acceleration limit needs omega2 (rad/s)")
    return list(qs)


def _rows(m: Mechanism, names, quantities, omega2) -> np.ndarray:
    """The sensitivity matrix dQ/dp (len(quantities), len(names)), exact."""
    all_names = list(m.params)
    sym = _symbolic(type(m), all_names)
    p = np.array([m.params[k] for k in all_names])
    cols = [all_names.index(k) for k in names]
    out = np.zeros((len(quantities), len(names)))
    for i, q in enumerate(quantities):
        if q in ("time_ratio", "stroke"):
            d = m.dead_centres()
            (x_max, _, a_max, dx_max, dv_max, _), (x_min, _, a_min, dx_min, dv_min, _) = (
                [np.asarray(v, float).ravel() for v in sym.x(th, p)] for th in (d.theta_max, d.theta_min)
            )
            if q == "stroke":
                row = dx_max - dx_min
            else:
                if a_max[0] == 0.0 or a_min[0] == 0.0:
                    raise DegenerateMechanism(f"{m!r}: a dead centre has x'' = 0; its time ratio is not smooth")
                s, r = m.stroke_angles()
                dtr_ds = 2 * math.pi / r**2 if s >= r else -2 * math.pi / s**2
                row = dtr_ds * (-dv_min / a_min[0] + dv_max / a_max[0])
        elif q == "gamma_min":
            least = m.gamma_min().value
            tied = [(j, th) for j, th, v in _gamma_minima(m) if v <= least + TIE]
            grads = [np.asarray(sym.gamma[j](th, p)[1], float).ravel() for j, th in tied] or [np.zeros(len(p))]
            grads = np.array(grads)
            row = grads[np.argmax(np.abs(grads), axis=0), np.arange(grads.shape[1])]
        else:
            th = m.peak_acceleration(omega2).theta2
            a2, dx2 = (np.asarray(v, float).ravel() for v in sym.x(th, p)[2::3])
            row = math.copysign(omega2 * omega2, a2[0]) * dx2
        out[i] = row[cols]
    out[np.abs(out) <= ROUNDING * np.abs(out).max(axis=1, keepdims=True)] = 0.0
    return out


def _omega2(omega2):
    if omega2 is None:
        return None
    if isinstance(omega2, bool) or not isinstance(omega2, (int, float)) or not math.isfinite(omega2) or omega2 == 0:
        raise InvalidParameter(f"omega2 must be a nonzero finite number (rad/s), got {omega2!r}")
    return float(omega2)


def sensitivities(mechanism: Mechanism, params=None, *, omega2: float | None = None) -> dict[str, dict[str, float]]:
    """Exact dQ/dp of time_ratio, stroke, gamma_min (rad) and, with omega2 (rad/s), the peak slider
    acceleration over the turn, for each parameter in ``params`` (default: the lengths and offsets).

    Where gamma_min is shared by several minima (a symmetric mechanism) it has a kink; the value given is
    then, per parameter, the one-sided slope of largest magnitude (a safe bound for a stack-up)."""
    names, omega2 = _names(mechanism, params), _omega2(omega2)
    qs = [q for q in QUANTITIES if q != "peak_acceleration" or omega2 is not None]
    rows = _rows(mechanism, names, qs, omega2)
    return {q: dict(zip(names, map(float, r), strict=True)) for q, r in zip(qs, rows, strict=True)}


@dataclass(frozen=True, repr=False)
class MonteCarlo:
    """Exact re-analysis of n random mechanisms: per limited quantity the fraction within its limit, the
    worst |deviation| and the largest linearisation error |dQ - S dp|; ``all_within`` meets every limit;
    ``failed`` samples could not be analysed (counted outside); ``deviations`` holds every dQ and ``errors``
    every sampled parameter error (parameters with an infinite tolerance are held at their nominal)."""

    n: int
    within: dict
    worst: dict
    linearisation: dict
    all_within: float
    failed: int
    deviations: dict = field(default_factory=dict)
    errors: dict = field(default_factory=dict)

    def __repr__(self):
        parts = ", ".join(f"{q}: {100 * f:.2f}% (worst {self.worst[q]:.4g})" for q, f in self.within.items())
        return f"MonteCarlo(n={self.n}, {parts}, all {100 * self.all_within:.2f}%, failed {self.failed})"


@dataclass(frozen=True, repr=False)
class Allocation:
    """Tolerances ``{param: t}`` (+/- t, the parameter's unit; inf where no limited quantity depends on it),
    status 'optimal' / 'infeasible' / 'failed' with a message, the sensitivities used and, per limit,
    ``usage``: the stack-up (worst-case sum or k times the rss) over the limit."""

    status: str
    message: str
    mechanism: Mechanism
    limits: dict
    method: str
    k: float
    tolerances: dict
    sensitivities: dict
    usage: dict
    omega2: float | None = None

    def __repr__(self):
        t = ", ".join(f"{p}=+/-{v:.4g}" for p, v in self.tolerances.items())
        return f"Allocation(status={self.status!r}, {self.method}, {t})"

    def monte_carlo(self, n: int = 10_000, seed: int = 0, progress: bool | None = None) -> MonteCarlo:
        """Re-analyse n mechanisms with errors uniform in +/- t (worst-case) or normal, sigma = t / k (rss).

        Every sample's dead centres and transmission minima are refined from the nominal's by Newton steps
        with exact (jet) derivatives, its acceleration extremes by Newton on central differences of the
        exact x'' (the value, at a stationary point, exact to rounding); each must beat a 180-point grid
        (the acceleration within 2%, by second differences), else the sample is analysed on its own
        through the mechanism API. The numbers are the exact analysis (to ~1e-12), not a linear estimate.
        progress: a bar on standard error (None: only when it is a terminal)."""
        if self.status != "optimal":
            raise InvalidParameter(f"no tolerances to check: status {self.status!r} ({self.message})")
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or not 1 <= n <= MAX_SAMPLES:
            raise InvalidParameter(f"n must be an integer in 1..{MAX_SAMPLES}, got {n!r}")
        return _monte_carlo(self, int(n), seed, progress)


def _bounds(bounds, names):
    """{param: (low, high)} (None: 0 or no bound) -> arrays low, high."""
    lo, hi = np.zeros(len(names)), np.full(len(names), np.inf)
    for k, v in (bounds or {}).items():
        if k not in names:
            raise InvalidParameter(f"bounds: {k!r} is not among the toleranced parameters {names}")
        try:
            a, b = v
            a, b = 0.0 if a is None else float(a), math.inf if b is None else float(b)
        except (TypeError, ValueError):
            raise InvalidParameter(f"bounds[{k!r}] must be (low, high), got {v!r}") from None
        if not 0 <= a <= b or a == math.inf:
            raise InvalidParameter(f"bounds[{k!r}] = {v!r} must satisfy 0 <= low <= high, low finite")
        lo[names.index(k)], hi[names.index(k)] = a, b
    return lo, hi


def allocate(mechanism: Mechanism, limits: dict, *, params=None, method: str = "worst-case", k: float = 3.0,
             weights=None, bounds=None, omega2: float | None = None) -> Allocation:  # fmt: skip
    """The tolerances t maximising sum w_i log t_i with, for each limited quantity Q (limit E):
    sum_i |dQ/dp_i| t_i <= E ('worst-case') or ||dQ/dp * t||_2 <= E / k ('rss').

    limits: {quantity: E > 0} over time_ratio, stroke (length), gamma_min (rad), peak_acceleration
    (length/s^2, needs omega2); params: the toleranced names (default: lengths and offsets); weights:
    {param: w > 0} (default 1); bounds: {param: (low, high)} on t."""
    import cvxpy as cp  # imported on use: it takes a fraction of a second to import

    names, omega2 = _names(mechanism, params), _omega2(omega2)
    if method not in METHODS:
        raise InvalidParameter(f"method must be one of {METHODS}, got {method!r}")
    if not isinstance(limits, dict) or not limits:
        raise InvalidParameter("limits must be a non-empty {quantity: allowed deviation} mapping")
    qs = _quantities(list(limits), omega2)
    E = np.array([_positive(f"limit {q}", limits[q]) for q in qs])
    k = _positive("k", k)
    w = np.ones(len(names))
    for name, v in (weights or {}).items():
        if name not in names:
            raise InvalidParameter(f"weights: {name!r} is not among the toleranced parameters {names}")
        w[names.index(name)] = _positive(f"weight of {name}", v)
    lo, hi = _bounds(bounds, names)
    S = _rows(mechanism, names, qs, omega2)
    base = dict(mechanism=mechanism, limits=dict(zip(qs, E.tolist(), strict=True)), method=method, k=k,
                sensitivities={q: dict(zip(names, r.tolist(), strict=True)) for q, r in zip(qs, S, strict=True)},
                omega2=omega2)  # fmt: skip
    A = np.abs(S) / E[:, None] * (1.0 if method == "worst-case" else k)  # each limit: ||A_j t|| <= 1
    over = [q for q, a in zip(qs, A, strict=True) if _stack(a, lo, method) > 1.0]
    if over:
        return Allocation("infeasible", f"infeasible: the lower bounds alone exceed the limits on {', '.join(over)}",
                          tolerances={}, usage={}, **base)  # fmt: skip
    scale = A.max(axis=0)
    live = scale > 0.0  # rounding-level sensitivities are exact zeros (see _rows)
    t = np.where(live, 0.0, hi)
    accuracy = ""
    if live.any():
        c = scale[live]  # u = c t: each live tolerance in units of its tightest single-limit share
        u, status = _convex(A[:, live] / c, w[live], lo[live] * c, hi[live] * c, method)
        if u is None:
            word = "infeasible" if status in (cp.INFEASIBLE, cp.INFEASIBLE_INACCURATE) else "failed"
            return Allocation(word, f"the conic solver reports {status}", tolerances={}, usage={}, **base)
        t[live] = np.clip(u / c, lo[live], hi[live])
        accuracy = "" if status == "polished" else f" ({status}: not refined to rounding)"
    tol = dict(zip(names, t.tolist(), strict=True))
    usage = {q: _stack(a, t, method) for q, a in zip(qs, A, strict=True)}
    free = [p for p, lv in zip(names, live, strict=True) if not lv]
    msg = f"{method} allocation of {len(names)} tolerances for {', '.join(qs)}{accuracy}"
    if free:
        msg += f"; no limited quantity depends on {', '.join(free)} (tolerance = its upper bound, or inf)"
    return Allocation("optimal", msg, tolerances=tol, usage=usage, **base)


def _convex(a, w, lo, hi, method):
    """maximise w . log u s.t. each row's stack-up of a u <= 1, lo <= u <= hi, with cvxpy (CLARABEL), then
    polished on the KKT equations of the active set. Returns (u or None, 'polished' or the cvxpy status)."""
    import cvxpy as cp  # imported on use: it takes a fraction of a second to import

    u = cp.Variable(w.size, pos=True)
    cons = [(r @ u if method == "worst-case" else cp.norm(cp.multiply(r, u))) <= 1 for r in a] + [u >= lo]
    if np.isfinite(hi).any():
        cons.append(u[np.flatnonzero(np.isfinite(hi))] <= hi[np.isfinite(hi)])
    problem = cp.Problem(cp.Maximize(w @ cp.log(u)), cons)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            problem.solve(solver=cp.CLARABEL)
    except (cp.error.SolverError, ValueError, ArithmeticError) as exc:
        return None, f"an error ({exc})"
    if problem.status not in (cp.OPTIMAL, cp.OPTIMAL_INACCURATE) or u.value is None:
        return None, problem.status
    polished = _polish(a, np.maximum(u.value, 1e-300), w, lo, hi, method)
    return (polished, "polished") if polished is not None else (u.value, problem.status)


def _polish(a, u, w, lo, hi, method):
    """Newton on the KKT equations w_i / u_i = sum_j lam_j dg_j/du_i (u_i not at a bound), g_j(u) = 1 (active
    limits; g = a u, or (a u)^2 summed for rss) from the solver's point: the optimum to rounding, or None if
    the active set guessed from the solver's point does not verify (multipliers >= 0, all limits held)."""
    quad = method != "worst-case"

    def g(u):
        return (a * u) ** 2 @ np.ones(u.size) if quad else a @ u

    act = np.flatnonzero(g(u) >= 1 - 1e-5)
    free = ~((u <= lo * (1 + 1e-6)) | (u >= hi * (1 - 1e-6)))
    u = np.where(free, u, np.where(u <= lo * (1 + 1e-6), lo, hi))
    f, m = np.flatnonzero(free), act.size
    if not f.size or not m:
        return None
    grad = (2 * a[act] ** 2 * u) if quad else a[act]
    lam = np.linalg.lstsq(grad[:, f].T, w[f] / u[f], rcond=None)[0]
    for _ in range(30):
        grad = (2 * a[act] ** 2 * u) if quad else a[act]
        F = np.concatenate([w[f] / u[f] - lam @ grad[:, f], g(u)[act] - 1])
        if np.abs(F).max() < 1e-13 * max(1.0, np.abs(w).max()):
            break
        J = np.zeros((f.size + m, f.size + m))
        J[: f.size, : f.size] = np.diag(-w[f] / u[f] ** 2 - (2 * (lam @ a[act] ** 2)[f] if quad else 0.0))
        J[: f.size, f.size :] = -grad[:, f].T
        J[f.size :, : f.size] = grad[:, f]
        try:
            step = np.linalg.solve(J, -F)
        except np.linalg.LinAlgError:
            return None
        u[f] += step[: f.size]
        lam = lam + step[f.size :]
        if not np.all(u[f] > 0):
            return None
    ok = np.abs(F).max() < 1e-10 and np.all(lam >= -1e-12) and np.all(g(u) <= 1 + 1e-12)
    return u if ok and np.all(u >= lo * (1 - 1e-12)) and np.all(u <= hi * (1 + 1e-12)) else None


def _stack(a, t, method) -> float:
    t = np.where(a > 0, t, 0.0)
    return float(a @ t if method == "worst-case" else np.sqrt(((a * t) ** 2).sum()))


def _positive(name, v) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)):
        raise InvalidParameter(f"{name} must be a number, got {v!r}")
    v = float(v)
    if not (math.isfinite(v) and v > 0):
        raise InvalidParameter(f"{name} must be positive and finite, got {v:g}")
    return v


# ---- Monte Carlo --------------------------------------------------------------------------------------
def _transmission(joint):
    """The transmission angle of ``joint`` as a function of a JET loop."""
    return lambda lp: transmission_angle(JET, lp.transmission[joint])


def _newton(cls, P, theta, quantity, names):
    """Refine stationary points of quantity(Loop) (JET) from theta, every sample at once (columns of P)."""
    th = theta.copy()
    step = np.full(th.shape, np.inf)
    params = {k: Jet.of(P[i], 0.0, 0.0) for i, k in enumerate(names)}  # jets: numpy arrays would not defer
    for _ in range(NEWTON_STEPS):
        q = quantity(cls.loop(JET, Jet.seed(th), params))
        with np.errstate(invalid="ignore", divide="ignore"):
            step = q.d1 / q.d2
        th = th - step
        if np.nanmax(np.abs(step), initial=0.0) < 1e-14:
            break
    q = quantity(cls.loop(JET, Jet.seed(th), params))
    return th, np.asarray(q.v, float), np.abs(step) <= STEP_TOL


def _accel_peak(cls, P, theta, names):
    """Extremes of x'' from theta: Newton on central differences (step FD_STEP) of the exact x'' (JET).
    The crank angle is found to ~1e-7 rad; the value, at a stationary point, to rounding."""
    params3 = {k: Jet.of(np.tile(P[i], 3), 0.0, 0.0) for i, k in enumerate(names)}
    params = {k: Jet.of(P[i], 0.0, 0.0) for i, k in enumerate(names)}
    th = theta.copy()
    h = FD_STEP
    for _ in range(NEWTON_STEPS):
        x2 = cls.loop(JET, Jet.seed(np.concatenate([th - h, th, th + h])), params3).x.d2.reshape(3, -1)
        with np.errstate(invalid="ignore", divide="ignore"):
            step = (x2[2] - x2[0]) * h / (2 * (x2[2] - 2 * x2[1] + x2[0]))
        th = th - step
        if np.nanmax(np.abs(step), initial=0.0) < 1e-9:
            break
    a2 = cls.loop(JET, Jet.seed(th), params).x.d2
    return np.asarray(a2, float), np.abs(step) <= 1e-6


def _analyse(m: Mechanism, P: np.ndarray, qs, omega2, plan) -> np.ndarray:
    """Exact quantities (len(qs), N) of the mechanisms with parameter columns P (all of m's parameters)."""
    cls, names = type(m), list(m.params)
    N = P.shape[1]
    ok = np.ones(N, bool)
    out = np.full((len(qs), N), np.nan)
    xs = {}
    for key, th0 in (("max", plan["max"]), ("min", plan["min"])):
        th, v, conv = _newton(cls, P, np.full(N, th0), lambda lp: lp.x, names)
        xs[key] = (th, v)
        ok &= conv
    grid = 2 * np.pi * np.arange(CHECK_GRID)[:, None] / CHECK_GRID
    with np.errstate(invalid="ignore", divide="ignore"):
        lp = cls.loop(NUMPY, grid, {k: P[i][None, :] for i, k in enumerate(names)})
    xg = np.broadcast_to(lp.x, (CHECK_GRID, N))
    slack = 1e-12 * (np.abs(xg).max(axis=0) + 1.0)
    ok &= (xs["max"][1] >= xg.max(axis=0) - slack) & (xs["min"][1] <= xg.min(axis=0) + slack)
    for _, margin in lp.margins:
        ok &= np.all(np.broadcast_to(margin, (CHECK_GRID, N)) >= -1e-12, axis=0)
    for i, q in enumerate(qs):
        if q == "stroke":
            out[i] = xs["max"][1] - xs["min"][1]
        elif q == "time_ratio":
            s = np.mod(xs["min"][0] - xs["max"][0], 2 * np.pi)
            out[i] = np.maximum(s, 2 * np.pi - s) / np.minimum(s, 2 * np.pi - s)
        elif q == "gamma_min":
            best, on_grid = np.full(N, np.pi / 2), np.full(N, np.pi / 2)
            for joint, ths in plan["gamma"].items():
                g = transmission_angle(NUMPY, lp.transmission[joint])
                on_grid = np.minimum(on_grid, np.broadcast_to(g, (CHECK_GRID, N)).min(axis=0))
                for th0 in ths:
                    _, v, conv = _newton(cls, P, np.full(N, th0), _transmission(joint), names)
                    ok &= conv
                    best = np.minimum(best, v)
            ok &= best <= on_grid + 1e-12
            out[i] = best
        else:
            peak = np.zeros(N)
            for th0 in plan["accel"]:
                a2, conv = _accel_peak(cls, P, np.full(N, th0), names)
                ok &= conv
                peak = np.maximum(peak, np.abs(a2))
            x2 = (np.roll(xg, 1, axis=0) - 2 * xg + np.roll(xg, -1, axis=0)) / (2 * np.pi / CHECK_GRID) ** 2
            ok &= peak >= np.abs(x2).max(axis=0) * (1 - ACCEL_CHECK)
            out[i] = peak * omega2 * omega2
    for j in np.flatnonzero(~ok):  # one at a time through the public API
        out[:, j] = _one(cls, dict(zip(names, P[:, j].tolist(), strict=True)), qs, omega2)
    return out


def _one(cls, params, qs, omega2) -> np.ndarray:
    try:
        m = cls(**params)
        vals = {"time_ratio": m.time_ratio, "stroke": m.stroke, "gamma_min": lambda: m.gamma_min().value,
                "peak_acceleration": lambda: m.peak_acceleration(omega2).value}  # fmt: skip
        return np.array([vals[q]() for q in qs])
    except QroptError:
        return np.full(len(qs), np.nan)


def _gamma_minima(m: Mechanism) -> list[tuple[str, float, float]]:
    """Every local minimum (joint, theta2, value) of every varying joint's transmission angle, exact."""
    grid = 2 * np.pi * np.arange(720) / 720
    lines = m.evaluate(NUMPY, grid).transmission
    p = np.array(list(m.params.values()))[:, None]
    out = []
    for joint, g in m.transmission_angles(grid).items():
        if lines[joint] is RIGHT_ANGLE:
            continue
        for th0 in grid[(g <= np.roll(g, 1)) & (g < np.roll(g, -1))]:
            th, v, _ = _newton(type(m), p, np.array([th0]), _transmission(joint), list(m.params))
            out.append((joint, float(th[0] % (2 * np.pi)), float(v[0])))
    return out


def _plan(m: Mechanism, qs, omega2) -> dict:
    """The nominal's stationary points every sample is refined from."""
    d = m.dead_centres()
    plan = {"max": d.theta_max, "min": d.theta_min, "gamma": {}, "accel": []}
    if "gamma_min" in qs:
        for joint, th, _ in _gamma_minima(m):
            plan["gamma"].setdefault(joint, []).append(th)
    if "peak_acceleration" in qs:
        ex = m.acceleration_extremes()
        plan["accel"] = [*ex.maxima[0].tolist(), *ex.minima[0].tolist()]
    return plan


def _monte_carlo(al: Allocation, n: int, seed, progress) -> MonteCarlo:
    m, qs = al.mechanism, list(al.limits)
    names = list(m.params)
    tol = {p: t for p, t in al.tolerances.items() if math.isfinite(t)}
    rng = np.random.default_rng(seed)
    nominal = np.array([m.params[k] for k in names])
    q0 = _one(type(m), dict(m.params), qs, al.omega2)
    S = np.array([[al.sensitivities[q].get(p, 0.0) for p in tol] for q in qs])
    plan = _plan(m, qs, al.omega2)
    dev = np.empty((len(qs), n))
    err = np.empty((len(tol), n))
    lin = np.empty((len(qs), n))
    bar = tqdm(total=n, desc="monte carlo", unit="mech", disable=None if progress is None else not progress)
    for start in range(0, n, CHUNK):
        size = min(CHUNK, n - start)
        t = np.array(list(tol.values()))[:, None]
        if al.method == "worst-case":
            delta = rng.uniform(-1.0, 1.0, (len(tol), size)) * t
        else:
            delta = rng.normal(0.0, 1.0, (len(tol), size)) * t / al.k
        P = np.repeat(nominal[:, None], size, axis=1)
        for i, p in enumerate(tol):
            P[names.index(p)] += delta[i]
        dq = _analyse(m, P, qs, al.omega2, plan) - q0[:, None]
        dev[:, start : start + size] = dq
        err[:, start : start + size] = delta
        lin[:, start : start + size] = dq - S @ delta
        bar.update(size)
    bar.close()
    E = np.array([al.limits[q] for q in qs])[:, None]
    inside = np.abs(dev) <= E  # nan (a sample that cannot be analysed) counts as outside
    return MonteCarlo(
        n=n,
        within={q: float(inside[i].mean()) for i, q in enumerate(qs)},
        worst={q: float(np.nanmax(np.abs(dev[i]), initial=0.0)) for i, q in enumerate(qs)},
        linearisation={q: float(np.nanmax(np.abs(lin[i]), initial=0.0)) for i, q in enumerate(qs)},
        all_within=float(inside.all(axis=0).mean()),
        failed=int(np.isnan(dev).any(axis=0).sum()),
        deviations={q: dev[i] for i, q in enumerate(qs)},
        errors={p: err[i] for i, p in enumerate(tol)},
    )


__all__ = ["sensitivities", "allocate", "Allocation", "MonteCarlo", "QUANTITIES", "METHODS"]
