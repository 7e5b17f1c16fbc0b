"""The paper's task (1) with the least peak slider acceleration at its 10 rad/s.

Oracle: closed form, eqs. (7)-(13): the best of its roots (peak acceleration evaluated exactly)."""

from problems import _oracles as oracles
from qropt.examples import paper_problem

ORACLE = {"kind": "closed form", "tolerance": 1e-8}


def build():
    return paper_problem().replace(objective="min_peak_accel", omega2=10.0, name="paper_drag_link_accel")


def oracle() -> dict:
    """The reference optimum: {'objective', 'params'}."""
    return oracles.paper(build())
