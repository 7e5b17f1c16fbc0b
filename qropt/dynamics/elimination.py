"""The exact elimination of a linkage's Newton-Euler system: its steps chosen once from the system's structure
(``pivots``), vectorised over the crank angles or written as CasADi expressions (``Elimination``), and what one
solve hands the loads (``Parts``). ``qropt.dynamics.inverse`` (numpy) and ``qropt.dynamics.compiled`` (CasADi)
both solve with it."""

from __future__ import annotations

from dataclasses import dataclass

import casadi
import numpy as np


@dataclass
class Parts:
    """What the loads need of one solve at n crank angles: ``solve(extra)`` gives the unknowns (K rows of n) with
    the known load and ``extra`` (an (n,) array, or None) on the load's row (``_System.load_row``); the output's
    position (its unit) and velocity (m/s), the slots' unit normals, the shaking (fx, fy, moment)."""

    solve: object
    x_out: object
    v_out: object
    normals: dict
    shaking: tuple


PIVOT_TOL = 1e-10  # a pivot below this times its column's largest entry: that angle is solved with pivoting


def _constant(v) -> float | None:
    """An entry's value if it is the same at every angle and design (a number, a constant CasADi expression),
    else None."""
    if isinstance(v, (int, float)):
        return float(v)
    if isinstance(v, casadi.SX) and v.is_constant():
        return float(casadi.evalf(v))
    return None


def pivots(entries: dict, K: int) -> list[tuple[tuple, tuple]] | None:
    """The elimination's steps for a system's structure ({(row, column): value}), each (rows, columns): a nonzero
    constant entry while one is left (the one with the fewest fill-ins); then a row left with one unknown; then
    two rows left with the same two unknowns (a dyad's inner pin: a 2x2 block, solved by its determinant). None
    where the rest is coupled otherwise. Constant pivots never vanish, and a single unknown or a block's
    determinant vanishes only where the system is singular, so one sequence serves every crank angle and every
    design of a linkage, with the fill-in of the structure."""
    rows: dict[int, dict[int, float | None]] = {r: {} for r in range(K)}
    for (r, c), v in entries.items():
        value = _constant(v)
        if value != 0.0:
            rows[r][c] = value
    out, left = [], list(range(K))
    while left:
        best = None
        for r in left:
            for c, v in rows[r].items():
                if v is not None:
                    cost = (len(rows[r]) - 1) * (sum(c in rows[q] for q in left) - 1)
                    if best is None or cost < best[0]:
                        best = (cost, r, c)
        if best is not None:
            step = ((best[1],), (best[2],))
        else:
            step = next((((q,), tuple(rows[q])) for q in left if len(rows[q]) == 1), None)
            if step is None:
                pairs = [(q, s) for q in left for s in left if q < s and len(set(rows[q]) | set(rows[s])) == 2]
                if not pairs:
                    return None
                q, s = pairs[0]
                step = ((q, s), tuple(sorted(set(rows[q]) | set(rows[s]))))
        rs, cs = step
        if len(rs) == 1:
            (r,), (c,) = step
            p = rows[r][c]
            for q in left:
                if q != r and c in rows[q]:
                    f = rows[q].pop(c)
                    for cc, v in rows[r].items():
                        if cc != c:
                            old = rows[q].get(cc, 0.0)
                            known = p is not None and f is not None and v is not None and old is not None
                            new = old - f / p * v if known else None
                            if new == 0.0:
                                rows[q].pop(cc, None)
                            else:
                                rows[q][cc] = new
        else:  # the fill of a block: expressions
            for q in left:
                if q not in rs and any(c in rows[q] for c in cs):
                    for c in cs:
                        rows[q].pop(c, None)
                    for r in rs:
                        rows[q].update({cc: None for cc in rows[r] if cc not in cs})
        for r in rs:
            left.remove(r)
        out.append(step)
    return out


class Elimination:
    """Gaussian elimination of n small sparse systems A_i x = b_i (one per crank angle) that share a structure,
    vectorised across the angles, in the steps of ``pivots``. ``entries``: {(row, column): value}, each value a
    number (the same at every angle: kept a number, so a constant entry costs no array operation), an (n,) array,
    or a CasADi expression (``n`` None: the solution as expressions); absent entries are zero. An angle where a
    pivot (or a block's determinant) is small for its column is solved again by LAPACK with pivoting
    (np.linalg.solve, which raises LinAlgError where the system is singular), as is every angle of a structure
    coupled beyond 2x2 blocks. The factors are kept, so further right-hand sides (friction's iteration) cost a
    substitution."""

    def __init__(self, entries: dict, K: int, n: int | None, order=None):
        self.K, self.n, self.entries = K, n, entries
        self.order = order = pivots(entries, K) if order is None else order
        self.dense = order is None
        self.bad = np.zeros(n or 0, bool)
        if self.dense:
            return
        rows = [{} for _ in range(K)]
        for (r, c), v in entries.items():
            rows[r][c] = v
        self.steps = []  # (q, r, f): row q -= f * row r
        self.inverse = {}  # a step's first row -> the inverse of its pivot, or of its 2x2 block (row-major)
        done = set()
        for rs, cs in order:
            done.update(rs)
            below = [q for q in range(K) if q not in done and any(c in rows[q] for c in cs)]
            if len(rs) == 1:
                p = rows[rs[0]][cs[0]]
                inv = self._reciprocal(p, [p] + [rows[q][cs[0]] for q in below])
                self.inverse[rs[0]] = (inv,)
                for q in below:
                    self._subtract(rows, q, rs[0], rows[q].pop(cs[0]) * inv, cs)
                continue
            (r1, r2), (c1, c2) = rs, cs
            a, b = rows[r1].get(c1, 0.0), rows[r1].get(c2, 0.0)
            c, d = rows[r2].get(c1, 0.0), rows[r2].get(c2, 0.0)
            inv = self._reciprocal(a * d - b * c, [a * d, b * c])
            B = self.inverse[r1] = (d * inv, -b * inv, -c * inv, a * inv)
            for q in below:
                f1, f2 = rows[q].pop(c1, 0.0), rows[q].pop(c2, 0.0)
                self._subtract(rows, q, r1, f1 * B[0] + f2 * B[2], cs)
                self._subtract(rows, q, r2, f1 * B[1] + f2 * B[3], cs)
        self.rows = rows

    def _reciprocal(self, p, column):
        """1/p; an (n,) pivot small against its column's entries marks its angles bad (solved by LAPACK)."""
        if not isinstance(p, np.ndarray):
            return 1.0 / p
        scale = np.abs(column[0])
        for v in column[1:]:
            scale = np.maximum(scale, np.abs(v))
        self.bad |= np.abs(p) <= PIVOT_TOL * scale
        return 1.0 / np.where(p == 0, 1.0, p)

    def _subtract(self, rows, q, r, f, cs):
        for cc, v in rows[r].items():
            if cc not in cs:
                rows[q][cc] = rows[q][cc] - f * v if cc in rows[q] else -f * v
        self.steps.append((q, r, f))

    def solve(self, rhs: dict) -> list:
        """x as K columns, each (n,) (or an expression), for the right-hand sides {row: number, (n,) array or
        expression} (absent rows zero). Columns rather than one (n, K) array: many small arrays keep the allocator
        from returning memory to the system and faulting it in again at every call."""
        K, n = self.K, self.n
        if self.dense:
            if n is None:
                A, b = casadi.SX(K, K), casadi.SX(K, 1)
                for (r, c), v in self.entries.items():
                    A[r, c] = v
                for r, v in rhs.items():
                    b[r] = v
                x = casadi.solve(A, b)
                return [x[i] for i in range(K)]
            return list(self._lapack(rhs, np.ones(n, bool)).T)
        b = [rhs.get(i, 0.0) for i in range(K)]
        for q, r, f in self.steps:
            b[q] = b[q] - f * b[r]
        x = [None] * K
        for rs, cs in reversed(self.order):
            acc = []
            for r in rs:
                a = b[r]
                for cc, v in self.rows[r].items():
                    if cc not in cs:
                        a = a - v * x[cc]
                acc.append(a)
            B = self.inverse[rs[0]]
            if len(rs) == 1:
                x[cs[0]] = acc[0] * B[0]
            else:
                x[cs[0]] = B[0] * acc[0] + B[1] * acc[1]
                x[cs[1]] = B[2] * acc[0] + B[3] * acc[1]
        if n is None:
            return x
        x = [v if isinstance(v, np.ndarray) and v.shape == (n,) else np.full(n, float(v)) for v in x]
        if self.bad.any():
            fix = self._lapack(rhs, self.bad)
            for j in range(K):
                x[j][self.bad] = fix[:, j]
        return x

    def _lapack(self, rhs, sel) -> np.ndarray:
        K, m = self.K, int(sel.sum())
        A = np.zeros((m, K, K))
        b = np.zeros((m, K))
        for (r, c), v in self.entries.items():
            A[:, r, c] = v if np.ndim(v) == 0 else v[sel]
        for r, v in rhs.items():
            b[:, r] = v if np.ndim(v) == 0 else v[sel]
        return np.linalg.solve(A, b[..., None])[..., 0]


__all__ = ["Elimination", "Parts", "pivots", "PIVOT_TOL"]
