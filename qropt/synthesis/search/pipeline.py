"""The default pipeline: the strategies of a solve, in order, each in a line.

``STARTS`` is the starts phase (the multi-start), which the transmission guard and the diagnosis also run on other
problems; ``DEFAULT`` is the whole solve. ``Solver(pipeline=[...])`` runs another list: a strategy left out is not
run, one added is run where it accepts the problem.
"""

from __future__ import annotations

from qropt.synthesis.search.atlas import AtlasStarts
from qropt.synthesis.search.base import Phase
from qropt.synthesis.search.best import Best
from qropt.synthesis.search.both_ways import BothWays
from qropt.synthesis.search.descended import Descended
from qropt.synthesis.search.diagnosis import Diagnose, Failed
from qropt.synthesis.search.enumeration import Enumeration
from qropt.synthesis.search.evolution import Evolution
from qropt.synthesis.search.fallback import WithoutClosedForms
from qropt.synthesis.search.family import FamilyScan
from qropt.synthesis.search.given import Given
from qropt.synthesis.search.guard import Guarded
from qropt.synthesis.search.least_size import LeastSize
from qropt.synthesis.search.local_solves import LocalSolves
from qropt.synthesis.search.plan import Planned
from qropt.synthesis.search.points import ClosedFormPoints
from qropt.synthesis.search.proof import ProvedInfeasible
from qropt.synthesis.search.reach import BoundsInReach
from qropt.synthesis.search.refresh import Refresh
from qropt.synthesis.search.related import Related
from qropt.synthesis.search.scale import UnitScale
from qropt.synthesis.search.second_pass import SecondPass
from qropt.synthesis.search.shapes import Shapes
from qropt.synthesis.search.sobol import Sobol
from qropt.synthesis.search.sqp import PeakSQP
from qropt.synthesis.search.walk import FamilyWalk
from qropt.synthesis.search.wrapped import Wrapped

STARTS = (
    Given(),  # the given starts, queued first
    Enumeration(),  # a closed form that gives every design: each polished (no multi-start)
    FamilyScan(),  # a closed-form family: scanned exactly, its best points queued
    AtlasStarts(),  # the atlas's designs of this shape, solved; where they certify, the phase ends
    ClosedFormPoints(),  # the closed forms' points (the best few where there are many)
    Shapes(),  # shapes best by the objective's grid value
    Related(),  # for a dynamic objective, the atlas's kinematic optima of this shape
    Sobol(),  # the space-filling starts
    LocalSolves(),  # every queued start solved locally
    FamilyWalk(),  # a family point IPOPT missed: a 1-D search along the family instead
    BothWays(),  # no design from the spread starts: each again in both TR orientations
)

DEFAULT = (
    UnitScale(),  # far from unit scale: solved at unit scale, the Result scaled back
    Planned(),  # the plan of starts
    BoundsInReach(),  # a bound beyond its own optimum, which the atlas holds: infeasible before any start
    Phase(STARTS),  # the multi-start
    Guarded(),  # a criterion seen badly near a toggle: the starts under a transmission guard, continued
    Evolution(),  # ... and descents from differential evolutions
    SecondPass(),  # those joined (the second pass first where only they found designs)
    Wrapped(),  # designs at a full-turn box's edge solved from across it
    ProvedInfeasible(),  # an enumeration without a valid design: infeasible
    WithoutClosedForms(),  # the closed forms gave nothing: solved again without them
    Best(),  # the certified designs, best first
    Refresh(),  # a dynamic objective's best solved again from itself
    LeastSize(),  # a continuum of optima: the least size
    PeakSQP(),  # a peak over the turn: the SQP on the exact peak from the best designs and the descents' ends
    Descended(),  # a descent's end that beats every certified design
    Failed(),  # no design and no diagnosis: the backend's reasons
    Diagnose(),  # no design: why, within the diagnosis's budget
)


def starts_of(pipeline) -> tuple:
    """The starts phase of a pipeline (its first Phase), else ``STARTS``."""
    return next((s.stages for s in pipeline if isinstance(s, Phase)), STARTS)


__all__ = ["STARTS", "DEFAULT", "starts_of"]
