"""Crank-rocker-driven slider (slide line through O2 and O4) for TR 1.2 and stroke 0.15 m; r1 = 0.3, r2 = 0.1,
r6 = 0.5 fixed; r3, r4, r5 free; best transmission angle.

Oracle: grid along r4 (r3 from the rocker's closed-form TR, r5 from the stroke, both by brentq), refined."""

from problems import _bases as problem_bases

ORACLE = {"kind": "grid", "tolerance": 1e-6}


def build():
    return problem_bases.crank_rocker_slider(objective="max_gamma_min", name="crank_rocker_slider_gamma")


def oracle() -> dict:
    """The reference optimum: {'objective', 'params'}."""
    return problem_bases.crank_rocker_slider_oracle(build())
