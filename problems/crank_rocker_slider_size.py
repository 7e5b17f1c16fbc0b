"""Crank-rocker-driven slider for TR 1.2 and stroke 0.15 m: the smallest sum of lengths.

Oracle: grid along r4 (closed forms and brentq), refined."""

from problems import _bases as problem_bases

ORACLE = {"kind": "grid", "tolerance": 1e-6}


def build():
    return problem_bases.crank_rocker_slider(objective="min_size", name="crank_rocker_slider_size")


def oracle() -> dict:
    """The reference optimum: {'objective', 'params'}."""
    return problem_bases.crank_rocker_slider_oracle(build())
