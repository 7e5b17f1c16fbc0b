"""Newton's method on the KKT conditions of a nearby problem's optimum, with its active set kept: the corrector of
a continuation (a chart's next cell, a front's next point), where the optimum moves smoothly with the problem.

From the neighbour's NLP point and multipliers, the rows it held at a bound (its equalities, the inequalities with
a multiplier, the variables on a bound) are held at theirs, and Newton solves the stationarity of the Lagrangian
and those rows for the point and the multipliers. The result is a local run like a backend's, but only once it is
verified a strict local minimum of the whole NLP: the KKT residuals to ``TOL``, every other row and bound met, each
held row's multiplier of the sign that a bound holding it needs and away from zero (strict complementarity), and
the Lagrangian's Hessian positive definite on the held rows' tangent space. Anything else (the active set changed,
the point left the region where the loop closes, a singular system, an NLP too large for its exact Hessian to pay)
returns None, and the backend runs from the neighbour's design instead.
"""

from __future__ import annotations

import time
import weakref
from dataclasses import dataclass

import casadi
import numpy as np

from qropt.kinematics.kernel import CSE, Batched
from qropt.synthesis.backends import Run, Status
from qropt.synthesis.settings import DEFAULT, Settings

TOL = 1e-11  # KKT residuals relative to their terms' scale; rows and bounds met to this, relative, at least 1
ACTIVE = 1e-7  # a multiplier counts (its row held) above this, relative to the largest
CURVED = 1e-10  # an eigenvalue of the KKT matrix counts as nonzero above this, relative to the largest


BLOCKS = ("samples", "fractions", "select", "caps")  # the exchange loop's blocks of p a hint keeps


@dataclass(frozen=True)
class Hint:
    """A certified optimum to continue from: its design (free values), the NLP point (a guarded NLP's lifted
    turn-back angles in it), its multipliers (rows, bounds; IPOPT's signs: positive at an upper bound), the
    exchange loop's parameter blocks (sample angles, fractions, the box's selection, caps) with how many sample
    slots it used, and a weak reference to its formulation, which stays in this process (a pickled hint fits no
    formulation)."""

    values: tuple
    w: np.ndarray
    lam_g: np.ndarray
    lam_x: np.ndarray
    blocks: dict
    used: tuple
    formulation: object = None  # a weak reference: a kept Result does not keep its NLP alive

    @classmethod
    def of(cls, form, values: dict, run, p, used) -> Hint:
        blocks = {k: v.copy() for k, v in form.p_blocks.split(p).items() if k in BLOCKS}
        return cls(_key(values), run.w, run.lam_g, run.lam_x, blocks, used, weakref.ref(form))

    @property
    def form(self):
        """Its formulation, or None (gone, or the hint was pickled)."""
        return self.formulation() if self.formulation is not None else None

    def fits(self, form, values: dict) -> bool:
        """Whether this is the optimum of ``form`` at the design ``values``."""
        return self.form is form and self.values == _key(values)

    def orientation(self, values: dict, branch: dict) -> int | None:
        """The TR orientation of this optimum's formulation where ``values`` and ``branch`` are its design's, else
        None (the caller checks that the formulation is its problem's)."""
        form = self.form
        mine = form is not None and self.values == _key(values) and form.branch == branch
        return form.orientation if mine else None

    def __getstate__(self):
        return {**self.__dict__, "formulation": None}

    def __setstate__(self, state):
        for k, v in state.items():
            object.__setattr__(self, k, v)


def _key(values: dict) -> tuple:
    return tuple(sorted((k, float(v)) for k, v in values.items()))


class _Compiled(Batched):
    HOT = 256  # evaluations after which a KKT function runs as machine code: a chart's hundreds of cells pay for
    # the compile (then cached on disk), a front's few points stay on CasADi's VM


def _functions(form, size_limit: int):
    """(f, grad f, g, dg/dw, the Lagrangian's Hessian) at z = (w, p, lam_g) as one dense row, built once per
    formulation and evaluated like the cycle kernels (``Batched``: buffers, machine code once it is used often),
    with the offsets of its parts; None for an NLP of more than ``size_limit`` instructions (its exact Hessian
    would take longer to build than the continuation saves)."""
    f = getattr(form, "_newton_kkt", False)
    if f is False:
        w, obj, g = form.w_sym, form.f_sym, form.g_sym
        size = casadi.Function("nlp", [w, form.p_sym], [obj, g]).n_instructions()
        if size > size_limit:
            form._newton_kkt = None
            return None
        lam = casadi.SX.sym("lam", g.numel())
        hess, _ = casadi.hessian(obj + casadi.dot(lam, g), w)
        parts = [obj, casadi.gradient(obj, w), g, casadi.jacobian(g, w), hess]
        kkt = casadi.Function(
            "kkt", [w, form.p_sym, lam], [casadi.vertcat(*[casadi.vec(casadi.densify(e)) for e in parts])]
        )
        n, k, m = w.numel(), form.p_sym.numel(), g.numel()
        z = casadi.SX.sym("z", n + k + m)
        row = kkt(z[:n], z[n : n + k], z[n + k :])
        batched = _Compiled(casadi.Function(f"kkt_{n}_{m}", [z], [row], CSE))
        f = form._newton_kkt = (batched, n, m, np.cumsum([1, n, m, m * n]))
    return f


def _evaluate(fun, w, p, lam) -> tuple:
    f, n, m, i = fun
    out = f(np.concatenate([w, p, lam])[None, :])[0]
    J = out[i[2] : i[3]].reshape((m, n), order="F")
    return out[0], out[i[0] : i[1]], out[i[1] : i[2]], J, out[i[3] :].reshape((n, n), order="F")


def correct(form, hint: Hint, p, lbx, ubx, settings: Settings = DEFAULT) -> Run | None:
    """The optimum at parameters p on the hint's active set, verified (module docstring), in ``newton_steps`` steps
    at most, for an NLP of ``newton_size`` instructions at most; None otherwise."""
    t0 = time.perf_counter()
    lbg, ubg = form.lbg, form.ubg
    lam_scale = max(_largest(hint.lam_g), _largest(hint.lam_x), 1e-300)
    rows = np.flatnonzero((lbg == ubg) | (np.abs(hint.lam_g) > ACTIVE * lam_scale))
    upper = hint.lam_g[rows] > 0
    side = np.where(lbg[rows] == ubg[rows], lbg[rows], np.where(upper, ubg[rows], lbg[rows]))
    on = np.abs(hint.lam_x) > ACTIVE * lam_scale
    at = np.where(hint.lam_x > 0, ubx, lbx)
    if not (np.isfinite(side).all() and np.isfinite(at[on]).all()):
        return None
    w = np.where(on, at, np.clip(hint.w, lbx, ubx)).astype(float)
    free = np.flatnonzero(~on)
    pick = (rows, free) if on.any() else (rows, slice(None))  # every variable free: plain row slices
    lam = np.zeros(lbg.size)
    lam[rows] = hint.lam_g[rows]
    fun = _functions(form, settings.newton_size)
    n, k = free.size, rows.size
    if fun is None or k > n:
        return None
    side_scale = max(1.0, _largest(side))
    for it in range(1, settings.newton_steps + 1):
        f, df, g, J, H = _evaluate(fun, w, p, lam)
        JA, Hf = J[rows][:, pick[1]], H[free][:, pick[1]]
        grad = df[free] + JA.T @ lam[rows]
        gap = g[rows] - side
        K = _kkt_matrix(Hf, JA)
        scale = max(1.0, _largest(df), _largest(JA.T * lam[rows]))
        if _largest(grad) <= TOL * scale and _largest(gap) <= TOL * side_scale:
            return _verified(
                form, w, f, g, J, df, K, lam, rows, upper, on, free, lbx, ubx, it, time.perf_counter() - t0
            )
        try:
            step = np.linalg.solve(K, -np.concatenate([grad, gap]))
        except np.linalg.LinAlgError:
            return None
        if not np.isfinite(step).all():
            return None
        w[free] += step[:n]
        lam[rows] += step[n:]
    return None


def _largest(v) -> float:
    return float(np.abs(v).max()) if v.size else 0.0


def _kkt_matrix(H, A) -> np.ndarray:
    n, k = H.shape[0], A.shape[0]
    K = np.zeros((n + k, n + k))
    K[:n, :n], K[:n, n:], K[n:, :n] = H, A.T, A
    return K


def _verified(form, w, f, g, J, df, K, lam, rows, upper, on, free, lbx, ubx, iterations, seconds) -> Run | None:
    """The run at w if it is a strict local minimum of the whole NLP on the held rows (module docstring): every
    row and bound met, the held inequalities' and bounds' multipliers of their bound's sign and away from zero
    (strictly active: the held rows' tangent space is then the critical cone), and the KKT matrix K
    of inertia (free variables, held rows, 0): the held rows independent and the Lagrangian's Hessian positive
    definite on their tangent space (the inertia of K is that of the reduced Hessian plus (rows, rows, 0))."""
    lbg, ubg = form.lbg, form.ubg
    tol = TOL * np.maximum(1.0, np.abs(np.where(np.isfinite(lbg), lbg, np.where(np.isfinite(ubg), ubg, 0.0))))
    if (g < lbg - tol).any() or (g > ubg + tol).any() or (w < lbx).any() or (w > ubx).any():
        return None
    lam_x = np.zeros(w.size)
    lam_x[on] = -(df + J[rows].T @ lam[rows])[on]
    weak = ACTIVE * max(_largest(lam), _largest(lam_x), 1e-300)  # strictly active: a multiplier away from zero
    ineq = lbg[rows] != ubg[rows]
    if (np.where(upper, lam[rows] <= weak, lam[rows] >= -weak) & ineq).any():
        return None
    if np.where(w[on] >= ubx[on], lam_x[on] <= weak, lam_x[on] >= -weak).any():
        return None
    e = np.linalg.eigvalsh(K)
    small = CURVED * max(1.0, _largest(e))
    if (e > small).sum() != free.size or (e < -small).sum() != rows.size:
        return None
    return Run(w, f, g, Status.SOLVED, "Newton on the neighbour's active set", iterations, seconds, lam, lam_x)


__all__ = ["Hint", "correct"]
