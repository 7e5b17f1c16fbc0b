"""The paper's task (1) with the smallest footprint (bounding box of every joint path over a turn).

Oracle: closed form, eqs. (7)-(13): the best of its roots (footprint evaluated exactly)."""

from problems import _oracles as oracles
from qropt.examples import paper_problem

ORACLE = {"kind": "closed form", "tolerance": 1e-8}


def build():
    return paper_problem().replace(objective="min_size", size="footprint", name="paper_drag_link_footprint")


def oracle() -> dict:
    """The reference optimum: {'objective', 'params'}."""
    return oracles.paper(build())
