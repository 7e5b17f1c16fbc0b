"""pylinkage's particle swarm on the problems it can express (the slider-crank, four-bars and four-bar-driven
sliders), the way its users work: the linkage is built and simulated in pylinkage, and TR, stroke, transmission
angle and acceleration are measured on the sampled loci."""

from __future__ import annotations

import math

import numpy as np

STEPS = 360
SUPPORTED = ("SliderCrank", "FourBar", "CrankRockerSlider", "DragLinkSlider")


def _linkage(pl, kind, p):
    o2 = pl.Ground(0.0, 0.0, name="O2")
    crank = pl.Crank(anchor=o2, radius=p["r2"], angular_velocity=2 * math.pi / STEPS, initial_angle=0.0, name="A")
    if kind == "SliderCrank":
        l1, l2 = pl.Ground(0.0, p["e"], name="L1"), pl.Ground(1.0, p["e"], name="L2")
        x0 = p["r2"] + math.sqrt(max(p["r3"] ** 2 - p["e"] ** 2, 0.0))
        slider = pl.RRPDyad(crank.output, l1, l2, p["r3"], x=x0, y=p["e"], name="C")
        return pl.Linkage([o2, crank, l1, l2, slider]), ["A", "C"]
    o4 = pl.Ground(p["r1"], 0.0, name="O4")
    # the start guess picks the branch (pylinkage keeps the nearest solution): sigma = -1 puts B below A->O4
    ax, ay = p["r2"], 0.0
    ux, uy = ax - p["r1"], ay
    ll = math.hypot(ux, uy)
    c = (p["r4"] ** 2 + ll * ll - p["r3"] ** 2) / (2 * p["r4"] * ll)
    ang = math.atan2(uy, ux) + p.get("sigma", -1.0) * math.acos(max(-1.0, min(1.0, c)))
    b = pl.RRRDyad(
        crank.output, o4, p["r3"], p["r4"], x=p["r1"] + p["r4"] * math.cos(ang), y=p["r4"] * math.sin(ang), name="B"
    )
    if kind == "FourBar":
        return pl.Linkage([o2, crank, o4, b]), ["A", "B"]
    cpin = pl.FixedDyad(o4, b, p["r5"], 0.0, name="C")
    h = p.get("h", 0.0)
    l1, l2 = pl.Ground(0.0, h, name="L1"), pl.Ground(1.0, h, name="L2")
    cx, cy = p["r1"] + p["r5"] * math.cos(ang), p["r5"] * math.sin(ang)
    d = pl.RRPDyad(
        cpin.output if hasattr(cpin, "output") else cpin,
        l1,
        l2,
        p["r6"],
        x=cx + math.sqrt(max(p["r6"] ** 2 - (h - cy) ** 2, 0.0)),
        y=h,
        name="D",
    )
    return pl.Linkage([o2, crank, o4, b, cpin, l1, l2, d]), ["A", "B", "C", "D"]


def measure(pl, kind, p, omega2=1.0):
    """Sampled TR, stroke (or swing), gamma_min, peak acceleration and bounding-box area of a design."""
    link, names = _linkage(pl, kind, p)
    rows = list(link.step(iterations=STEPS))
    comps = [c.name for c in link.components]
    loc = {n: np.array([r[comps.index(n)] for r in rows], float) for n in names}
    four_bar = kind == "FourBar"
    out = np.unwrap(np.arctan2(loc["B"][:, 1], loc["B"][:, 0] - p["r1"])) if four_bar else loc[names[-1]][:, 0]
    i, j = int(np.argmax(out)), int(np.argmin(out))
    a = ((j - i) % STEPS) / STEPS * 2 * math.pi
    tr = max(a, 2 * math.pi - a) / max(min(a, 2 * math.pi - a), 1e-12)
    gam = []
    if kind != "SliderCrank":
        u, w = loc["A"] - loc["B"], np.array([p["r1"], 0.0]) - loc["B"]
        cr, dt = u[:, 0] * w[:, 1] - u[:, 1] * w[:, 0], (u * w).sum(1)
        gam.append(np.arctan2(np.abs(cr), np.abs(dt)).min())
    if kind != "FourBar":
        pin = loc["A"] if kind == "SliderCrank" else loc["C"]
        r = loc[names[-1]] - pin
        gam.append(np.arctan2(np.abs(r[:, 0]), np.abs(r[:, 1])).min())
    dth = 2 * math.pi / STEPS
    acc = (np.roll(out, -1) - 2 * out + np.roll(out, 1)) / dth**2 * omega2**2
    pts = np.concatenate([loc[n] for n in names] + [np.zeros((1, 2))])
    area = float(np.ptp(pts[:, 0]) * np.ptp(pts[:, 1]))
    return {
        "time_ratio": tr,
        "travel": float(out.max() - out.min()),
        "gamma_min": float(min(gam)),
        "peak_accel": float(np.abs(acc).max()),
        "footprint": area,
    }


def run(pl, problem, seed):
    kind = problem.mechanism.__name__
    if kind not in SUPPORTED:
        return {"values": None, "nfev": None, "message": "not applicable", "branch": None}
    names = list(problem.free)
    sign = -1.0 if problem.objective == "max_gamma_min" else 1.0
    calls = [0]
    base = {**problem.fixed, **{k: v[0] for k, v in problem.branches.items()}}

    def fitness(_linkage, dims, _pos=None):
        calls[0] += 1
        p = {**base, **dict(zip(names, (float(x) for x in dims), strict=True))}
        try:
            with np.errstate(all="ignore"):
                m = measure(pl, kind, p, problem.omega2)
        except Exception:  # noqa: BLE001 - pylinkage raises on unbuildable designs
            return 1e6
        if not all(math.isfinite(v) for v in m.values()):
            return 1e6
        pen = abs(m["time_ratio"] - problem.targets.get("time_ratio", m["time_ratio"]))
        for k in ("stroke", "swing"):
            if k in problem.targets:
                pen += abs(m["travel"] - problem.targets[k]) / problem.targets[k]
        bound = problem.conditions.get("gamma_min")
        if bound is not None:
            pen += max(0.0, bound - m["gamma_min"])
        obj = {
            "max_gamma_min": m["gamma_min"],
            "min_peak_accel": m["peak_accel"],
            "min_size": m["footprint"]
            if problem.size == "footprint"
            else (max if problem.size == "longest" else sum)(p[k] for k in problem.mechanism.LENGTHS if k in p),
        }.get(problem.objective, 0.0)
        return sign * obj + 1e3 * pen

    lo = [problem.free[k][0] for k in names]
    hi = [problem.free[k][1] for k in names]
    np.random.seed(seed)
    template, _ = _linkage(pl, kind, {**base, **{k: 0.5 * (a + b) for k, (a, b) in problem.free.items()}})
    result = pl.particle_swarm_optimization(
        fitness,
        template,
        dimensions=len(names),
        n_particles=30,
        iterations=40,
        bounds=(lo, hi),
        order_relation=min,
        verbose=False,
    )
    best = _best(result, fitness)
    if best is None:
        return {"values": None, "nfev": calls[0], "message": "no particle", "branch": None}
    return {
        "values": dict(zip(names, (float(x) for x in best), strict=True)),
        "nfev": calls[0],
        "message": "particle swarm (pylinkage)",
        "branch": None,
    }


def _best(result, fitness):
    """The best dimensions from pylinkage's result ensemble (its API varies across versions)."""
    cands = []
    for attr in ("dimensions", "positions", "agents"):
        obj = getattr(result, attr, None)
        if obj is not None:
            arr = np.atleast_2d(np.asarray(obj, float))
            cands += list(arr)
    if not cands:
        try:
            cands = [np.asarray(a[1] if isinstance(a, tuple) else a, float) for a in result]
        except TypeError:
            return None
    return min(cands, key=lambda d: fitness(None, d)) if cands else None
