"""Crank-shaper with a rod to the ram (slide line 0.62 m above the lever pivot) for TR 1.6 and stroke 0.4 m:
best transmission angle over the rod length.

Oracle: r2, r4 in closed form (TR and stroke fix them); grid over r6, refined."""

from problems import _bases as problem_bases

ORACLE = {"kind": "grid", "tolerance": 1e-7}


def build():
    return problem_bases.crank_shaper_rod(objective="max_gamma_min", name="crank_shaper_rod_gamma")


def oracle() -> dict:
    """The reference optimum: {'objective', 'params'}."""
    return problem_bases.crank_shaper_rod_oracle(build())
