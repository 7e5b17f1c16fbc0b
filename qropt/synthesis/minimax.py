"""A peak over the turn (the peak crank torque, the peak shaking force) minimised on the targets by a trust-region
SQP on its exact extremes: the local method for the min-max where a Nelder-Mead descent stalls at equal peaks.

The design is z, the free parameters but the first length (lengths in log; the scale is fixed by the stroke:
every design is scaled to it). The peak is F(z) = max_i f_i(z), f_i the local maxima of the quantity q over the
turn (those within NEAR of the largest, at most PEAKS). Each step solves the QP (scaled by F)

    min t + s'Bs / 2   s.t.   f_i + g_i's <= t,   a's = 0,   lo <= c + Cs <= hi,   |s|_inf <= delta

g_i is f_i's gradient, the derivative of q at the extreme's fixed crank angle (the envelope theorem); a the
gradient of log(TR / target); c the free parameters' coordinates and C their derivatives (the box), all by
forward differences of step STEP. B is the Lagrangian's Hessian, sum lambda_i H_i + mu H_TR, with H_i = q_zz -
q_zt^2 / q_tt (differences of step CURVE at fixed angles, ANGLE in the crank angle), lambda and mu the last
QP's multipliers, eigenvalues clipped to be positive. The step's design is put back on the TR along a (its
least-norm change) and scaled to the stroke, so every design met is on the targets; it is taken where the exact
F falls by at least RHO_TAKE of the predicted decrease. Where the linearised peaks and box miss by second-order
terms (the Maratos effect: steps along a curved valley where several peaks stay equal) the QP is solved once
more with their values at the trial design. The end is first-order stationary (Clarke) where its linear model
predicts a decrease below FIRST_ORDER within a step of CHECK.

The solver runs it on its best certified designs and its descents' ends at the end of a solve
(``Solver.polished``), and with ``Solver(sqp=True)`` on the evolution's designs as starts too.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from qropt.errors import QroptError
from qropt.synthesis import criteria, evolution
from qropt.synthesis import starts as starts_
from qropt.synthesis.settings import DEFAULT, Settings

PEAKS, NEAR = 8, 0.3  # the extremes the QP bounds: at most this many, within this fraction of the largest
STEP, CURVE, ANGLE = 1e-6, 1e-4, 1e-5  # finite-difference steps: gradients, curvatures (log or range units), rad
DELTA, DELTA_LEAST = 0.02, 1e-9  # the trust region's first and least radius (infinity norm, z's units)
RHO_TAKE, RHO_GROW, RHO_SHRINK = 0.01, 0.75, 0.25  # actual / predicted decrease: take, grow, shrink the region
CHECK, FIRST_ORDER = 1e-3, 1e-5  # the end is stationary where its linear model predicts a decrease below
# FIRST_ORDER (relative) within a step of CHECK: a slope below 1 % of the peak per unit of z (near a toggle an
# extreme's own slope can be many times the peak; the derivatives are differences)
CLIP = 1e-6  # the Hessian's eigenvalues at least this times its largest (a convex QP)
MARGIN = 1e-9  # the QP keeps the coordinates this far inside the box (its rows miss by higher-order terms)
TR_TOL, RESTORE = 1e-13, 12  # |log(TR / target)| a design on the targets meets; most restoration steps


@dataclass(frozen=True)
class Polished:
    """The end of an SQP run: the exact peak (the criterion's units), the design (free parameters), the steps
    taken, whether the end is first-order stationary (``_predicted`` below FIRST_ORDER), that predicted decrease
    (relative) and the number of extremes the model bounds there."""

    value: float
    design: dict
    steps: int
    stationary: bool
    predicted: float
    extremes: int

    @property
    def local(self) -> str:
        """The certificate's words on what holds at the end."""
        if self.stationary:
            return (
                f"first-order stationary (Clarke) for the peak over the turn: the linear model of its "
                f"{self.extremes} largest extremes, the TR and the box predicts a decrease of {self.predicted:.1e} "
                f"of it at most within a step of {CHECK:g} (an SQP on the exact peak, {self.steps} steps, every "
                "point on the targets)"
            )
        return f"none: an SQP on the exact peak stopped after {self.steps} steps, every point on the targets"


def applies(problem) -> bool:
    """Whether the objective is a peak over the turn (a criterion with a ``quantity``) of a problem the evolution
    puts on its targets (``evolution.applies``), without a free counterweight (its moments are the NLP's)."""
    c = criteria.of_problem(problem)
    balancing = problem.masses is not None and problem.masses.balancing
    return evolution.applies(problem) and c is not None and c.quantity is not None and not balancing


class _Coordinates:
    """The design's coordinates x (the free parameters but the first length, lengths in log), designs scaled to
    the stroke, their TR residual, and designs put back on the TR along its gradient."""

    def __init__(self, problem):
        self.problem, kinds = problem, problem.mechanism.kinds()
        self.log = {k: kinds[k] == "length" for k in problem.free}
        first = next((k for k in problem.free if self.log[k] and k != problem.mechanism.SYNTHESIS.crank), None)
        self.names = [k for k in problem.free if k != first]
        self.all = list(problem.free)
        self.lo = np.array([self._c(k, problem.free[k][0]) for k in self.all])
        self.hi = np.array([self._c(k, problem.free[k][1]) for k in self.all])
        self.branch = starts_.branches(problem)[0]
        self.tr, self.stroke = problem.targets["time_ratio"], problem.targets["stroke"]

    def _c(self, k, x):
        return math.log(x) if self.log[k] else x

    def z(self, d: dict) -> np.ndarray:
        return np.array([self._c(k, d[k]) for k in self.names])

    def coords(self, d: dict) -> np.ndarray:
        return np.array([self._c(k, d[k]) for k in self.all])

    def point(self, base: dict, z: np.ndarray) -> tuple[dict, float] | None:
        """(the design at z scaled to the stroke, log(TR / target)) or None where it does not build."""
        if not np.all(np.isfinite(z)) or np.max(np.abs(z)) > 50:
            return None
        d = base | {k: math.exp(x) if self.log[k] else float(x) for k, x in zip(self.names, z, strict=True)}
        try:
            m = self.problem.build(d, self.branch)
            miss, stroke = math.log(m.time_ratio() / self.tr), m.stroke()
        except (QroptError, ValueError, ZeroDivisionError):
            return None
        if not (math.isfinite(miss) and stroke > 0):
            return None
        return starts_.scaled(self.problem, d, self.stroke / stroke), miss

    def design(self, base: dict, z: np.ndarray, a: np.ndarray | None = None) -> dict | None:
        """The design at z put on the TR by steps along a (the TR residual's gradient: its least-norm change)
        until the residual is below TR_TOL, scaled to the stroke; None where that fails. Without a: z's design
        itself where it meets the TR already."""
        for _ in range(RESTORE):
            got = self.point(base, z)
            if got is None:
                return None
            d, miss = got
            if abs(miss) <= TR_TOL:
                return d
            if a is None or not a @ a > 0:
                return None
            z = z - miss * a / (a @ a)
        return None


class _Failed(Exception):
    """A difference's design that does not close or misses the targets: the model cannot be built."""


def _quantity(problem, c, d: dict | None, branch, angles: np.ndarray) -> np.ndarray:
    """q at the crank angles of design d (exact)."""
    from qropt.synthesis.dynamic import _cycle

    if d is None:
        raise _Failed
    try:
        return np.asarray(c.quantity(_cycle(problem, problem.build(d, branch)).at(angles)), float)
    except (QroptError, ValueError, ZeroDivisionError) as e:
        raise _Failed from e


def _extremes(problem, c, d: dict, branch, n=PEAKS, near=NEAR) -> tuple[np.ndarray, np.ndarray]:
    from qropt.synthesis.dynamic import _cycle

    peaks = _cycle(problem, problem.build(d, branch)).peaks(c.quantity, n, near)
    return np.array([p.theta2 for p in peaks]), np.array([p.value for p in peaks])


def _sided(xy: _Coordinates, d: dict, z: np.ndarray, j: int, h: float) -> tuple[float, dict, float]:
    """(sign, design, TR residual): z moved by h along coordinate j, else by -h where that design does not close
    (a near-toggle design lies near such a border)."""
    for sign in (1.0, -1.0):
        e = np.zeros(z.size)
        e[j] = sign * h
        if (got := xy.point(d, z + e)) is not None:
            return sign, got[0], got[1]
    raise _Failed


def _model(problem, c, xy: _Coordinates, d: dict, angles: np.ndarray) -> tuple:
    """(f, G, C, a, H, Hr): the extremes' values and gradients, the coordinates' Jacobian, the TR residual's
    gradient, the extremes' Hessians and the residual's (one-sided differences, each to the side where the design
    closes). The Hessians are zero where a curvature's design does not close on either side."""
    z, m, n = xy.z(d), angles.size, len(xy.names)
    br = xy.branch
    shifted = np.concatenate([angles, angles + ANGLE, angles - ANGLE])
    base = _quantity(problem, c, d, br, shifted)
    f, c0 = base[:m], xy.coords(d)
    r0 = xy.point(d, z)[1]
    G, C, a, signs = np.zeros((m, n)), np.zeros((c0.size, n)), np.zeros(n), np.zeros(n)
    for j in range(n):
        signs[j], dj, r = _sided(xy, d, z, j, STEP)
        G[:, j] = (_quantity(problem, c, dj, br, angles) - f) / (signs[j] * STEP)
        C[:, j] = (xy.coords(dj) - c0) / (signs[j] * STEP)
        a[j] = (r - r0) / (signs[j] * STEP)
    try:
        H, Hr, qjj = _curvatures(problem, c, xy, d, shifted, base, r0)
    except _Failed:
        return f, G, C, a, np.zeros((m, n, n)), np.zeros((n, n))
    # the forward differences' first error term, -h/2 times the second derivative (near a toggle q_zz is large)
    G -= 0.5 * signs * STEP * qjj
    a -= 0.5 * signs * STEP * np.diag(Hr)
    return f, G, C, a, H, Hr


def _curvatures(problem, c, xy: _Coordinates, d: dict, shifted: np.ndarray, base: np.ndarray, r0: float) -> tuple:
    """The extremes' Hessians q_zz - q_zt^2 / q_tt, the TR residual's and q_zz's diagonals (``_model``);
    ``shifted``: the extremes' angles and those ANGLE either side, ``base``: q there."""
    z, m, n, br = xy.z(d), shifted.size // 3, len(xy.names), xy.branch
    angles, f = shifted[:m], base[:m]
    once, r1, side = [], np.zeros(n), np.zeros(n)
    for j in range(n):
        side[j], dj, r1[j] = _sided(xy, d, z, j, CURVE)
        once.append(_quantity(problem, c, dj, br, shifted))
    qzz, rzz = np.zeros((m, n, n)), np.zeros((n, n))
    for j in range(n):
        for k in range(j, n):
            e = np.zeros(n)
            e[j] += side[j] * CURVE
            e[k] += side[k] * CURVE
            got = xy.point(d, z + e)
            if got is None:
                raise _Failed
            v, h2 = _quantity(problem, c, got[0], br, angles), side[j] * side[k] * CURVE**2
            qzz[:, j, k] = qzz[:, k, j] = (v - once[j][:m] - once[k][:m] + f) / h2
            rzz[j, k] = rzz[k, j] = (got[1] - r1[j] - r1[k] + r0) / h2

    def q_t(v):
        return (v[m : 2 * m] - v[2 * m :]) / (2 * ANGLE)

    q_tt = (base[m : 2 * m] - 2 * f + base[2 * m :]) / ANGLE**2
    q_zt = np.stack([(q_t(once[j]) - q_t(base)) / (side[j] * CURVE) for j in range(n)], axis=1)
    H = np.array([qzz[i] - np.outer(q_zt[i], q_zt[i]) / q_tt[i] if q_tt[i] < 0 else qzz[i] for i in range(m)])
    return H, rzz, np.array([np.diag(qzz[i]) for i in range(m)])


def _qp(F, f, G, C, c0, a, xy, B, delta):
    """The step's QP (module docstring), scaled by F, solved by Clarabel (its rows stated directly: for a QP of a
    few dozen rows a modelling layer's canonicalisation costs more than the solve): (s, the extremes'
    multipliers, the TR row's, predicted decrease) or None where Clarabel does not solve it."""
    import clarabel
    from scipy import sparse

    m, n = G.shape
    col = np.zeros((C.shape[0], 1))
    A = np.vstack(
        [
            np.append(a, 0.0)[None, :],  # a's = 0 (the zero cone)
            np.hstack([G / F, -np.ones((m, 1))]),  # (f - F) / F + G s / F <= t
            np.hstack([C, col]),  # the box
            np.hstack([-C, col]),
            np.hstack([np.eye(n), np.zeros((n, 1))]),  # |s|_inf <= delta
            np.hstack([-np.eye(n), np.zeros((n, 1))]),
        ]
    )
    b = np.concatenate([[0.0], (F - f) / F, xy.hi - MARGIN - c0, c0 - xy.lo - MARGIN, np.full(2 * n, delta)])
    rows = np.isfinite(b)  # an unbounded side of the box is no row
    if not (rows[: 1 + m].all() and np.all(np.isfinite(A)) and np.all(np.isfinite(B))):
        return None
    P = np.zeros((n + 1, n + 1))
    P[:n, :n] = B
    q = np.zeros(n + 1)
    q[n] = 1.0
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    cones = [clarabel.ZeroConeT(1), clarabel.NonnegativeConeT(int(rows.sum()) - 1)]
    A_csc, P_csc = sparse.csc_matrix(A[rows]), sparse.triu(sparse.csc_matrix(P), format="csc")
    solution = clarabel.DefaultSolver(P_csc, q, A_csc, b[rows], cones, settings).solve()
    if solution.status not in (clarabel.SolverStatus.Solved, clarabel.SolverStatus.AlmostSolved):
        return None  # an inaccurate end is still a step (AlmostSolved): the exact trial judges it
    x, z = np.asarray(solution.x, float), np.asarray(solution.z, float)
    step = x[:n]
    if not np.all(np.isfinite(x)):
        return None
    return step, np.maximum(z[1 : 1 + m], 0.0), float(z[0]), -(x[n] + 0.5 * step @ B @ step)


def _matched(angles: np.ndarray, to: np.ndarray) -> list[int]:
    """For each angle, the index of the nearest of ``to`` (around the turn)."""
    return [int(np.argmin(np.abs((to - a + math.pi) % (2 * math.pi) - math.pi))) for a in angles]


def polish(problem, design: dict, steps: int | None = None, settings: Settings = DEFAULT) -> Polished | None:
    """The SQP of the module docstring from a design on the targets (free parameters), of ``steps`` steps at most
    (``settings.sqp_steps``); None where it does not apply (``applies``) or the design has no exact value."""
    if not applies(problem):
        return None
    c, xy = criteria.of_problem(problem), _Coordinates(problem)
    F = evolution.value(problem, design, xy.branch)
    if F is None:
        return None
    d, delta, lam, fresh, taken = design, DELTA, None, True, 0
    count, last, mu = 0, None, 0.0
    for _ in range(steps or settings.sqp_steps):
        if fresh:
            try:
                angles, _ = _extremes(problem, c, d, xy.branch)
                f, G, C, a, H, Hr = _model(problem, c, xy, d, angles)
            except (_Failed, QroptError):
                break
            if lam is not None:  # the last multipliers on the nearest extremes
                moved = np.zeros(angles.size)
                for i, j in enumerate(_matched(last, angles)):
                    moved[j] += lam[i]
                lam = moved
            last, fresh, count = angles, False, angles.size
        hl = np.tensordot(lam if lam is not None else np.zeros(f.size), H, 1) / F + mu * Hr
        w, V = np.linalg.eigh(hl)
        B = (V * np.clip(w, CLIP * max(1.0, float(w.max())), None)) @ V.T
        c0, z = xy.coords(d), xy.z(d)
        got = _qp(F, f, G, C, c0, a, xy, B, delta)
        if got is None:
            break
        s, new_lam, mu, pred = got
        if pred <= settings.sqp_stationary:
            if lam is not None and np.allclose(lam, new_lam, atol=1e-3):
                break
            lam = new_lam
            continue
        lam = new_lam
        trial, Ft = _trial(problem, xy, d, z + s, a)
        rho = -1.0 if Ft is None else (F - Ft) / (F * pred)
        if rho < RHO_GROW and trial is not None:  # a second-order correction
            try:
                at, values = _extremes(problem, c, trial, xy.branch, 2 * PEAKS, 2 * NEAR)
            except QroptError:
                at = None
            if at is not None:
                shifted = np.array([values[j] for j in _matched(last, at)]) - G @ s
                moved = xy.coords(trial) - C @ s
                again = _qp(F, shifted, G, C, moved, a, xy, B, delta)
                if again is not None:
                    t2, F2 = _trial(problem, xy, d, z + again[0], a)
                    if F2 is not None and (Ft is None or Ft > F2):
                        trial, Ft, rho, s = t2, F2, (F - F2) / (F * pred), again[0]
        if rho > RHO_TAKE:
            d, F, fresh, taken = trial, Ft, True, taken + 1
            if rho > RHO_GROW and np.max(np.abs(s)) > 0.9 * delta:
                delta *= 2
            elif rho < RHO_SHRINK:
                delta /= 4
        else:
            delta /= 4
            if delta < DELTA_LEAST:
                break
    predicted = _predicted(problem, c, xy, d, F, None if fresh else (f, G, C, a))
    return Polished(F, d, taken, predicted <= FIRST_ORDER, predicted, count)


def _predicted(problem, c, xy: _Coordinates, d: dict, F: float, model: tuple | None) -> float:
    """The decrease (relative) the linear model of the end's extremes, TR and box predicts within a step of CHECK:
    zero at a first-order stationary point whatever the radius, unlike the last step's prediction, which shrinks
    with the trust region. ``model``: (f, G, C, a) at d where the last step built it, else built here."""
    if model is None:
        try:
            angles, _ = _extremes(problem, c, d, xy.branch)
            model = _model(problem, c, xy, d, angles)[:4]
        except (_Failed, QroptError):
            return math.inf
    f, G, C, a = model
    B = np.zeros((G.shape[1], G.shape[1]))
    got = _qp(F, f, G, C, xy.coords(d), a, xy, B, CHECK)
    return math.inf if got is None else max(got[-1], 0.0)


def _trial(problem, xy: _Coordinates, d: dict, z: np.ndarray, a: np.ndarray) -> tuple:
    """(the design at z put on the targets or None where that fails, its exact peak or None where it leaves the
    box or breaks a condition): a design outside the box still gives the second-order correction its place."""
    trial = xy.design(d, z, a)
    if trial is None or evolution.outside(problem, trial) > 0:
        return trial, None
    return trial, evolution.value(problem, trial, xy.branch)


__all__ = ["Polished", "applies", "polish"]
