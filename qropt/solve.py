"""solve(problem) -> Result: IPOPT from analytic warm starts and a space-filling multi-start,
an exchange loop for continuous-cycle extremes, and a certificate by exact numeric evaluation."""

from __future__ import annotations

import collections
import contextlib
import functools
import itertools
import math
import time

import numpy as np
from scipy.stats import qmc

from qropt import analytic
from qropt.errors import AssemblyError, QroptError
from qropt.mechanisms import FourBar
from qropt.nlp import BASE_SAMPLES, EXTRA_SAMPLES, TWO_PI, Formulation, slow_interval
from qropt.problem import Problem
from qropt.result import Result

_FORMULATIONS: dict = {}
FEAS_TOL = 1e-8  # largest accepted constraint violation (lengths, radians)
GAP_TOL = 1e-8  # certified minus NLP epigraph value that ends the exchange loop


def _key(problem: Problem, branch, orientation, range_target, sense):
    c = problem.conditions
    cond = (c.get("grashof"), c.get("gamma_min"), repr(c.get("linear")), repr(c.get("ratio")))
    return (problem.mechanism, tuple(problem.free), tuple(problem.fixed), tuple(problem.targets), cond,
            problem.objective, problem.size, problem.accel_over, tuple(sorted(branch.items())), orientation,
            range_target, sense)  # fmt: skip


def formulation(problem, branch, orientation, range_target=None, sense=1) -> Formulation:
    """The NLP of this problem structure, built once and reused: fixed values, targets and samples are CasADi
    parameters, and the free bounds are read from the problem at solve time."""
    key = _key(problem, branch, orientation, range_target, sense)
    f = _FORMULATIONS.get(key)
    if f is None:
        f = _FORMULATIONS[key] = Formulation(problem, branch, orientation, range_target, sense)
    f.problem = problem
    return f


@functools.lru_cache(maxsize=256)
def _build(problem, values: tuple, branch: tuple):
    return problem.build(dict(values), dict(branch))


def build(problem, values: dict, branch: dict):
    """problem.build, cached (mechanisms are immutable): a start is built once for all its uses."""
    return _build(problem, tuple(sorted(values.items())), tuple(sorted(branch.items())))


def branches(problem):
    names = list(problem.branches)
    return [dict(zip(names, combo, strict=True)) for combo in itertools.product(*problem.branches.values())]


def starts(problem, n: int, seed: int, use_analytic: bool) -> list[tuple[str, dict]]:
    """Analytic starts first, then a scrambled Sobol design over the free bounds (log-spaced for lengths)."""

    def clip(v):
        return {k: min(max(x, problem.free[k][0]), problem.free[k][1]) for k, x in v.items()}

    out = [("analytic", clip(s)) for s in analytic.warm_starts(problem)] if use_analytic else []
    if n > 0:
        names = list(problem.free)
        points = []
        for row in qmc.Sobol(len(names), scramble=True, seed=seed).random(8 * n):
            v = {}
            for k, x in zip(names, row, strict=True):
                lo, hi = problem.free[k]
                v[k] = lo * (hi / lo) ** x if k in problem.mechanism.LENGTHS and lo > 0 else lo + (hi - lo) * x
            points.append(v)
        kept = [v for v in points if _assembles(problem, v)][:n]
        out += [("multistart", v) for v in (kept or points[:n])]
    return out


def _assembles(problem, values) -> bool:
    try:
        build(problem, values, branches(problem)[0]).dead_centres()
        return True
    except QroptError:
        return False


def _angle_gap(a, b):
    return abs((a - b + math.pi) % TWO_PI - math.pi)


def quantities(problem, m) -> dict:
    """Exact quantities of a mechanism for a Result."""
    q = {"time_ratio": m.time_ratio(), "gamma_min": m.gamma_min().value}
    q["swing" if isinstance(m, FourBar) else "stroke"] = m.stroke()
    q["peak_accel"] = None if isinstance(m, FourBar) else m.peak_acceleration(problem.omega2, problem.accel_over)[0]
    q["grashof"] = m.grashof().kind if hasattr(m, "grashof") else None
    q["size"] = m.size(problem.size)
    q["working_direction"] = m.working_direction(problem.omega2)
    return q


def objective_value(problem, q) -> float | None:
    return {"max_gamma_min": q["gamma_min"], "min_size": q["size"], "min_peak_accel": q["peak_accel"]}.get(
        problem.objective
    )


def certify(problem, form, values, branch, th, z, targets):
    """Exact check of an NLP point. Returns (mechanism or None, info dict, angles to add, fractions to add)."""
    try:
        return _certify(problem, form, values, branch, th, z)
    except AssemblyError as e:
        mids = [((lo + hi) / 2) % TWO_PI for _, lo, hi in e.failures]
        return None, {"ok": False, "reason": str(e)}, mids, []
    except QroptError as e:
        return None, {"ok": False, "reason": str(e)}, [], []


def _certify(problem, form, values, branch, th, z):
    m = problem.build(values, branch)
    d = m.dead_centres()
    if _angle_gap(d.theta_max, th[0]) > 1e-7 or _angle_gap(d.theta_min, th[1]) > 1e-7:
        return m, {"ok": False, "reason": "the NLP's dead centres are local, not the global extremes"}, [], []
    if d.reversals != 1:
        return m, {"ok": False, "reason": f"the slider reverses {d.reversals} times a turn"}, [], []
    info = {"ok": True, "nlp": None, "certified": None, "gap": 0.0}
    add, frac = [], []
    obj = problem.objective if not form.range_target else None
    g = m.gamma_min()
    if obj == "max_gamma_min":
        exact = math.cos(g.value)
        info.update(nlp=math.acos(min(1.0, z[0])), certified=g.value, gap=exact - z[0])
        if exact - z[0] > GAP_TOL:  # every local minimum of every joint below the NLP's value
            for t, v in m.transmission_minima():
                add += [float(a) for a, b in sorted(zip(t, v, strict=True), key=lambda q: q[1]) if math.cos(b) > z[0]]
    elif obj == "min_peak_accel":
        peak, t = m.peak_acceleration(1.0, problem.accel_over)
        w2 = problem.omega2**2
        info.update(nlp=z[0] * w2, certified=peak * w2, gap=(peak - z[0]) * w2)
        if peak - z[0] > GAP_TOL:  # every local extreme of the acceleration above the NLP's bound
            ts, vs = (np.concatenate(x) for x in zip(*m._acceleration_extremes, strict=True))
            worst = [float(a) for a, b in sorted(zip(ts, vs, strict=True), key=lambda q: -abs(q[1])) if abs(b) > z[0]]
            if problem.accel_over == "working":
                lo, length = m.working_arc()
                frac += [((a - lo) % TWO_PI) / length for a in worst if (a - lo) % TWO_PI <= length] or [
                    ((t - lo) % TWO_PI) / length
                ]
            else:
                add += worst or [t]
    elif obj == "min_size" and problem.size == "footprint":
        box, angles = m.bounding_box()
        exact = (box[1] - box[0]) * (box[3] - box[2])
        nlp = (z[0] + z[1]) * (z[2] + z[3])
        info.update(nlp=nlp, certified=exact, gap=exact - nlp)
        if exact - nlp > GAP_TOL * max(1.0, exact):
            add += list(angles)
    elif obj == "min_size":
        info.update(nlp=m.size(problem.size), certified=m.size(problem.size), gap=0.0)
    bound = problem.conditions.get("gamma_min")
    if bound is not None and g.value < bound - FEAS_TOL:
        add.append(g.theta2)
    return m, info, add, frac


def _residuals(problem, form, g, m, targets):
    res = {k: v for k, v in form.violations(g).items() if not k.startswith("epigraph")}
    if m is not None:
        q = {"time_ratio": m.time_ratio(), "stroke": m.stroke(), "swing": m.stroke()}
        for k, v in targets.items():
            res[f"{k} (exact)"] = abs(q[k] - v)
        if "gamma_min" in problem.conditions:
            res["gamma_min bound (exact)"] = max(0.0, problem.conditions["gamma_min"] - m.gamma_min().value)
    return res


def _peaks(problem, values, branch):
    """Initial lifted acceleration extremes: the start design's largest |d2x/dtheta2| (in the working
    stroke when asked), else spread over the turn."""
    if problem.objective != "min_peak_accel":
        return None
    try:
        m = build(problem, values, branch)
        ts, vs = (np.concatenate(x) for x in zip(*m._acceleration_extremes, strict=True))
    except QroptError:
        return None
    order = np.argsort(-np.abs(vs))
    if problem.accel_over == "working":
        lo, length = m.working_arc()
        order = [i for i in order if (ts[i] - lo) % TWO_PI <= length]
        return [lo + (ts[i] - lo) % TWO_PI for i in order] or None
    return [float(ts[i]) for i in order]


def start_orientation(problem, values, branch):
    """+1 if the start's slow interval runs from theta_max to theta_min (counter-clockwise), -1 if not,
    None if it does not turn fully."""
    try:
        a, b = build(problem, values, branch).stroke_angles()
        return 1 if a >= b else -1
    except QroptError:
        return None


def _place(slots, used, new, period, near):
    """Put new sample angles into the extra slots: an angle close to an extra sample moves it there (the
    worst angle drifts as the design changes), others take free slots. Returns the slots in use."""
    for t in new:
        extra = np.arange(BASE_SAMPLES, used)
        if extra.size:
            d = np.abs((slots[extra] - t + period / 2) % period - period / 2)
            k = int(np.argmin(d))
            if d[k] < near:
                slots[extra[k]] = t
                continue
        if used < BASE_SAMPLES + EXTRA_SAMPLES:
            slots[used] = t
            used += 1
    return used


def _converged(stats) -> bool:
    """IPOPT solved the NLP (to its tolerance, or to its acceptable level)."""
    return bool(stats.get("success")) or stats.get("return_status") == "Solved_To_Acceptable_Level"


def run_start(problem, values0, branch, targets, max_rounds=30, range_target=None, sense=1, orientation=None):
    """One local solve with its exchange loop: a dict describing the candidate.

    orientation: which way the TR equality is met (+1, -1); None takes the start's own.
    """
    try:
        m0 = build(problem, values0, branch)
        d = m0.dead_centres()
        a, b = m0.stroke_angles()
        orientation = orientation or (1 if a >= b else -1)
        th0 = (d.theta_max, d.theta_max + a)
    except QroptError:
        orientation, tr = orientation or 1, targets.get("time_ratio", 1.5)
        th0 = (0.5, 0.5 + slow_interval(tr, orientation))
    if "time_ratio" in targets and range_target != "time_ratio":
        th0 = (th0[0], th0[0] + slow_interval(targets["time_ratio"], orientation))
    form = formulation(problem, branch, orientation, range_target, sense)
    samples, fractions = form.base_samples()
    used, used_f = BASE_SAMPLES, BASE_SAMPLES
    p = form.param_vector(targets, samples, fractions)
    w = form.epigraph_start(form.pack(values0, th0, phi=_peaks(problem, values0, branch)), p)
    t_ipopt, iters, statuses, rounds = 0.0, 0, [], 0
    while rounds < max_rounds:
        rounds += 1
        w, f, g, st = form.solve(w, p)
        t_ipopt += st.get("t_wall_total", 0.0)
        iters += st.get("iter_count", 0)
        statuses.append(st.get("return_status", "?"))
        values = dict(zip(form.free, w[: form.nx].tolist(), strict=True))
        th, z = w[form.nx : form.nx + 2], w[form.nx + 2 : form.nx + 2 + form.nz]
        m, info, add, frac = certify(problem, form, values, branch, th, z, targets)
        if not _converged(st) and not range_target:
            break
        if not add and not frac:
            break
        used = _place(samples, used, add, TWO_PI, 0.05)
        used_f = _place(fractions, used_f, frac, 1.0, 0.01)
        p = form.param_vector(targets, samples, fractions)
        w = form.epigraph_start(w, p) if info.get("gap", 0) > 0 or not info.get("ok") else w
    res = _residuals(problem, form, g, m, {k: targets[k] for k in form.targets})
    ok = bool(info.get("ok")) and _converged(st)
    ok = ok and max(res.values(), default=0.0) <= FEAS_TOL and info.get("gap", 0.0) <= GAP_TOL
    return {
        "ok": ok,
        "q": quantities(problem, m) if ok else None,
        "values": values,
        "branch": branch,
        "orientation": orientation,
        "mechanism": m,
        "info": {**info, "rounds": rounds},
        "residuals": res,
        "ipopt": {"statuses": statuses, "iterations": iters, "t_ipopt": t_ipopt},
        "f": f,
    }


def _distinct(cands):
    out = []
    for c in cands:
        v = np.array([c["values"][k] for k in sorted(c["values"])])
        if all(
            c["branch"] != o["branch"]
            or np.max(np.abs(v - np.array([o["values"][k] for k in sorted(o["values"])])) / np.maximum(1, np.abs(v)))
            > 1e-6
            for o in out
        ):
            out.append(c)
    return out


def _to_result(problem, c, status, message, stats, local=()):
    m, q = c["mechanism"], c["q"]
    params = dict(m.params)
    return Result(
        status=status,
        message=message,
        params=params,
        mechanism=m,
        objective=objective_value(problem, q),
        quantities=q,
        residuals=c["residuals"],
        certificate=c["info"],
        stats={**stats, **c["ipopt"], "branch": c["branch"], "orientation": c["orientation"]},
        local_optima=tuple(local),
    )


def solve(problem: Problem, *, starts_n: int = 8, use_analytic: bool = True, seed: int = 0,
          targets: dict | None = None, max_rounds: int = 30, extra_starts=()) -> Result:  # fmt: skip
    """Solve a synthesis problem; returns a Result whatever happens (only invalid input raises).

    starts_n: Sobol multi-start points; use_analytic: start from every closed form as well;
    targets: override the problem's target values (the NLP is not rebuilt);
    extra_starts: more starting points (free-parameter dicts), tried first.
    """
    t0 = time.perf_counter()
    targets = dict(problem.targets if targets is None else targets)
    cands = []
    given = [("given", {k: v[k] for k in problem.free}) for v in extra_starts]
    for origin, v in given + starts(problem, starts_n, seed, use_analytic):
        for br in branches(problem):
            own = start_orientation(problem, v, br)
            ways = [own] if origin in ("analytic", "given") and own else [1, -1]
            for orientation in ways:
                c = run_start(problem, v, br, targets, max_rounds, orientation=orientation)
                c["origin"] = origin
                cands.append(c)
    good = [c for c in cands if c["ok"]]
    stats = {"starts": len(cands), "t_total": None, "formulations": len(_FORMULATIONS),
             "iterations_total": sum(c["ipopt"]["iterations"] for c in cands)}  # fmt: skip
    if good:
        best_first = sorted(_distinct(good), key=lambda c: objective_value(problem, c["q"]) or 0.0,
                            reverse=problem.objective == "max_gamma_min")  # fmt: skip
        stats["t_total"] = time.perf_counter() - t0
        stats["local_optima"] = len(best_first)
        local = [_to_result(problem, c, "optimal" if problem.objective else "feasible", "local optimum", stats)
                 for c in best_first]  # fmt: skip
        status = "optimal" if problem.objective else "feasible"
        msg = f"best of {len(best_first)} distinct local optima from {len(cands)} starts, certified"
        return _to_result(problem, best_first[0], status, msg, stats, local)
    reasons = sorted({c["info"].get("reason", "") or ", ".join(c["ipopt"]["statuses"][-1:]) for c in cands})
    reach, msgs = {}, []
    for k, v in targets.items():
        lo, hi = target_range(problem, k, targets, starts_n=starts_n, seed=seed)
        reach[k] = (lo, hi)
        msgs.append(_range_message(problem, k, v, lo, hi))
    stats["t_total"] = time.perf_counter() - t0
    outside = [m for (k, (lo, hi)), m in zip(reach.items(), msgs, strict=True) if not lo <= targets[k] <= hi]
    if outside:
        return Result("infeasible", "; ".join(outside), stats=stats, reachable=reach)
    if all(max(c["residuals"].values(), default=0.0) > FEAS_TOL or c["mechanism"] is None for c in cands):
        ends = collections.Counter(c["ipopt"]["statuses"][-1] for c in cands)
        how = ", ".join(f"{n} {k}" for k, n in ends.most_common())
        msg = f"none of {len(cands)} starts reaches a design meeting the targets and conditions together (IPOPT: "
        msg += f"{how}), though each target alone can be met (" + "; ".join(msgs) + ")"
        return Result("infeasible", msg, stats=stats, reachable=reach)
    why = "; ".join(reasons[:3])
    return Result("failed", f"no start converged to a certified design ({why}); " + "; ".join(msgs), stats=stats,
                  reachable=reach)  # fmt: skip


def _range_message(problem, k, v, lo, hi):
    bounds = ", ".join(f"{n} in [{a:g}, {b:g}]" for n, (a, b) in problem.free.items())
    if not math.isfinite(lo):
        return f"no design turns fully and meets the conditions for {bounds}"
    where = "below" if v < lo else "above" if v > hi else "inside"
    return f"{k} {v:g} is {where} the reachable {lo:.6g}..{hi:.6g} for {bounds}"


def target_range(problem, target, targets=None, *, starts_n=8, seed=0):
    """(low, high) of one target over the free bounds and conditions (other targets dropped).

    Every value is that of a certified design: the optimised extremes and the start designs themselves.
    (nan, nan) if no design turns fully.
    """
    targets = dict(problem.targets if targets is None else targets)
    sub = problem.replace(targets={target: targets[target]})
    seen = []

    def value(m):
        return m.time_ratio() if target == "time_ratio" else m.stroke()

    pts = starts(problem, starts_n, seed, True)
    for _, v in pts:
        for br in branches(problem):
            with contextlib.suppress(QroptError):
                seen.append(value(problem.build(v, br)))
    for sense in (1, -1):
        for _, v in pts:
            for br, way in itertools.product(branches(problem), (1, -1)):
                c = run_start(sub, v, br, {target: targets[target]}, 3, target, sense, way)
                m = c["mechanism"]
                internal = ("dead centre", "time_ratio orientation")
                conditions = [x for k, x in c["residuals"].items() if not k.startswith(internal)]
                if m is not None and m.dead_centres().reversals == 1 and max(conditions, default=0.0) <= 1e-9:
                    seen.append(value(m))  # the exact value of a design that meets every condition
    if not seen:
        return float("nan"), float("nan")
    return float(min(seen)), float(max(seen))


__all__ = ["solve", "target_range", "formulation", "quantities"]
