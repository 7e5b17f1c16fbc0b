"""The paper's design task (1): a new coupler r3 and pin location r5 for TR 1.5 and stroke 0.3 m,
keeping r1 = 0.1, r2 = 0.225, r4 = 0.275, r6 = 0.3 m; drag-link; best minimum transmission angle.
(The same problem is built into qropt as ``qropt.examples.paper_problem``.)

Oracle: closed form, eqs. (7)-(13): r3 = 0.2504281 m (gamma_min 27.008 deg) or 0.1543445 m
(9.095 deg), r5 = 0.15 m.
"""

from problems import _oracles as oracles
from qropt.examples import paper_problem

ORACLE = {"kind": "closed form", "tolerance": 1e-9}


def build():
    return paper_problem()


def oracle() -> dict:
    """The reference optimum: {'objective', 'params'} (the best of eqs. 7-13's roots)."""
    return oracles.paper(build())
