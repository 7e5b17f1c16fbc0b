"""Hard: the paper's linkage pushed to TR 3.4, near the largest reachable 3.538, where the coupler approaches
the change point r3 = 0.4 and the transmission angle collapses.

Oracle: closed form, eqs. (7)-(13)."""

from problems import _oracles as oracles
from qropt.examples import paper_problem

ORACLE = {"kind": "closed form", "tolerance": 1e-8}


def build():
    return paper_problem().replace(targets={"time_ratio": 3.4, "stroke": 0.3}, name="drag_link_near_change_point")


def oracle() -> dict:
    """The reference optimum: {'objective', 'params'}."""
    return oracles.paper(build())
