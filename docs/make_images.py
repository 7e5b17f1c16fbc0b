"""Draws every picture README.md and docs/*.md show, into docs/images/. Run from the repository root:

python docs/make_images.py            # all of them (about half a minute on two cores)
python docs/make_images.py types      # only the ones whose names start with 'types'
"""

from __future__ import annotations

import math
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
IMAGES = ROOT / "docs" / "images"
sys.path.insert(0, str(ROOT))  # the chart problem files live in problems/

import qropt  # noqa: E402
from qropt.examples import paper_mechanism  # noqa: E402
from qropt.io import plots  # noqa: E402


def types(path):
    qropt.design(1.5, 0.3).plot(path)


def front(path):
    p = qropt.Problem(
        "CrankRockerSlider",
        fixed={"r1": 0.3, "r2": 0.1, "r6": 0.5},
        free={"r3": (0.15, 0.6), "r4": (0.15, 0.45), "r5": (0.02, 0.45)},
        targets={"time_ratio": 1.2, "stroke": 0.15},
        omega2=2.0,
    )
    qropt.pareto(p, ("max_gamma_min", "min_size"), n=20).plot(path)


def crank_rocker_chart(path):
    from problems import chart_crank_rocker as cr

    qropt.chart(cr.build(), cr.X, cr.Y, progress=False).plot(path)


def slider_crank_chart(path):
    from problems import chart_slider_crank as sc

    qropt.chart(sc.build(), sc.X, sc.Y, progress=False).plot(path)


def paper_mechanism_cycle(path):
    plots.save(plots.cycle_figure(paper_mechanism(), math.radians(60), 10.0), path)


def family(path):
    p = qropt.Problem(
        "DragLinkSlider",
        fixed={"r2": 0.225, "r4": 0.275, "r5": 0.15, "r6": 0.3},
        free={"r1": (0.02, 0.2), "r3": (0.05, 0.6)},
        targets={"time_ratio": 1.5},
    )
    f = qropt.family(p)
    plots.save(plots.family_figure(f, best=f.best("max_gamma_min")), path)


def reachable(path):
    plots.save(plots.reachable_figure(qropt.reachable(paper_mechanism(), "r3"), (1.5, 2.0)), path)


def servo(path):
    m = qropt.SliderCrank(r2=0.1, r3=0.4)
    qropt.speed_profile(m, omega_max=20, v_cut=0.5, a_max=40, alpha_max=400, v_max=2).plot(path)


def forces(path):
    masses, loads = qropt.Masses.steel(2e-4, ram=20.0), qropt.Loads(cutting_force=1000.0, gravity=9.81)
    plots.save(plots.dynamics_figure(paper_mechanism(), 10.0, masses, loads, math.radians(60)), path)


def torque_front(path):
    sc = qropt.Problem(
        "slider-crank",
        free={"r2": (0.015, 1.5), "r3": (0.015, 1.5), "e": (-1.5, 1.5)},
        targets={"time_ratio": 1.5, "stroke": 0.3},
        masses=qropt.Masses.bars(2.0, 5.0),
        loads=qropt.Loads(cutting_force=1000.0, gravity=9.81),
        omega2=10.0,
    )
    qropt.pareto(sc, ("max_gamma_min", "min_peak_torque"), n=20).plot(path)


def polygons(path):
    m = paper_mechanism()
    m = type(m)(**{**m.params, "r3": 0.2504})  # the paper's Table 4 design, as its Tables 2-3
    m.relative_motion(math.radians(60), 10.0).plot(path)


def app_pages(path):
    """The web app's pages in Chromium, as the browser test leaves them (app_mechanism.png, app_design.png and
    app_synthesis.png together: the test writes all three)."""
    import os
    import subprocess

    env = {**os.environ, "QROPT_SCREENSHOTS": str(path.parent)}
    test = [sys.executable, "-m", "pytest", "-q", "-n", "0", "-p", "no:cacheprovider", "tests/test_browser.py"]
    subprocess.run(test, cwd=ROOT, env=env, check=True)


PICTURES = {
    "types.png": types,
    "front.png": front,
    "crank_rocker_chart.png": crank_rocker_chart,
    "slider_crank_chart.png": slider_crank_chart,
    "paper_mechanism.png": paper_mechanism_cycle,
    "family.png": family,
    "reachable.png": reachable,
    "servo.png": servo,
    "forces.png": forces,
    "polygons.png": polygons,
    "torque_front.png": torque_front,
    "app_mechanism.png": app_pages,  # and app_design.png, app_synthesis.png
}


def main(argv: list[str]) -> None:
    IMAGES.mkdir(parents=True, exist_ok=True)
    for name, draw in PICTURES.items():
        if argv and not any(name.startswith(a) for a in argv):
            continue
        start = time.perf_counter()
        draw(IMAGES / name)
        print(f"docs/images/{name}  {time.perf_counter() - start:.1f} s")


if __name__ == "__main__":
    main(sys.argv[1:])
