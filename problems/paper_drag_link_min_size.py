"""The paper's task (1) with the smallest sum of link lengths: the shorter coupler, r3 = 0.1543445 m.

Oracle: closed form, eqs. (7)-(13).
"""

from problems.paper_drag_link import build as paper


def build():
    return paper().replace(objective="min_size", size="sum", name="paper_drag_link_min_size")
