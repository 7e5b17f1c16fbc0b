"""The paper's design task, in one run: the closed form alone (the floor), ``solve()`` with its defaults (every
local optimum, certified), ``solve()`` with the closed-form starts only, and scipy SLSQP on the same formulation
(the benchmarks' one driver: same CasADi functions, exact derivatives, qropt's starts). Also the exact analysis
of a new mechanism (construction, TR, stroke, gamma_min), its peak acceleration, and a full-cycle motion (the
slider's x, v, a; and with every link's rates). Times are warm: a kernel used often runs as machine code.
Prints medians and ratios; writes benchmarks/results/synthesis.json.

Run: ``python -m benchmarks.synthesis``.
"""

from __future__ import annotations

import math
import statistics
import sys
import time

import numpy as np
from tqdm import tqdm

import qropt
from benchmarks.methods import local_solve, local_starts
from benchmarks.report import save
from qropt import DragLinkSlider
from qropt.examples import paper_mechanism, paper_problem
from qropt.synthesis import analytic

R1, R2, R4, R6 = 0.1, 0.225, 0.275, 0.3


def timed(f, repeat):
    out, value = [], None
    for _ in range(repeat):
        t = time.perf_counter()
        value = f()
        out.append(time.perf_counter() - t)
    return 1e3 * statistics.median(out), value


def closed_form():
    """Every root of eqs. (7)-(13), each built and its exact gamma_min evaluated; the best one."""
    designs = [
        DragLinkSlider(r1=R1, r2=R2, r3=s.r3, r4=R4, r5=0.15, r6=R6) for s in analytic.drag_link_r3(1.5, R1, R2, R4)
    ]
    return max(designs, key=lambda m: m.gamma_min().value)


def slsqp(problem):
    """SLSQP on qropt's NLP from qropt's starts: the best converged design's values (no certificate)."""
    best = None
    for *_, form, w0, p in local_starts(problem, 0):
        x, _ = local_solve(problem, form, w0, p, "SLSQP")
        if x is not None:
            f = float(form.functions(x, p)[0])
            g = np.array(form.functions(x, p)[1]).ravel()
            feasible = np.all(g >= form.lbg - 1e-8) and np.all(g <= form.ubg + 1e-8)
            if feasible and (best is None or f < best[0]):
                best = (f, form.unpack(x).values)
    return best[1] if best else None


def analysis(params):
    m = DragLinkSlider(**params)
    return m.time_ratio(), m.stroke(), m.gamma_min().value


def main(repeat: int = 21):
    problem = paper_problem()
    qropt.solve(problem)  # build the NLPs and compile the kinematics once
    bar = tqdm(total=7, desc="synthesis benchmark", disable=not sys.stderr.isatty(), leave=False)
    t_floor, m_floor = timed(closed_form, repeat)
    bar.update()
    t_default, res = timed(lambda: qropt.solve(problem), repeat)
    bar.update()
    t_analytic, res0 = timed(lambda: qropt.solve(problem, starts_n=0), repeat)
    bar.update()
    t_slsqp, best = timed(lambda: slsqp(problem), max(3, repeat // 4))
    bar.update()
    r3_slsqp = best["r3"] if best else float("nan")
    g_slsqp = DragLinkSlider(r1=R1, r2=R2, r3=r3_slsqp, r4=R4, r5=best["r5"], r6=R6).gamma_min().value
    params = dict(paper_mechanism().params)
    t_ana, _ = timed(lambda: analysis(params), 200)
    bar.update()
    t_peak, _ = timed(lambda: DragLinkSlider(**params).peak_acceleration(10.0), 200)
    bar.update()
    m = DragLinkSlider(**params)
    theta = np.linspace(0.0, 2 * math.pi, 3600, endpoint=False)
    t_motion, _ = timed(lambda: m.motion(theta, 10.0), 200)
    t_slider, _ = timed(lambda: m.slider(theta, 10.0), 200)
    bar.close()
    rows = [
        ("closed form (eqs. 7-13 + exact gamma_min)", t_floor, m_floor.params["r3"], m_floor.gamma_min().value),
        ("qropt solve(), defaults", t_default, res.params["r3"], res.objective),
        ("qropt solve(), closed-form starts only", t_analytic, res0.params["r3"], res0.objective),
        ("scipy SLSQP, same formulation and starts", t_slsqp, r3_slsqp, g_slsqp),
    ]
    print(f"paper design task: TR 1.5, stroke 0.3 m, max gamma_min (median of {repeat}, ms)")
    for name, t, r3, g in rows:
        print(
            f"  {name:44s} {t:9.2f} ms  {t / t_floor:7.1f}x floor  r3 = {r3:.10f}  gamma_min {math.degrees(g):.6f} deg"
        )
    print(f"  solve(): {len(res.local_optima)} local optima; {res.certificate.global_claim}")
    print(f"  SLSQP / solve() defaults: {t_slsqp / t_default:.1f}x")
    print("exact analysis of the paper's mechanism (median of 200)")
    print(f"  construction + TR + stroke + gamma_min      {1e3 * t_ana:9.1f} us")
    print(f"  construction + peak acceleration            {1e3 * t_peak:9.1f} us")
    print(f"  x, v, a at 3,600 angles (slider)            {1e3 * t_slider:9.1f} us")
    print(f"  x, v, a and link rates at 3,600 angles      {1e3 * t_motion:9.1f} us")
    save(
        "synthesis.json",
        {
            "median_ms": {
                "closed_form": t_floor,
                "solve_default": t_default,
                "solve_closed_form_starts": t_analytic,
                "slsqp": t_slsqp,
                "analysis": t_ana,
                "peak_acceleration": t_peak,
                "motion_3600": t_motion,
                "slider_3600": t_slider,
            },
            "r3": {"closed_form": m_floor.params["r3"], "solve": res.params["r3"], "slsqp": r3_slsqp},
        },
    )


if __name__ == "__main__":
    main()
