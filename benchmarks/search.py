"""An independent check that ``design()`` finds the best design of each row: a batched search over random shapes
and a large multi-start, at tasks that are not the benchmarks'.

For a task (TR, stroke) and a row of ``design`` (its problem ``type_problem(kind, TR, stroke, objective)``):

1. **Shapes.** ``n`` random designs in the row's box (lengths log-uniform, offsets and angles uniform), each
   analysed at once with every other (the type's own ``loop`` in numpy, broadcast over designs x ``M`` crank
   angles: no solver, no closed form). A design counts when it assembles over the whole turn, keeps its rules
   (Grashof class), its output reverses twice a turn and, scaled to the task's stroke (TR, gamma_min and the
   shape do not change with scale; the peak acceleration grows with it, the footprint with its square), stays
   inside the box. Its TR, stroke, gamma_min, peak acceleration (spectral second derivative) and footprint come
   from the grid (dead centres refined by the grid parabola). An objective the grid does not give (the dynamic
   ones: their loads and the ram do not scale with the stroke) is the exact analysis of each scaled design near
   the task (``criteria.objective_of``: the inverse dynamics over the turn), up to a few thousand a million
   shapes.
2. **Polish.** The ``polish`` designs within ``window`` of the TR that are best by the objective start local
   solves (the row's NLP, no closed forms, no Sobol points): each ends at an exact, certified design.
3. **Multi-start.** The row's problem solved with ``starts`` Sobol starts per two free parameters (a default
   solve has 8), without the atlas that a default solve starts from.
4. **Evolution** (``evolve`` generations, 0 for none; ``qropt.synthesis.evolution``, with more generations,
   seeds and designs than a solve's): differential evolution over the box, each candidate moved onto the TR by
   its crank length and scaled to the stroke, ranked by the exact objective. Its best distinct designs go two
   ways: a Nelder-Mead descent on the exact objective with every point put on the targets exactly, which needs
   no NLP at all (where the objective is a peak over the turn, the SQP on its exact extremes from each design and
   each descent's end too, ``minimax.polish``); and local solves of the row's NLP, as in 2.

The reference is the best design of 2, 3 and 4 (certified by the solver, or, for the descent, evaluated
exactly on the targets); ``design``'s row misses when it is worse than the
reference by more than ``TOL`` (relative). Used by ``tests/test_global.py`` (small) and ``python -m
benchmarks.search`` (10^6 shapes per row; writes results/search.json and results/search.md).
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from qropt import Solver
from qropt.kinematics.closures import RIGHT_ANGLE, transmission_angle
from qropt.kinematics.ops import NUMPY
from qropt.mechanisms import REQUIRED
from qropt.studies._design import TYPES, design, type_problem
from qropt.synthesis import criteria, descents, evolution
from qropt.synthesis import starts as starts_
from qropt.synthesis.criteria import sense
from qropt.synthesis.result import SOLUTION_PRESENT

M = 64  # crank angles of the grid
CHUNK = 20_000  # designs analysed in one numpy call
TOL = 1e-4  # relative: a row this much worse than the reference misses. The coupler slider has certified optima
# this close: 5e-6 apart at TR 2.284 (0.0003 deg) and 1.9e-5 at TR 2.056 (1.24908 and 1.24910 rad, 0.0013 deg),
# one design to a designer; 1e-4 of a transmission angle of 1 rad is 0.006 deg, of a peak acceleration 0.01 %


def _params(problem, rng, n: int) -> dict:
    """n random designs of the problem's box: free lengths log-uniform, offsets and angles uniform."""
    cls = problem.mechanism
    kinds = cls.kinds()
    p = {}
    for k, (lo, hi) in problem.free.items():
        if kinds[k] == "length" and lo > 0:
            p[k] = np.exp(rng.uniform(math.log(lo), math.log(hi), n))
        else:
            p[k] = rng.uniform(lo, hi, n)
    p |= {k: np.full(n, float(v)) for k, v in problem.fixed.items()}
    p |= {k: float(v[0]) for k, v in problem.branches.items()}
    shortest = {"crank-rocker": "r2", "drag-link": "r1"}.get(problem.conditions.get("grashof"))
    if shortest in problem.free:  # the four-bar's class by construction: s + l <= p + q, s the shortest
        others = np.stack([p[k] for k in ("r1", "r2", "r3", "r4") if k != shortest])
        room = np.minimum(others.min(axis=0), others.sum(axis=0) - 2 * others.max(axis=0))
        lo = problem.free[shortest][0]
        u = rng.uniform(0.0, 1.0, n)
        p[shortest] = np.where(room > lo, lo * np.exp(u * np.log(np.maximum(room, lo) / lo)), p[shortest])
    return p


def _grid(problem, p: dict) -> dict:
    """The grid analysis of designs p (arrays of n): ok, time_ratio, stroke, gamma_min (rad), peak_accel (at
    omega2 = 1), footprint; lengths as given."""
    cls = problem.mechanism
    n = next(v.size for v in p.values() if isinstance(v, np.ndarray))
    col = {k: (v[:, None] if isinstance(v, np.ndarray) else v) for k, v in p.items()}
    full = {k: v for k, v in cls.PARAMS.items() if v is not REQUIRED and v is not None} | cls.completed(p) | col
    th = np.linspace(0.0, 2 * np.pi, M, endpoint=False)[None, :]
    with np.errstate(all="ignore"):
        lp = cls.loop(NUMPY, th, full)
        x = np.broadcast_to(lp.x, (n, M))
        ok = np.isfinite(x).all(axis=1)
        for _, margin in lp.margins:
            ok &= (np.broadcast_to(margin, (n, M)) >= 0).all(axis=1)
        for rule in cls.rules(NUMPY, full, problem.conditions.get("grashof")):
            ok &= np.broadcast_to(rule.value, (n, 1))[:, 0] >= 0
        d = np.diff(x, axis=1, append=x[:, :1])
        ok &= (np.sign(d) != np.sign(np.roll(d, 1, axis=1))).sum(axis=1) == 2  # one max, one min a turn
        h = 2 * np.pi / M

        def refined(i):  # vertex of the parabola through the grid extreme and its neighbours
            rows = np.arange(n)
            a, b, c = x[rows, (i - 1) % M], x[rows, i], x[rows, (i + 1) % M]
            den = a - 2 * b + c
            u = np.where(den != 0, 0.5 * (a - c) / den, 0.0)
            return (i + u) * h, b - 0.25 * (a - c) * u

        t_max, x_max = refined(np.argmax(x, axis=1))
        t_min, x_min = refined(np.argmin(x, axis=1))
        a = (t_min - t_max) % (2 * np.pi)
        tr = np.maximum(a, 2 * np.pi - a) / np.minimum(a, 2 * np.pi - a)
        gamma = np.full(n, np.pi / 2)
        for lines in lp.transmission.values():
            if lines is not RIGHT_ANGLE:
                g = np.broadcast_to(transmission_angle(NUMPY, lines), (n, M))
                gamma = np.minimum(gamma, g.min(axis=1))
        k = np.fft.rfftfreq(M, 1.0 / M)
        accel = np.abs(np.fft.irfft(-(k**2) * np.fft.rfft(x, axis=1), n=M, axis=1)).max(axis=1)
        xs = np.concatenate([np.broadcast_to(pt[0], (n, M)) for pt in lp.points.values()], axis=1)
        ys = np.concatenate([np.broadcast_to(pt[1], (n, M)) for pt in lp.points.values()], axis=1)
        foot = (xs.max(axis=1) - xs.min(axis=1)) * (ys.max(axis=1) - ys.min(axis=1))
    ok &= np.isfinite(tr) & np.isfinite(gamma) & np.isfinite(accel) & np.isfinite(foot)
    return {
        "ok": ok,
        "time_ratio": tr,
        "stroke": x_max - x_min,
        "gamma_min": gamma,
        "peak_accel": accel,
        "footprint": foot,
    }


def shapes(problem, n: int, seed: int, window: float = 0.02):
    """Designs of the problem's box scaled to its stroke and within ``window`` of its TR (grid values), by
    the objective's grid value, best first: (list of free-parameter dicts, grid objective values, counted)."""
    rng = np.random.default_rng(seed)
    tr, stroke = problem.targets["time_ratio"], problem.targets["stroke"]
    kinds = problem.mechanism.kinds()
    scaled_names = [k for k in problem.free if kinds[k] in ("length", "offset")]
    found, values, counted = [], [], 0
    for start in range(0, n, CHUNK):
        p = _params(problem, rng, min(CHUNK, n - start))
        g = _grid(problem, p)
        s = stroke / g["stroke"]
        keep = g["ok"] & (np.abs(g["time_ratio"] - tr) <= window * tr) & np.isfinite(s) & (s > 0)
        for k in scaled_names:
            lo, hi = problem.free[k]
            keep &= (p[k] * s >= lo) & (p[k] * s <= hi)
        counted += int(g["ok"].sum())
        value = {
            "max_gamma_min": -g["gamma_min"],
            "min_size": g["footprint"] * s**2,
            "min_peak_accel": g["peak_accel"] * s * problem.omega2**2,
        }.get(problem.objective)
        for i in np.flatnonzero(keep):
            design = {k: float(p[k][i] * (s[i] if k in scaled_names else 1.0)) for k in problem.free}
            v = evolution.value(problem, design) if value is None else float(value[i])
            if v is not None:
                found.append(design)
                values.append(v)
    order = np.argsort(values)
    return [found[i] for i in order], [values[i] for i in order], counted


EVOLVE_SEEDS = 2  # evolutions per row, each from its own seed
EVOLVE_KEEP = 6  # distinct designs of each evolution descended and solved
DESCENT_EVALS = 1500  # exact evaluations of a descent


def reference(
    problem, n: int, seed: int, polish: int = 16, starts: int = 64, evolve_generations: int = 0, solver=None
) -> dict:
    """The best design of the polished shapes, a multi-start of ``starts`` Sobol starts per two free parameters
    and, with ``evolve_generations``, the evolution's descents and solves (see the module docstring)."""
    solver = solver or Solver(atlas=False)  # independent of the atlas, which a default solve starts from
    t0 = time.perf_counter()
    found, values, counted = shapes(problem, n, seed)
    t_shapes = time.perf_counter() - t0
    best = None  # (found by, the objective minimised, the objective, the design's parameters)
    polished = solver.solve(problem, starts_n=0, use_analytic=False, extra_starts=found[:polish], diagnose=False)
    n_starts = starts_.grown(starts, problem, starts_.plan(problem, use_analytic=False))  # per two free parameters
    multi = solver.solve(problem, starts_n=n_starts, use_analytic=False, seed=seed, diagnose=False)
    solves = [("shapes", polished), ("multistart", multi)]
    evolved, exact = {}, None
    if evolve_generations:
        t1 = time.perf_counter()
        kept = [
            d for s in range(EVOLVE_SEEDS) for d in evolution.evolve(problem, evolve_generations, seed + s, EVOLVE_KEEP)
        ]
        # each design descended on the targets; for a peak over the turn the SQP from it and its end too, as a solve's
        ends = descents.descents(problem, kept, DESCENT_EVALS, sqp=True)
        solved = solver.solve(problem, starts_n=0, use_analytic=False, extra_starts=kept, diagnose=False)
        solves.append(("evolution", solved))
        exact = (ends[0].value, ends[0].design) if ends else None
        evolved = {
            "evolved": len(kept),
            "descent": None if exact is None else -sense(problem.objective) * exact[0],
            "descent_params": None if exact is None else exact[1],
            "evolution_solve": solved.objective if solved.status in SOLUTION_PRESENT else None,
            "seconds_evolution": time.perf_counter() - t1,
        }
    for how, r in solves:
        if r.status in SOLUTION_PRESENT and (best is None or -sense(problem.objective) * r.objective < best[1]):
            best = (how, -sense(problem.objective) * r.objective, r.objective, dict(r.params))
    if exact is not None and (best is None or exact[0] < best[1]):
        best = ("evolution, exact", exact[0], -sense(problem.objective) * exact[0], exact[1])
    return {
        "shapes": n,
        "starts": n_starts,
        "valid": counted,
        "near_task": len(found),
        "best_grid": None if not values else values[0],
        "seconds_shapes": t_shapes,
        "seconds": time.perf_counter() - t0,
        "found_by": None if best is None else best[0],
        "objective": None if best is None else best[2],
        "params": None if best is None else best[3],
    } | evolved


def compare(
    time_ratio: float,
    stroke: float,
    objective: str,
    n: int,
    seed: int,
    types=None,
    starts: int = 64,
    evolve_generations: int = 0,
    **kw,
):
    """Every row of ``design(time_ratio, stroke, objective, **kw)`` against its reference: one dict per row
    (``kw``: masses, loads, omega2 of a dynamic objective)."""
    c = design(time_ratio, stroke, objective=objective, types=types, **kw)
    out = []
    for row in c.rows:
        problem = type_problem(row.type, time_ratio, stroke, objective=objective, **kw)
        ref = reference(problem, n, seed, starts=starts, evolve_generations=evolve_generations)
        mine = row.result.objective if row.result.status in SOLUTION_PRESENT else None
        worse = -sense(objective)  # larger is worse
        if ref["objective"] is None:
            miss = False
        elif mine is None:
            miss = True
        else:
            miss = worse * mine > worse * ref["objective"] + TOL * max(1.0, abs(ref["objective"]))
        out.append(
            {
                "type": row.type,
                "time_ratio": time_ratio,
                "stroke": stroke,
                "objective": objective,
                "status": row.result.status,
                "design": mine,
                "claim": row.result.certificate.global_claim if row.result.certificate else None,
                "reference": ref,
                "miss": bool(miss),
            }
        )
    return out


def main(argv=None) -> int:
    from benchmarks.report import RESULTS, save
    from benchmarks.tasks import LOADS, MASSES, OMEGA2, tasks

    ap = argparse.ArgumentParser(prog="python -m benchmarks.search", description=__doc__.split("\n\n")[0])
    ap.add_argument("--tasks", type=int, default=4)
    ap.add_argument("--shapes", type=int, default=1_000_000)
    ap.add_argument("--starts", type=int, default=64, help="Sobol starts per two free parameters (a solve's: 8)")
    ap.add_argument("--objectives", nargs="+", default=["max_gamma_min", "min_peak_accel"])
    ap.add_argument("--types", nargs="+", default=None, help="rows of design() (default: every row)")
    ap.add_argument("--evolve", type=int, default=0, help="generations of the evolution (default: none)")
    ap.add_argument("--seed", type=int, default=20261124)
    ap.add_argument("--name", default="search", help="results/<name>.json and .md")
    a = ap.parse_args(argv)
    task_list = tasks(a.tasks, seed=a.seed + 1)  # not the benchmark's tasks
    rows = []
    for objective in a.objectives:
        # a dynamic objective with benchmarks.tasks' default mass model (steel links, a 20 kg ram, 1,000 N)
        kw = {"masses": MASSES, "loads": LOADS, "omega2": OMEGA2} if criteria.of(objective).needs_masses else {}
        for tr, s in task_list:
            got = compare(tr, s, objective, a.shapes, a.seed, a.types, a.starts, a.evolve, **kw)
            rows += got
            for r in got:
                ref = r["reference"]
                flag = "MISS" if r["miss"] else "ok"
                print(
                    f"{objective:15s} TR {tr:5.3f} stroke {s:7.4f} {r['type']:20s} {flag:4s} design {r['design']} "
                    f"reference {ref['objective']} ({ref['found_by']}; {ref['near_task']} shapes near the task"
                    + (f"; evolution: descent {ref['descent']}, solve {ref['evolution_solve']})" if a.evolve else ")"),
                    flush=True,
                )
    misses = sum(r["miss"] for r in rows)
    save(f"{a.name}.json", {"shapes": a.shapes, "starts": a.starts, "evolve": a.evolve, "rows": rows, "misses": misses})
    lines = ["| objective | type | rows | misses |", "|---|---|---|---|"]
    for objective in a.objectives:
        for t in TYPES:
            mine = [r for r in rows if r["objective"] == objective and r["type"] == t]
            if mine:
                lines.append(f"| {objective} | {t} | {len(mine)} | {sum(r['miss'] for r in mine)} |")
    (RESULTS / f"{a.name}.md").write_text("\n".join(lines) + "\n")
    print(f"{misses} of {len(rows)} rows missed the reference")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
