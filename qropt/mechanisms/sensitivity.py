"""Exact sensitivities of a mechanism's cycle quantities, and those quantities for many nearby mechanisms at once,
by AD of the type's loop (``Mechanism.sensitivity`` and ``Mechanism.nearby`` call these)."""

from __future__ import annotations

import math

import numpy as np

from qropt.errors import DegenerateMechanism, InvalidParameter, QroptError
from qropt.kinematics import cycle
from qropt.mechanisms.values import SENSITIVE, Sensitivity
from qropt.validate import number

TIE = 1e-9  # rad (relative for accelerations): stationary values this close share the extreme
NEARBY_GRID = 180  # crank angles on which every tracked nearby mechanism is checked
ACCEL_CHECK = 0.02  # a tracked peak |x''| must reach the grid's second differences within this


def sensitivity(m, quantity: str, omega2: float | None = None) -> Sensitivity:
    """Exact derivatives of 'time_ratio', 'stroke', 'gamma_min' (rad) or 'peak_acceleration' (over the turn,
    length/s^2 at omega2 rad/s) with respect to every parameter but the branch signs, in ``params`` order.

    A dead centre solves x'(theta*; p) = 0, so d theta*/dp = -(dx'/dp) / x'' (implicit function theorem); the
    stroke, gamma_min and the peak acceleration are values at stationary points, so their derivatives are
    partial derivatives at the fixed crank angle (envelope theorem), all by AD of the type's loop. Where the
    quantity is the larger or least of equal pieces it has a kink (TR = 1 where both strokes take pi; a
    transmission minimum or an acceleration peak reached at two crank angles): ``branches`` then holds every
    piece's gradient, ``left`` and ``right`` the one-sided derivatives and ``kink`` says why."""
    if quantity not in SENSITIVE:
        raise InvalidParameter(f"sensitivity: unknown quantity {quantity!r}; one of {list(SENSITIVE)}")
    if quantity == "peak_acceleration" and (omega2 is None or number("omega2", omega2) == 0.0):
        raise InvalidParameter(f"the peak acceleration's sensitivity needs a nonzero omega2 (rad/s), got {omega2}")
    m._require_full_turn()
    k, p = m._kernel, m._vector
    n = p.size
    names = tuple(q for q in m.params if q not in m.BRANCHES)
    cols = [list(m.params).index(q) for q in names]
    combine, kink = "max", ""
    if quantity in ("time_ratio", "stroke"):
        d = m.dead_centres()
        r = k.parametric("x")(np.column_stack([[d.theta_max, d.theta_min], np.broadcast_to(p, (2, n))]))
        x2, dx, dv = r[:, 2], r[:, 3 : 3 + n], r[:, 3 + n : 3 + 2 * n]
        if quantity == "stroke":
            rows = [dx[0] - dx[1]]
        else:
            if x2[0] == 0.0 or x2[1] == 0.0:
                raise DegenerateMechanism(f"{m!r}: a dead centre has x'' = 0; its time ratio is not smooth")
            a, b = m.stroke_angles()
            da = dv[0] / x2[0] - dv[1] / x2[1]  # a = theta_min - theta_max
            slow_a, slow_b = 2 * math.pi / b**2 * da, -2 * math.pi / a**2 * da  # TR = a / b, or b / a
            if abs(a - b) <= TIE:
                rows = [slow_a, slow_b]
                kink = "both strokes take pi (TR = 1, its least): TR - 1 grows as |dTR| either way"
            else:
                rows = [slow_a if a >= b else slow_b]
    elif quantity == "gamma_min":
        combine, least = "min", m.gamma_min().value
        minima = m.transmission_minima_by_joint()
        tied = []
        for j in k.joints:
            ts, vs = minima.get(j, ((), ()))
            tied += [(j, t) for t, v in zip(ts, vs, strict=True) if v <= least + TIE]
        rows = [k.parametric(j)(np.append(t, p)[None, :])[0, 1:] for j, t in tied] or [np.zeros(n)]
        if len(rows) > 1:
            kink = f"gamma_min is reached at {len(rows)} crank angles: it falls either way from a ridge"
    else:
        ex = m.acceleration_extremes()
        ts, vs = np.concatenate([ex.maxima[0], ex.minima[0]]), np.concatenate([ex.maxima[1], ex.minima[1]])
        if not ts.size:
            raise DegenerateMechanism(f"{m!r}: the slider acceleration has no regular extremes")
        tied = np.abs(vs) >= np.abs(vs).max() * (1 - TIE)
        r = k.parametric("x")(np.column_stack([ts[tied], np.broadcast_to(p, (int(tied.sum()), n))]))
        w2 = float(omega2) ** 2
        rows = list(np.sign(vs[tied])[:, None] * w2 * r[:, 3 + 2 * n :])
        if len(rows) > 1:
            kink = f"the peak |acceleration| is reached at {len(rows)} crank angles"
    return Sensitivity(quantity, names, np.array(rows)[:, cols], combine, kink)


def nearby(m, P, quantities=("time_ratio", "stroke"), omega2: float | None = None) -> np.ndarray:
    """Exact 'time_ratio', 'stroke', 'gamma_min' and 'peak_acceleration' (over the turn, at omega2) of many
    mechanisms of this type near this one, all at once: P holds one parameter set per row, (K, len(params)) in
    ``params`` order (branch signs included). Returns (len(quantities), K); nan where one cannot be analysed.

    Every stationary point (dead centres, transmission minima, acceleration extremes) is followed from this
    mechanism's by exact Newton steps, one compiled call per point; each must converge and hold the global
    extreme of a NEARBY_GRID-point grid (the peak acceleration within ACCEL_CHECK of the grid's second
    differences), else that mechanism is analysed on its own through this API."""
    qs = [quantities] if isinstance(quantities, str) else list(quantities)
    if not qs or any(q not in SENSITIVE for q in qs):
        raise InvalidParameter(f"nearby: quantities are among {list(SENSITIVE)}, got {quantities!r}")
    if "peak_acceleration" in qs:
        if omega2 is None or number("omega2", omega2) == 0.0:
            raise InvalidParameter("nearby: the peak acceleration needs a nonzero omega2 (rad/s)")
        omega2 = float(omega2)
    P = np.asarray(P)
    if P.dtype.kind not in "iuf" or P.ndim != 2 or P.shape[1] != len(m.params) or not np.isfinite(P).all():
        raise InvalidParameter(f"nearby: P must be finite numbers, one row of {list(m.params)} per mechanism")
    P = P.astype(float)
    m._require_full_turn()
    k, N = m._kernel, P.shape[0]
    d = m.dead_centres()
    tmax, xmax, ok = k.track("cycle", 0, d.theta_max, P, 1.0)
    tmin, xmin, conv = k.track("cycle", 0, d.theta_min, P, -1.0)
    ok &= conv
    xg, gammas, margins = k.grid_many(P, NEARBY_GRID, "gamma_min" in qs)
    with np.errstate(invalid="ignore"):
        slack = 1e-12 * (np.abs(xg).max(axis=0) + 1.0)
        ok &= (xmax >= xg.max(axis=0) - slack) & (xmin <= xg.min(axis=0) + slack)
        for margin in margins:
            ok &= np.all(margin >= -cycle.MARGIN_TOL, axis=0)
    out = np.full((len(qs), N), np.nan)
    for i, q in enumerate(qs):
        if q == "stroke":
            out[i] = xmax - xmin
        elif q == "time_ratio":
            s = np.mod(tmin - tmax, cycle.TWO_PI)
            out[i] = np.maximum(s, cycle.TWO_PI - s) / np.minimum(s, cycle.TWO_PI - s)
        elif q == "gamma_min":
            best, on_grid = np.full(N, math.pi / 2), np.full(N, math.pi / 2)
            minima = m.transmission_minima_by_joint()
            for j, g in zip(k.joints, gammas, strict=True):
                on_grid = np.minimum(on_grid, g.min(axis=0))
                for t0 in minima.get(j, ((),))[0]:
                    _, v, conv = k.track("cycle", 1 + k.joints.index(j), t0, P, 1.0)
                    ok &= conv
                    best = np.minimum(best, v)
            with np.errstate(invalid="ignore"):
                ok &= best <= on_grid + 1e-12
            out[i] = best
        else:
            peak, ex = np.zeros(N), m.acceleration_extremes()
            for sign, (ts, _) in ((1.0, ex.maxima), (-1.0, ex.minima)):
                for t0 in ts:
                    _, v, conv = k.track("accel", 0, t0, P, sign)
                    ok &= conv
                    peak = np.maximum(peak, np.abs(v))
            x2 = (np.roll(xg, 1, axis=0) - 2 * xg + np.roll(xg, -1, axis=0)) / (cycle.TWO_PI / xg.shape[0]) ** 2
            with np.errstate(invalid="ignore"):
                ok &= peak >= np.abs(x2).max(axis=0) * (1 - ACCEL_CHECK)
            out[i] = peak * omega2 * omega2
    for j in np.flatnonzero(~ok):  # one at a time through the API
        out[:, j] = _nearby_one(m, P[j], qs, omega2)
    return out


def _nearby_one(m, row, qs, omega2) -> np.ndarray:
    try:
        near = type(m)(**dict(zip(m.params, row.tolist(), strict=True)), units=m.units)
        vals = {
            "time_ratio": near.time_ratio,
            "stroke": near.stroke,
            "gamma_min": lambda: near.gamma_min().value,
            "peak_acceleration": lambda: near.peak_acceleration(omega2).value,
        }
        return np.array([vals[q]() for q in qs])
    except QroptError:
        return np.full(len(qs), np.nan)


__all__ = ["sensitivity", "nearby", "TIE", "NEARBY_GRID", "ACCEL_CHECK"]
