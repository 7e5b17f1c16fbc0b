"""Hard: the paper's task with both four-bar assembly branches (sigma = -1 and +1) enumerated: four local
optima in two mirror pairs.

Oracle: closed form, eqs. (7)-(13) (the branch mirrors give the same lengths and gamma_min)."""

from problems import _oracles as oracles
from qropt.examples import paper_problem

ORACLE = {"kind": "closed form", "tolerance": 1e-8}


def build():
    return paper_problem().replace(branches={"sigma": (-1, 1)}, name="drag_link_both_branches")


def oracle() -> dict:
    """The reference optimum: {'objective', 'params'}."""
    return oracles.paper(build())
