"""The paper's task (1) with the smallest sum of link lengths: the shorter coupler, r3 = 0.1543445 m.

Oracle: closed form, eqs. (7)-(13): the best of its roots."""

from problems import _oracles as oracles
from qropt.examples import paper_problem

ORACLE = {"kind": "closed form", "tolerance": 1e-9}


def build():
    return paper_problem().replace(objective="min_size", size="sum", name="paper_drag_link_min_size")


def oracle() -> dict:
    """The reference optimum: {'objective', 'params'}."""
    return oracles.paper(build())
