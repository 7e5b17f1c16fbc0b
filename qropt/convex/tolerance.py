"""Tolerance allocation: exact sensitivities of the time ratio, stroke, gamma_min and peak slider
acceleration to a mechanism's lengths and offsets, the largest tolerances that keep them within limits
(a convex program solved with cvxpy), and an exact Monte Carlo check of the allocation.

The sensitivities are ``Mechanism.sensitivity`` (AD of the type's own loop: implicit function theorem at
the dead centres, envelope theorem at the other stationary points) and the Monte Carlo's re-analysis is
``Mechanism.nearby`` (the exact analysis of many mechanisms at once). Tolerances are symmetric, +/- t_i in
the parameter's unit; gamma_min is in rad, the peak acceleration in length/s^2 at the given omega2.
Where a quantity has a kink at the nominal (TR = 1, a transmission minimum shared by two crank angles) the
one-sided derivatives differ: the stack-up uses the steeper, and the results say so (``kinks``).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field

import numpy as np
from tqdm import tqdm

from qropt.errors import InvalidParameter
from qropt.mechanisms import Mechanism

QUANTITIES = ("time_ratio", "stroke", "gamma_min", "peak_acceleration")
METHODS = ("worst-case", "rss")
TOLERANCED = ("length", "offset", "angle")  # the parameter kinds (Mechanism.kinds()) given tolerances by default
CHUNK = 2000  # samples analysed at once (bounded memory)
MAX_SAMPLES = 10_000_000
ROUNDING = 1e-12  # a sensitivity below this fraction of its row's largest is rounding: zero


def _names(m: Mechanism, params) -> list[str]:
    if not isinstance(m, Mechanism):
        raise InvalidParameter(f"expected a qropt mechanism, got {m!r}")
    if params is None:
        kinds = type(m).kinds()  # the lengths first (in LENGTHS order), then the offsets and angles
        return [k for k in type(m).LENGTHS if k in m.params] + [
            k for k in m.params if kinds.get(k) in TOLERANCED and k not in type(m).LENGTHS
        ]
    allowed = [k for k in m.params if k not in type(m).BRANCHES]
    if isinstance(params, str):
        params = [params]
    if isinstance(params, dict) or not isinstance(params, (list, tuple, set, frozenset, np.ndarray)):
        raise InvalidParameter(f"params must be a parameter name or a list of them (of {allowed}), got {params!r}")
    names = list(params)
    for k in names:
        if k not in allowed:
            why = "branch signs have no tolerance" if k in type(m).BRANCHES else "unknown parameter"
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


def _rows(m: Mechanism, names, quantities, omega2):
    """The exact sensitivities of each quantity (``Mechanism.sensitivity``) restricted to ``names``: the matrix
    dQ/dp (len(quantities), len(names)) of the steeper one-sided slopes, and per quantity its Sensitivity."""
    out, sens = np.zeros((len(quantities), len(names))), {}
    for i, q in enumerate(quantities):
        s = m.sensitivity(q, omega2)
        cols = [s.names.index(k) for k in names]
        branches = _clean(s.branches[:, cols])
        sens[q] = s._replace(names=tuple(names), branches=branches)
        out[i] = sens[q].gradient
    return out, sens


def _clean(rows):
    """Entries below ROUNDING of their row's largest are rounding: exact zeros."""
    rows = rows.copy()
    rows[np.abs(rows) <= ROUNDING * np.abs(rows).max(axis=1, keepdims=True)] = 0.0
    return rows


def _omega2(omega2):
    if omega2 is None:
        return None
    if isinstance(omega2, bool) or not isinstance(omega2, (int, float)) or not math.isfinite(omega2) or omega2 == 0:
        raise InvalidParameter(f"omega2 must be a nonzero finite number (rad/s), got {omega2!r}")
    return float(omega2)


class Sensitivities(dict):
    """{quantity: {param: dQ/dp}} (the steeper one-sided slope where Q has a kink), with ``left`` and ``right``
    (the one-sided derivatives, same layout) and ``kinks`` ({quantity: why}, empty where every Q is smooth)."""

    def __init__(self, rows, sens, names):
        super().__init__({q: dict(zip(names, map(float, r), strict=True)) for q, r in zip(sens, rows, strict=True)})
        self.left = {q: dict(zip(names, map(float, s.left), strict=True)) for q, s in sens.items()}
        self.right = {q: dict(zip(names, map(float, s.right), strict=True)) for q, s in sens.items()}
        self.kinks = {q: s.kink for q, s in sens.items() if s.kink}


def sensitivities(mechanism: Mechanism, params=None, *, omega2: float | None = None) -> Sensitivities:
    """Exact dQ/dp of time_ratio, stroke, gamma_min (rad) and, with omega2 (rad/s), the peak slider
    acceleration over the turn, for each parameter in ``params`` (default: the lengths and offsets), from
    ``Mechanism.sensitivity``.

    Where Q has a kink at these parameters (TR = 1, as for an in-line slider-crank; gamma_min shared by several
    minima of a symmetric mechanism) the value given is, per parameter, the one-sided slope of largest
    magnitude (a safe bound for a stack-up); the result's ``left``, ``right`` and ``kinks`` say so."""
    names, omega2 = _names(mechanism, params), _omega2(omega2)
    qs = [q for q in QUANTITIES if q != "peak_acceleration" or omega2 is not None]
    rows, sens = _rows(mechanism, names, qs, omega2)
    return Sensitivities(rows, sens, names)


@dataclass(frozen=True, repr=False)
class MonteCarlo:
    """Exact re-analysis of n random mechanisms: per limited quantity the fraction within its limit, the
    worst |deviation| and the largest linearisation error |dQ - dQ_lin| (dQ_lin = S dp, or at a kink the
    largest or least of the pieces' S_j dp); ``all_within`` meets every limit; ``failed`` samples could not
    be analysed (counted outside); ``deviations`` holds every dQ and ``errors`` every sampled parameter error
    (parameters with an infinite tolerance are held at their nominal); ``kinks``: {quantity: why} for the
    quantities not differentiable at the nominal (their dQ is not S dp, e.g. TR - 1 >= 0 at TR = 1)."""

    n: int
    within: dict
    worst: dict
    linearisation: dict
    all_within: float
    failed: int
    deviations: dict = field(default_factory=dict)
    errors: dict = field(default_factory=dict)
    kinks: dict = field(default_factory=dict)

    def __repr__(self):
        parts = ", ".join(f"{q}: {100 * f:.2f}% (worst {self.worst[q]:.4g})" for q, f in self.within.items())
        kinks = "".join(f", {q} at a kink" for q in self.kinks)
        return f"MonteCarlo(n={self.n}, {parts}, all {100 * self.all_within:.2f}%, failed {self.failed}{kinks})"


@dataclass(frozen=True, repr=False)
class Allocation:
    """Tolerances ``{param: t}`` (+/- t, the parameter's unit; inf where no limited quantity depends on it),
    status 'optimal' / 'infeasible' / 'failed' with a message, the sensitivities used and, per limit,
    ``usage``: the stack-up (worst-case sum or k times the rss) over the limit; ``kinks``: {quantity: why}
    for limited quantities with a kink at the nominal (their sensitivities are the steeper one-sided slopes)."""

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
    kinks: dict = field(default_factory=dict)
    pieces: dict = field(default_factory=dict)  # quantity -> Sensitivity restricted to the toleranced names

    def __repr__(self):
        t = ", ".join(f"{p}=+/-{v:.4g}" for p, v in self.tolerances.items())
        return f"Allocation(status={self.status!r}, {self.method}, {t})"

    def monte_carlo(self, n: int = 10_000, seed: int | None = 0, progress: bool | None = None) -> MonteCarlo:
        """Re-analyse n mechanisms with errors uniform in +/- t (worst-case) or normal, sigma = t / k (rss).

        ``Mechanism.nearby`` follows every sample's dead centres, transmission minima and acceleration extremes
        from the nominal's by exact Newton steps, checks them against a 180-point grid and analyses a sample
        that fails on its own: the numbers are the exact analysis (to ~1e-12), not a linear estimate.
        seed: a non-negative integer (or None: fresh entropy). progress: a bar on standard error (None: only
        when it is a terminal)."""
        if self.status != "optimal":
            raise InvalidParameter(f"no tolerances to check: status {self.status!r} ({self.message})")
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or not 1 <= n <= MAX_SAMPLES:
            raise InvalidParameter(f"n must be an integer in 1..{MAX_SAMPLES}, got {n!r}")
        if seed is not None and (isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0):
            raise InvalidParameter(f"seed must be a non-negative integer (or None), got {seed!r}")
        return _monte_carlo(self, int(n), seed, progress)


def _bounds(bounds, names):
    """{param: (low, high)} (None: 0 or no bound) -> arrays low, high."""
    lo, hi = np.zeros(len(names)), np.full(len(names), np.inf)
    if bounds is not None and not isinstance(bounds, dict):
        raise InvalidParameter(f"bounds must be a {{param: (low, high)}} mapping, got {bounds!r}")
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
        if b == 0.0:
            raise InvalidParameter(
                f"bounds[{k!r}] = {v!r}: the upper bound must be positive (a zero tolerance "
                f"makes log t = -inf; leave {k} out of params to hold it exact)"
            )
        lo[names.index(k)], hi[names.index(k)] = a, b
    return lo, hi


def allocate(
    mechanism: Mechanism,
    limits: dict,
    *,
    params=None,
    method: str = "worst-case",
    k: float = 3.0,
    weights=None,
    bounds=None,
    omega2: float | None = None,
) -> Allocation:
    """The tolerances t maximising sum w_i log t_i with, for each limited quantity Q (limit E):
    sum_i |dQ/dp_i| t_i <= E ('worst-case') or ||dQ/dp * t||_2 <= E / k ('rss').

    limits: {quantity: E > 0} over time_ratio, stroke (length), gamma_min (rad), peak_acceleration
    (length/s^2, needs omega2); params: the toleranced names (default: lengths and offsets); weights:
    {param: w > 0} (default 1); bounds: {param: (low, high)} on t."""
    import cvxpy as cp  # imported on use: it is slow to import

    names, omega2 = _names(mechanism, params), _omega2(omega2)
    if method not in METHODS:
        raise InvalidParameter(f"method must be one of {METHODS}, got {method!r}")
    if not isinstance(limits, dict) or not limits:
        raise InvalidParameter("limits must be a non-empty {quantity: allowed deviation} mapping")
    qs = _quantities(list(limits), omega2)
    E = np.array([_positive(f"limit {q}", limits[q]) for q in qs])
    k = _positive("k", k)
    w = _weights(weights, names)
    lo, hi = _bounds(bounds, names)
    S, pieces = _rows(mechanism, names, qs, omega2)
    base = dict(
        mechanism=mechanism,
        limits=dict(zip(qs, E.tolist(), strict=True)),
        method=method,
        k=k,
        sensitivities={q: dict(zip(names, r.tolist(), strict=True)) for q, r in zip(qs, S, strict=True)},
        omega2=omega2,
    )
    base.update(kinks={q: s.kink for q, s in pieces.items() if s.kink}, pieces=pieces)
    A = np.abs(S) / E[:, None] * (1.0 if method == "worst-case" else k)  # each limit: ||A_j t|| <= 1
    over = [q for q, a in zip(qs, A, strict=True) if _stack(a, lo, method) > 1.0]
    if over:
        return Allocation(
            "infeasible",
            f"infeasible: the lower bounds alone exceed the limits on {', '.join(over)}",
            tolerances={},
            usage={},
            **base,
        )
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
    for q, why in base["kinks"].items():
        msg += f"; {q} has a kink at the nominal ({why}): its sensitivities are the steeper one-sided slopes"
    if free:
        msg += f"; no limited quantity depends on {', '.join(free)} (tolerance = its upper bound, or inf)"
    return Allocation("optimal", msg, tolerances=tol, usage=usage, **base)


WEIGHT_SPAN = 1e12  # largest over least weight: beyond it the lightest tolerances fall below rounding


def _weights(weights, names) -> np.ndarray:
    """{param: w > 0} -> weights (default 1) scaled so the largest is 1 (only their ratios matter)."""
    if weights is not None and not isinstance(weights, dict):
        raise InvalidParameter(f"weights must be a {{param: weight}} mapping, got {weights!r}")
    w = np.ones(len(names))
    for name, v in (weights or {}).items():
        if name not in names:
            raise InvalidParameter(f"weights: {name!r} is not among the toleranced parameters {names}")
        w[names.index(name)] = _positive(f"weight of {name}", v)
    if w.max() / w.min() > WEIGHT_SPAN:
        raise InvalidParameter(
            f"weights span a ratio of {w.max() / w.min():.3g} (heaviest {names[int(np.argmax(w))]}, lightest "
            f"{names[int(np.argmin(w))]}): tolerances grow in proportion to their weights, so beyond "
            f"{WEIGHT_SPAN:.0e} the lightest would be below rounding of the heaviest; give weights within that ratio"
        )
    return w / w.max()


def _convex(a, w, lo, hi, method):
    """maximise w . log u s.t. each row's stack-up of a u <= 1, lo <= u <= hi, with cvxpy (CLARABEL), then
    polished on the KKT equations of the active set. Returns (u or None, 'polished' or the cvxpy status)."""
    import cvxpy as cp  # imported on use: it is slow to import

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
def _monte_carlo(al: Allocation, n: int, seed, progress) -> MonteCarlo:
    m, qs = al.mechanism, list(al.limits)
    names = list(m.params)
    tol = {p: t for p, t in al.tolerances.items() if math.isfinite(t)}
    rng = np.random.default_rng(seed)
    nominal = np.array([m.params[k] for k in names])
    q0 = m.nearby(nominal[None, :], qs, al.omega2)[:, 0]
    pieces = {
        q: al.pieces[q]._replace(branches=al.pieces[q].branches[:, [al.pieces[q].names.index(p) for p in tol]])
        for q in qs
    }
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
        dq = m.nearby(P.T, qs, al.omega2) - q0[:, None]
        dev[:, start : start + size] = dq
        err[:, start : start + size] = delta
        lin[:, start : start + size] = dq - np.array([pieces[q].change(delta) for q in qs])
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
        kinks=dict(al.kinks),
    )


__all__ = ["sensitivities", "allocate", "Allocation", "MonteCarlo", "Sensitivities", "QUANTITIES", "METHODS"]
